//! Forward kinematics and momentum of a tree with flexible bodies, into the rigid
//! [`Data`]'s poses: what the effects of a simulation read of each body.

use super::data::{FlexData, check_state, transforms, velocities};
use super::model::FlexModel;
use crate::data::Data;
use crate::energy::center_of_mass;
use crate::error::DynamicsError;
use crate::kinematics::{base_pose, check_len};
use crate::spatial::Vec3;

/// Poses (`data.rotation`, `data.position`), hinge transforms (`data.xup`) and spatial
/// velocities (`data.v`) of every body of `model`'s rigid tree, with each hinge on a
/// flexible parent carried by the deformation at its point (as [`super::aba()`] moves it).
/// A body's frame is its floating reference frame: its own deformation moves its material,
/// not its frame. Fills `flex`'s first pass as well.
pub fn forward_kinematics(
    model: &FlexModel,
    flex: &mut FlexData,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<(), DynamicsError> {
    check_state(model, q, v)?;
    velocities(model, flex, q, v);
    place(model, flex, data, q);
    data.v.copy_from_slice(&flex.v);
    Ok(())
}

/// [`forward_kinematics`]'s poses alone (`data.rotation`, `data.position`, `data.xup`), the
/// same bits, for a caller that reads no velocity (a view): the first pass's transforms
/// without its velocities, motion subspaces and deformed inertias. `data.v` is left as it
/// was.
pub fn forward_poses(
    model: &FlexModel,
    flex: &mut FlexData,
    data: &mut Data,
    q: &[f64],
) -> Result<(), DynamicsError> {
    check_len("q", q.len(), model.nq())?;
    transforms(model, flex, q);
    place(model, flex, data, q);
    Ok(())
}

/// The bodies' poses in `data` from the first pass's transforms in `flex`.
fn place(model: &FlexModel, flex: &FlexData, data: &mut Data, q: &[f64]) {
    let rigid = &model.rigid;
    let (att, pos) = base_pose(rigid, q);
    data.rotation[0] = att.to_rotation_matrix().into_inner();
    data.position[0] = pos;
    for i in 1..rigid.n_bodies() {
        let p = rigid.parent[i].expect("non-root body has a parent");
        let x = flex.xup[i];
        data.xup[i] = x;
        data.rotation[i] = data.rotation[p] * x.rot.transpose();
        data.position[i] = data.position[p] + data.rotation[p] * x.trans;
    }
}

/// Total linear momentum (N s) and angular momentum about the system's centre of mass
/// (N m s), inertial axes, after [`forward_kinematics`] on `(q, v)`: each body's
/// `[[I, P], [Pᵀ, 1]] [vᵢ; η̇ᵢ]`'s frame part, `I vᵢ + P η̇ᵢ` (with stiffening, `I(η)` and
/// `P(η)` at the deformation), the momentum conjugate to the frame's motion. The centre of mass is the
/// undeformed bodies' (the linear model leaves the deformation's first moment out of the
/// kinetic energy, and so out of the centre of mass) unless a body has `stiffening`: then
/// the first moments at the deformation (`b S₁ᵀ η − ½ (ηᵀ J₀ η) a` of each stiffened beam),
/// the centre of mass whose velocity is the linear momentum over the mass, about which the
/// angular momentum is conserved whatever the linear momentum.
pub fn momentum(model: &FlexModel, data: &Data, q: &[f64], v: &[f64]) -> (Vec3, Vec3) {
    let rigid = &model.rigid;
    let nv = rigid.nv();
    let mut p = Vec3::zeros();
    let mut h_origin = Vec3::zeros();
    let (mut mass, mut first) = (0.0, Vec3::zeros());
    for i in 0..rigid.n_bodies() {
        let inertia = model.inertia_at(i, q);
        mass += inertia.mass;
        first += data.position[i] * inertia.mass + data.rotation[i] * inertia.h;
        let mut f = inertia.mul_motion(&data.v[i]);
        for k in 0..model.modes[i] {
            let e = model.offset[i] + k;
            f += model.momentum_at(i, q, k) * v[nv + e];
        }
        let r = &data.rotation[i];
        let lin = r * f.lin;
        p += lin;
        h_origin += r * f.ang + data.position[i].cross(&lin);
    }
    let c = if model.stiffening.iter().any(Option::is_some) {
        first / mass
    } else {
        center_of_mass(rigid, data)
    };
    (p, h_origin - c.cross(&p))
}

/// [`super::energy`] and [`momentum`] in one pass, after [`forward_kinematics`] on `(q, v)`:
/// the first pass's velocities and deformed inertias in `flex` are read, not made again (an
/// output row's kinematics has just made them), and each body's momentum `I vᵢ + P η̇ᵢ` is
/// formed once for both. Bit for bit the two functions' values, as
/// `(kinetic, strain, p, h)`.
pub fn energy_and_momentum(
    model: &FlexModel,
    flex: &FlexData,
    data: &Data,
    q: &[f64],
    v: &[f64],
) -> (f64, f64, Vec3, Vec3) {
    let rigid = &model.rigid;
    let mut t = 0.0;
    let (mut p, mut h_origin) = (Vec3::zeros(), Vec3::zeros());
    let (mut mass, mut first) = (0.0, Vec3::zeros());
    for i in 0..rigid.n_bodies() {
        let f = super::body_momentum(model, flex, i, q, v, &mut t);
        let inertia = &flex.inertia[i];
        mass += inertia.mass;
        first += data.position[i] * inertia.mass + data.rotation[i] * inertia.h;
        let r = &data.rotation[i];
        let lin = r * f.lin;
        p += lin;
        h_origin += r * f.ang + data.position[i].cross(&lin);
    }
    let (t, strain) = super::add_armature_and_strain(model, q, v, t);
    let c = if model.stiffening.iter().any(Option::is_some) {
        first / mass
    } else {
        center_of_mass(rigid, data)
    };
    (t, strain, p, h_origin - c.cross(&p))
}
