//! [`Data`]: the reusable workspace of the per-call algorithms (Pinocchio's `Data`).
//!
//! Everything is allocated once by [`Data::new`]; the algorithms then only write into it.
//! `Data` is scratch, not state: a field's contents are meaningful only right after the
//! algorithm that fills it and until the next call that writes it (any algorithm may reuse
//! any buffer). Keep the physical state (`q`, `v`) in your own vectors.

use crate::model::Model;
use crate::spatial::{ArticulatedInertia, Force, Mat3, Motion, RigidInertia, Transform, Vec3};
use nalgebra::{DMatrix, DVector};

/// Scratch buffers and results for one [`Model`]. Per-body vectors are indexed like
/// [`Model::bodies`] and expressed in each body's own frame unless said otherwise.
///
/// Each field names the algorithms that fill it; read it right after one of them (with the
/// same `q`, `v`), never as a record of an earlier call. Results are also returned by
/// reference by the algorithms themselves (`aba` returns `&data.ddq`).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, spatial::Mat3};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 10.0, Mat3::identity()))
///     .build()?;
/// let data = Data::new(&model);
/// assert_eq!(data.mass_matrix.nrows(), 6);
/// # Ok::<(), satsim_tree::ModelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Data {
    /// `Xup[i]`: from `λ(i)`'s coordinates to body `i`'s. Filled by
    /// [`crate::update_transforms`] and so by every algorithm taking `q`.
    pub xup: Vec<Transform>,
    /// Body-to-inertial rotation of each body. Filled by [`crate::forward_kinematics`]
    /// (read by [`crate::center_of_mass`], [`crate::momentum`]).
    pub rotation: Vec<Mat3>,
    /// Body frame origin in inertial coordinates (m). Filled by [`crate::forward_kinematics`].
    pub position: Vec<Vec3>,
    /// Spatial velocity of each body. Filled by [`crate::forward_kinematics`],
    /// [`crate::rnea()`], [`crate::aba::aba`] (not for gyrostat rotors in ABA).
    pub v: Vec<Motion>,
    /// Spatial acceleration of each body. Filled by [`crate::forward_kinematics_acc`],
    /// [`crate::rnea()`], [`crate::aba::aba`] (not for gyrostat rotors in ABA).
    pub a: Vec<Motion>,
    /// Velocity-product acceleration `cᵢ = vᵢ ×m Sᵢ q̇ᵢ`. Filled by [`crate::aba::aba`].
    pub c: Vec<Motion>,
    /// Spatial force transmitted across each body's hinge. Filled by [`crate::rnea()`].
    pub f: Vec<Force>,
    /// Articulated-body inertias. Filled by [`crate::aba::aba`]: the root's `IA₀`; a hinged
    /// body's is left projected, `IAᵢ − Uᵢ Dᵢ⁻¹ Uᵢᵀ` (the inertia its parent receives; ABA
    /// projects in place); unspecified for gyrostat rotors, hinges locked in
    /// [`crate::aba::aba_hybrid`] and the links and tips of a [`crate::Chain`].
    pub ia: Vec<ArticulatedInertia>,
    /// Per body: whether ABA's pass 2 has started `ia[i]` (a child has added to it). The
    /// first child writes its parent's inertia as the rigid start plus its own part, so
    /// that no body's start is copied in first.
    pub(crate) ia_started: Vec<bool>,
    /// [`crate::rnea::rnea_for`]'s bodies: 0 not visited, 1 an ancestor of a hinge asked
    /// for, 2 below one.
    pub(crate) rnea_reach: Vec<u8>,
    /// Articulated bias forces. Filled by [`crate::aba::aba`].
    pub pa: Vec<Force>,
    /// Per chain tip ([`crate::Chain`]): what ABA's pass 3 reads of the chain's pass 2.
    pub(crate) chain: Vec<ChainWork>,
    /// `Uᵢ = IAᵢ Sᵢ`. Filled by [`crate::aba::aba`] (for the hinges of a [`crate::Chain`]: the
    /// columns of `U L⁻ᵀ` at the hinge point, `D = L Δ Lᵀ`).
    pub u_col: Vec<Force>,
    /// `Dᵢ = Sᵢᵀ Uᵢ`. Filled by [`crate::aba::aba`] (for a chain's hinges: the pivots `Δ`).
    pub d: Vec<f64>,
    /// `uᵢ = τᵢ − Sᵢᵀ pAᵢ`. Filled by [`crate::aba::aba`] (for a chain's hinges: `L⁻¹ u`).
    pub u: Vec<f64>,
    /// Composite rigid-body inertias. Filled by [`crate::crba()`].
    pub ic: Vec<RigidInertia>,
    /// Joint-space mass matrix `M`, `nv x nv`. Filled by [`crate::crba()`] (and so by
    /// [`crate::cholesky::crba_cholesky`] and [`crate::impulse::hinge_impulse`]).
    pub mass_matrix: DMatrix<f64>,
    /// Cholesky factor of `M` (lower triangle). Filled by [`crate::cholesky::crba_cholesky`]
    /// (models under [`crate::llt::FAER_MIN_DOF`] DOF) and [`crate::impulse::hinge_impulse`].
    pub chol: DMatrix<f64>,
    /// Generalised forces, `nv`. Filled by [`crate::rnea()`].
    pub tau: DVector<f64>,
    /// Velocity-product (bias) forces `C(q, v)` with external forces, `nv`. Filled by
    /// [`crate::bias`] (and so by [`crate::cholesky::crba_cholesky`]).
    pub bias: DVector<f64>,
    /// Generalised accelerations, `nv`. Filled by [`crate::aba::aba`], [`crate::aba::aba_hybrid`]
    /// and [`crate::cholesky::crba_cholesky`]; [`crate::impulse::hinge_impulse`] writes `M⁻¹ e_k`
    /// here, and [`crate::bias`] uses it as zero acceleration.
    pub ddq: DVector<f64>,
    /// faer's factorisation buffers, for models of [`crate::llt::FAER_MIN_DOF`] or more
    /// DOF (used by [`crate::cholesky::crba_cholesky`]).
    pub faer: Option<crate::llt::FaerWork>,
}

impl Data {
    /// Allocates the workspace for `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.n_bodies();
        let nv = model.nv();
        Self {
            xup: vec![Transform::identity(); n],
            rotation: vec![Mat3::identity(); n],
            position: vec![Vec3::zeros(); n],
            v: vec![Motion::zero(); n],
            a: vec![Motion::zero(); n],
            c: vec![Motion::zero(); n],
            f: vec![Force::zero(); n],
            ia: vec![ArticulatedInertia::default(); n],
            ia_started: vec![false; n],
            rnea_reach: vec![0; n],
            pa: vec![Force::zero(); n],
            chain: vec![ChainWork::default(); n],
            u_col: vec![Force::zero(); n],
            d: vec![0.0; n],
            u: vec![0.0; n],
            ic: vec![RigidInertia::default(); n],
            mass_matrix: DMatrix::zeros(nv, nv),
            chol: DMatrix::zeros(nv, nv),
            tau: DVector::zeros(nv),
            bias: DVector::zeros(nv),
            ddq: DVector::zeros(nv),
            faer: (nv >= crate::llt::FAER_MIN_DOF).then(|| crate::llt::FaerWork::new(nv)),
        }
    }
}

/// What ABA's pass 2 leaves at a [`crate::Chain`]'s tip for pass 3 (indexed by body, so that
/// a `Data` serves any form of its model).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ChainWork {
    /// From the chain parent's coordinates to the hinge point's frame (the tip's axes).
    pub(crate) x: Transform,
    /// The chain's velocity-product acceleration at the hinge point (the tip's axes).
    pub(crate) c: Motion,
    /// The unit lower factor of `D = L Δ Lᵀ`: `[l₁₀, l₂₀, l₂₁]`.
    pub(crate) l: [f64; 3],
    /// `1 / Δ`, elimination order.
    pub(crate) inv: [f64; 3],
}
