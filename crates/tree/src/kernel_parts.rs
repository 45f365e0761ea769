//! Parts for specialised forward-dynamics kernels: what a [`crate::Kernel`] built outside
//! this crate (e.g. `satsim-satellite`'s unrolled ABA for the preprint satellite) needs of the
//! engine's internals to be the same algorithm as [`crate::aba::aba`], with the same errors.
//!
//! A kernel is ABA specialised for one layout, its constants folded in once; to give the
//! generic algorithm's results to round-off, and its errors exactly, it reads the model as
//! ABA does and tests pivots as ABA does:
//!
//! - [`CoordAxis`]: a hinge about a coordinate axis, and the fast-path products ABA takes
//!   for it (transforms, inertia similarities, projections), [`coord_axis`] per body;
//! - the model's ABA forms: [`ChainPart`] and [`chain_part`] (the multi-axis
//!   [`crate::Chain`]s), [`is_gyrostat`], [`carrier_inertia`] and [`carrier_start`] (the
//!   gyrostat form, [`crate::Gyrostat`]), [`hinge_transform`] (a hinge's `Xup` as ABA
//!   computes it);
//! - ABA's pivot test and its error: [`SINGULAR_PIVOT_RELATIVE`], [`offset_scale`],
//!   [`massless_hinges_below`] (the hinges a [`DynamicsError::SingularHinge`] names);
//! - shared pieces of the chain form: [`add_linear_inv_transform`];
//! - [`check_len`]: the dimension check (and its [`DynamicsError::Dimension`]).
//!
//! Nothing here is needed to *call* forward dynamics: that is [`crate::ForwardDynamics`].

use crate::error::DynamicsError;
use crate::model::{Joint, Model};
use crate::real::{Real, mat3};
use crate::spatial::{
    ArticulatedInertia, Force, Mat3, RigidInertia, Transform, Vec3, add_blocks, cross_columns, skew,
};
use nalgebra::Matrix3;

pub use crate::axis::CoordAxis;
pub use crate::model::ChainPart;

/// Pivots `Dᵢ` below this fraction of the articulated inertia's scale are singular (ABA's
/// test, and every kernel's).
pub const SINGULAR_PIVOT_RELATIVE: f64 = 1e-13;

/// `Ok` where `got == expected`, else the [`DynamicsError::Dimension`] error naming `what`
/// (the argument's name, as the engine's algorithms name theirs: `"q"`, `"v"`, `"tau"`,
/// `"fext"`, `"locked"`, `"ddq"`).
#[inline]
pub fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), DynamicsError> {
    if got != expected {
        return Err(DynamicsError::Dimension {
            what,
            expected,
            got,
        });
    }
    Ok(())
}

/// Body `body`'s hinge as a coordinate-axis hinge, where it turns about one with no fixed
/// rotation (the fast path of the per-call algorithms); `None` for the root and for general
/// hinges.
pub fn coord_axis(model: &Model, body: usize) -> Option<CoordAxis> {
    model.coord_axis[body]
}

/// Body `body`'s part in a [`crate::Chain`] (a massless link, a tip, or neither).
pub fn chain_part(model: &Model, body: usize) -> ChainPart {
    model.chain_part[body]
}

/// Whether body `body` is a [`crate::Gyrostat`] rotor (ABA folds it into its parent).
pub fn is_gyrostat(model: &Model, body: usize) -> bool {
    model.is_gyrostat[body]
}

/// Body `body`'s rigid inertia with its gyrostat rotors locked on: what ABA's gyrostat form
/// takes as the body's inertia in its velocity-product (bias) terms.
pub fn carrier_inertia(model: &Model, body: usize) -> &RigidInertia {
    &model.carrier_inertia[body]
}

/// The articulated inertia ABA's gyrostat form starts body `body` from: its carrier inertia
/// less `J a aᵀ` (angular block) for each of its rotors (which are free about their axes).
pub fn carrier_start(model: &Model, body: usize) -> &ArticulatedInertia {
    &model.carrier_ia[body]
}

/// `Xup` of `joint` at angle `phi`, through its coordinate-axis form `axis` where it has one
/// ([`coord_axis`]): bit for bit the transform ABA computes.
#[inline]
pub fn hinge_transform(joint: &Joint, axis: Option<&CoordAxis>, phi: f64) -> Transform {
    joint.transform_with(axis, phi)
}

/// `out += Xᵀ [0 0; 0 C] X` (or `out = start + ...`): a purely linear inertia (what a
/// spherical joint passes on) moved by `X`, `Eᵀ C E` then the translation's two lever terms.
#[inline(always)]
pub fn add_linear_inv_transform<T: Real>(
    c: &Matrix3<T>,
    x: &Transform<T>,
    out: &mut ArticulatedInertia<T>,
    start: Option<&ArticulatedInertia<T>>,
) {
    let c = mat3::tr_mul_mat(&x.rot, &mat3::mul_mat(c, &x.rot));
    // [1 [r]×; 0 1] [0 0; 0 C] [1 0; −[r]× 1] = [−[r]×C[r]× [r]×C; −C[r]× C].
    let nb = cross_columns(&x.trans, &c);
    let na = cross_columns(&x.trans, &nb.transpose()).transpose();
    add_blocks(&na, &nb, &c, out, start);
}

/// The tree form's singular-pivot scale of a chain's link whose origin lies at `d` from the
/// hinge point (tip's axes): `tr A + |d|² tr C` of the link's articulated inertia about its
/// origin, where the inertia at the point is `[A_h B_h; B_hᵀ C] − Σ w wᵀ / Δ` (the hinges
/// eliminated before it) with `tr A` = `tr_a`, `tr C` = `tr_c` already projected.
pub fn offset_scale(
    d: &Vec3,
    bh: &Mat3,
    c: &Mat3,
    w: &[Force],
    piv: &[f64],
    tr_a: f64,
    tr_c: f64,
) -> f64 {
    // About the origin, A_o = A + B[d]× − [d]×Bᵀ − [d]×C[d]×, so
    // tr A_o = tr A − 2 tr([d]×Bᵀ) − dᵀCd + |d|² tr C.
    let mut tr_db = (skew(d) * bh.transpose()).trace();
    let mut dcd = d.dot(&(c * d));
    for (w, &p) in w.iter().zip(piv) {
        tr_db -= w.ang.dot(&d.cross(&w.lin)) / p;
        dcd -= d.dot(&w.lin).powi(2) / p;
    }
    let d2 = d.norm_squared();
    tr_a - 2.0 * tr_db - dcd + d2 * tr_c + tr_c * d2
}

/// The hinges reached from body `i` downwards through massless bodies: the other axes of a
/// multi-axis hinge made of massless links (named in a singular-configuration error).
pub fn massless_hinges_below(model: &Model, i: usize) -> Vec<String> {
    let mut names = Vec::new();
    let mut stack = vec![i];
    while let Some(b) = stack.pop() {
        if model.bodies[b].mass != 0.0 {
            continue;
        }
        for c in model.children(b) {
            let joint = model.joints[c].as_ref().expect("joint");
            names.push(model.hinge_names[joint.hinge].clone());
            stack.push(c);
        }
    }
    names
}
