//! Forward kinematics: hinge transforms `Xup`, inertial poses, body velocities and
//! accelerations (Featherstone §4.1 and the first pass of RNEA).

use crate::data::Data;
use crate::error::DynamicsError;
use crate::model::{BaseKind, Model};
use crate::spatial::{Motion, Vec3};
use nalgebra::{Quaternion, UnitQuaternion};

pub(crate) fn check_len(
    what: &'static str,
    got: usize,
    expected: usize,
) -> Result<(), DynamicsError> {
    if got != expected {
        return Err(DynamicsError::Dimension {
            what,
            expected,
            got,
        });
    }
    Ok(())
}

/// Computes `Xup[i]` for every hinge from the angles in `q`.
pub fn update_transforms(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), DynamicsError> {
    check_len("q", q.len(), model.nq())?;
    for i in 1..model.n_bodies() {
        data.xup[i] = model.xup(i, q);
    }
    Ok(())
}

/// The root attitude (root body to inertial) and position held in a free base's `q`.
pub fn base_pose(model: &Model, q: &[f64]) -> (UnitQuaternion<f64>, Vec3) {
    match model.base {
        BaseKind::Free => (
            UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
            Vec3::new(q[4], q[5], q[6]),
        ),
        BaseKind::Fixed => (UnitQuaternion::identity(), Vec3::zeros()),
    }
}

/// The root's spatial velocity held in `v` (zero for a fixed base).
#[inline]
pub(crate) fn base_motion(model: &Model, s: &[f64]) -> Motion {
    match model.base {
        BaseKind::Free => Motion::from_slice(s),
        BaseKind::Fixed => Motion::zero(),
    }
}

/// Poses (`data.rotation`, `data.position`) and spatial velocities (`data.v`) of all bodies.
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, forward_kinematics, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Fixed)
///     .body(Body::new("table", 1.0, Mat3::identity()))
///     .body(Body::new("arm", 1.0, Mat3::identity()))
///     .hinge(Hinge::revolute("h", "table", "arm", Vec3::z()).child_at(Vec3::new(-1.0, 0.0, 0.0)))
///     .build()?;
/// let mut data = Data::new(&model);
/// forward_kinematics(&model, &mut data, &[std::f64::consts::FRAC_PI_2], &[2.0])?;
/// assert!((data.position[1] - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
/// assert!((data.v[1].lin - Vec3::new(0.0, 2.0, 0.0)).norm() < 1e-12); // body axes
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn forward_kinematics(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<(), DynamicsError> {
    check_len("v", v.len(), model.nv())?;
    update_transforms(model, data, q)?;
    let (att, pos) = base_pose(model, q);
    data.rotation[0] = att.to_rotation_matrix().into_inner();
    data.position[0] = pos;
    data.v[0] = base_motion(model, v);
    for i in 1..model.n_bodies() {
        let p = model.parent[i].expect("non-root body has a parent");
        let joint = model.joints[i].as_ref().expect("joint");
        let x = data.xup[i];
        data.rotation[i] = data.rotation[p] * x.rot.transpose();
        data.position[i] = data.position[p] + data.rotation[p] * x.trans;
        data.v[i] = x.apply_motion(&data.v[p]) + joint.s * v[joint.dof];
    }
    Ok(())
}

/// As [`forward_kinematics`], plus spatial accelerations `data.a` for generalised
/// accelerations `a` (body-frame derivative convention for the base, as in `v`).
pub fn forward_kinematics_acc(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> Result<(), DynamicsError> {
    check_len("a", a.len(), model.nv())?;
    forward_kinematics(model, data, q, v)?;
    data.a[0] = base_motion(model, a);
    for i in 1..model.n_bodies() {
        let p = model.parent[i].expect("parent");
        let joint = model.joints[i].as_ref().expect("joint");
        let vj = joint.s * v[joint.dof];
        data.a[i] = data.xup[i].apply_motion(&data.a[p])
            + joint.s * a[joint.dof]
            + data.v[i].cross_motion(&vj);
    }
    Ok(())
}
