//! Flexible bodies: elastic coordinates (floating frame of reference, small deformation,
//! mass-normalised modes) inside the recursive algorithms, beside the rigid ones.
//!
//! - [`FlexModel`]: a rigid [`crate::Model`] plus per-body [`ModalData`] (from a [`Beam`] or
//!   given) and, for each hinge on a flexible parent, the [`NodeShape`]s at its point that
//!   carry it. [`FlexData`] is its workspace: the per-call algorithms allocate nothing.
//! - [`rnea()`] (inverse dynamics, [`bias`]), [`crba()`] (mass matrix), [`aba()`] (O(n)
//!   forward dynamics; [`aba_hybrid`] with locked hinges), [`energy`]; for a simulation's
//!   effects, [`forward_kinematics`] (the bodies' poses, into a rigid [`crate::Data`]) and
//!   [`momentum`]; for its output rows, [`energy_and_momentum`] (one pass over the
//!   kinematics') and [`forward_poses`] (the poses alone, for a view).
//!
//! Coordinates: `q = [rigid q…, η…]`, `v = [rigid v…, η̇…]` (see [`model`]). The model is
//! linear in the deformation (modal integrals evaluated undeformed; with a beam's
//! `stiffening`, consistent to second order, below) and exactly Lagrangian:
//! with no damping, kinetic plus strain energy is conserved. The derivation is the theory
//! page "Flexible bodies". A beam's geometric stiffening is in the same Lagrangian (Kane,
//! Ryan and Banerjee's consistent linearisation): the deflection's first-order inertia
//! (first moment `b S₁ᵀ η` and products of inertia: a dynamic imbalance under spin, the
//! centrifugal load on the modes), the foreshortening's kinetic energy and the
//! deflection's own rotational inertia (`−½ ωᵀ G(η) ω`), the foreshortening's shift of the
//! first moment and its momentum (`P(η) = P − c (J₀ η)ᵀ`), so the axial load is that of the
//! frame's whole acceleration: the spin about its own origin, the origin's centripetal
//! acceleration (a hub's radius), thrust along the beam, a spin-up.
//!
//! ```
//! use satsim_tree::{BaseKind, Body, Hinge, ModelBuilder, spatial::{Mat3, Vec3}};
//! use satsim_tree::flexible::{aba, Beam, FlexData, FlexModel, Flexible, Modes};
//! let builder = ModelBuilder::new(BaseKind::Free)
//!     .body(Body::new("bus", 100.0, Mat3::identity() * 10.0))
//!     .body(Body::new("panel", 0.0, Mat3::zeros()))
//!     .hinge(Hinge::revolute("h", "bus", "panel", Vec3::z()).at(Vec3::y()));
//! let beam = Beam { root: Vec3::zeros(), axis: Vec3::y(), bend: Vec3::z(), length: 2.0,
//!                   ei: 500.0, rho_a: 5.0, modes: 3 };
//! let flex = [Flexible { body: "panel".into(), modes: Modes::Beam(beam), damping: 0.0,
//!                        stiffening: true }];
//! let model = FlexModel::build(builder, &flex)?;
//! assert_eq!((model.nq(), model.nv()), (8 + 3, 7 + 3));
//! let mut data = FlexData::new(&model);
//! let mut q = model.neutral();
//! q[8] = 0.01; // the first mode deflected
//! let ddq = aba(&model, &mut data, &q, &vec![0.0; model.nv()], &vec![0.0; model.nv()], None)?;
//! assert!(ddq[7] < 0.0); // the mode springs back
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod aba;
pub mod beam;
mod chain;
pub mod crba;
pub mod data;
mod deflection;
mod dense;
pub mod field;
pub mod kinematics;
pub mod modal;
pub mod model;
mod node;
pub mod rnea;

pub use aba::{aba, aba_hybrid, aba_hybrid_with_kinematics, aba_with_kinematics};
pub use beam::{Beam, Stiffening, StiffeningIntegrals};
pub use crba::crba;
pub use data::FlexData;
pub use field::FieldLoad;
pub use kinematics::{energy_and_momentum, forward_kinematics, forward_poses, momentum};
pub use modal::{ModalData, NodeShape};
pub use model::{
    Deflection, FlexError, FlexModel, Flexible, LargeDeflection, MAGNIFICATION_LIMIT,
    MODES_FILE_NODE_TOLERANCE, Modes, SMALL_DEFLECTION, UNRESOLVED, WatchPoint,
};
pub use rnea::{bias, gyrostat_torques, gyrostat_torques_on_base, rnea, rnea_with_kinematics};

use crate::error::DynamicsError;
use crate::spatial;

/// Kinetic energy `½ Σ ([vᵢ; η̇ᵢ]ᵀ [[I, P], [Pᵀ, 1]] [vᵢ; η̇ᵢ]) + ½ Σ armature φ̇²` (with
/// stiffening, `I(η)` and `P(η)` at the deformation) and strain energy `½ Σ ωₖ² ηₖ²` (J), as
/// `(kinetic, strain)`.
pub fn energy(
    model: &FlexModel,
    data: &mut FlexData,
    q: &[f64],
    v: &[f64],
) -> Result<(f64, f64), DynamicsError> {
    data::check_state(model, q, v)?;
    data::velocities(model, data, q, v);
    let mut t = 0.0;
    for i in 0..model.rigid.n_bodies() {
        body_momentum(model, data, i, q, v, &mut t);
    }
    Ok(add_armature_and_strain(model, q, v, t))
}

/// Body `i`'s momentum `I vᵢ + P η̇ᵢ` (body axes, about its frame's origin) from the first
/// pass in `data`, its kinetic energy added to `t`.
#[inline(always)]
fn body_momentum(
    model: &FlexModel,
    data: &FlexData,
    i: usize,
    q: &[f64],
    v: &[f64],
    t: &mut f64,
) -> spatial::Force {
    let nv = model.rigid.nv();
    let vi = data.v[i];
    let mut h = data.inertia[i].mul_motion(&vi);
    for k in 0..model.modes[i] {
        let e = model.offset[i] + k;
        // ½ (vᵀ P η̇ + η̇ᵀ Pᵀ v) adds vᵀ P η̇ once: half of it through h.
        let pk = model.momentum_at(i, q, k);
        h += pk * v[nv + e];
        *t += 0.5 * v[nv + e] * (v[nv + e] + vi.dot(&pk));
    }
    *t += 0.5 * vi.dot(&h);
    h
}

/// `t` plus the rotors' kinetic energy `½ Σ armature φ̇²` (added in order, as the energy
/// sums), and the strain energy `½ Σ ωₖ² ηₖ²`.
fn add_armature_and_strain(model: &FlexModel, q: &[f64], v: &[f64], mut t: f64) -> (f64, f64) {
    for j in model.rigid.joints.iter().flatten() {
        t += 0.5 * j.armature() * v[j.dof] * v[j.dof];
    }
    let nq = model.rigid.nq();
    let strain = (0..model.n_elastic)
        .map(|e| 0.5 * model.stiffness[e] * q[nq + e] * q[nq + e])
        .sum();
    (t, strain)
}
