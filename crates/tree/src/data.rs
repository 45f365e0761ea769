//! [`Data`]: the reusable workspace of the per-call algorithms (Pinocchio's `Data`).
//!
//! Everything is allocated once by [`Data::new`]; the algorithms then only write into it.

use crate::model::Model;
use crate::spatial::{ArticulatedInertia, Force, Mat3, Motion, RigidInertia, Transform, Vec3};
use nalgebra::{DMatrix, DVector};

/// Scratch buffers and results for one [`Model`]. Per-body vectors are indexed like
/// `model.bodies` and expressed in each body's own frame unless said otherwise.
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
    /// `Xup[i]`: from `λ(i)`'s coordinates to body `i`'s.
    pub xup: Vec<Transform>,
    /// Body-to-inertial rotation of each body (after [`crate::forward_kinematics`]).
    pub rotation: Vec<Mat3>,
    /// Body frame origin in inertial coordinates (m).
    pub position: Vec<Vec3>,
    /// Spatial velocity of each body.
    pub v: Vec<Motion>,
    /// Spatial acceleration of each body.
    pub a: Vec<Motion>,
    /// Velocity-product acceleration `cᵢ = vᵢ ×m Sᵢ q̇ᵢ`.
    pub c: Vec<Motion>,
    /// Spatial force transmitted across each body's hinge (RNEA).
    pub f: Vec<Force>,
    /// Articulated-body inertias (ABA).
    pub ia: Vec<ArticulatedInertia>,
    /// Articulated bias forces (ABA).
    pub pa: Vec<Force>,
    /// `Uᵢ = IAᵢ Sᵢ` (ABA).
    pub u_col: Vec<Force>,
    /// `Dᵢ = Sᵢᵀ Uᵢ` (ABA).
    pub d: Vec<f64>,
    /// `uᵢ = τᵢ − Sᵢᵀ pAᵢ` (ABA).
    pub u: Vec<f64>,
    /// Composite rigid-body inertias (CRBA).
    pub ic: Vec<RigidInertia>,
    /// Joint-space mass matrix `M` (CRBA), `nv x nv`.
    pub mass_matrix: DMatrix<f64>,
    /// Cholesky factor of `M` (lower triangle), forward dynamics by CRBA.
    pub chol: DMatrix<f64>,
    /// Generalised forces (RNEA output), `nv`.
    pub tau: DVector<f64>,
    /// Velocity-product (bias) forces `C(q, v)` with external forces, `nv`.
    pub bias: DVector<f64>,
    /// Generalised accelerations (ABA or CRBA forward dynamics), `nv`.
    pub ddq: DVector<f64>,
    /// faer's factorisation buffers, for models of [`crate::cholesky::FAER_MIN_DOF`] or more DOF.
    pub faer: Option<crate::cholesky::FaerWork>,
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
            pa: vec![Force::zero(); n],
            u_col: vec![Force::zero(); n],
            d: vec![0.0; n],
            u: vec![0.0; n],
            ic: vec![RigidInertia::default(); n],
            mass_matrix: DMatrix::zeros(nv, nv),
            chol: DMatrix::zeros(nv, nv),
            tau: DVector::zeros(nv),
            bias: DVector::zeros(nv),
            ddq: DVector::zeros(nv),
            faer: (nv >= crate::cholesky::FAER_MIN_DOF).then(|| crate::cholesky::FaerWork::new(nv)),
        }
    }
}
