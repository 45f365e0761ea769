//! Forward kinematics: hinge transforms `Xup`, inertial poses, body velocities and
//! accelerations (Featherstone §4.1 and the first pass of RNEA).

use crate::data::Data;
use crate::error::DynamicsError;
use crate::model::{BaseKind, Model};
use crate::spatial::{Motion, Vec3};
use nalgebra::{Quaternion, UnitQuaternion};

pub(crate) use crate::kernel_parts::check_len;

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

/// Poses (`data.rotation`, `data.position`), hinge transforms (`data.xup`) and spatial
/// velocities (`data.v`) of all bodies. The transforms are those [`crate::aba::aba`] computes
/// (the same [`Model`] function), so that ABA may reuse them
/// ([`crate::aba::aba_with_kinematics`]) when the caller has run kinematics for the same `q`;
/// the velocities equal ABA's to the last bit (tested).
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
        // The general product, inlined: equal to ABA's coordinate-axis path (which only
        // leaves out products with exact zeros and ones) and cheaper here than its call.
        data.v[i] = x.apply_motion(&data.v[p]) + joint.s * v[joint.dof];
    }
    Ok(())
}

/// The poses and hinge transforms of [`forward_kinematics`] (bit for bit), without the
/// velocities (`data.v` is left as it was): for a caller that reads only where the bodies
/// are (the gravity gradient, the centre of mass), a third less work.
///
/// ```
/// use satsim_tree::{Data, forward_kinematics, forward_poses, samples::chain, BaseKind};
/// let model = chain(3, BaseKind::Free);
/// let (mut a, mut b) = (Data::new(&model), Data::new(&model));
/// let q = model.neutral();
/// forward_kinematics(&model, &mut a, &q, &vec![0.5; model.nv()])?;
/// forward_poses(&model, &mut b, &q)?;
/// assert_eq!((a.rotation, a.position), (b.rotation, b.position));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn forward_poses(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), DynamicsError> {
    forward_poses_of(model, data, q, model.n_bodies())
}

/// [`forward_poses`] of the first `n` bodies only (`n ≤ n_bodies`; a parent comes before
/// its children, so these are closed under parents): their hinge transforms and poses, bit
/// for bit [`forward_poses`]'; every other body's entries keep whatever they held. For a
/// caller that reads none of the rest (a simulation whose effects read no pose of the
/// rotors it adds last).
///
/// ```
/// use satsim_tree::{Data, forward_poses, forward_poses_of, samples::chain, BaseKind};
/// let model = chain(3, BaseKind::Free);
/// let (mut all, mut two) = (Data::new(&model), Data::new(&model));
/// let q = model.neutral();
/// forward_poses(&model, &mut all, &q)?;
/// forward_poses_of(&model, &mut two, &q, 2)?;
/// assert_eq!(all.rotation[..2], two.rotation[..2]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn forward_poses_of(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    n: usize,
) -> Result<(), DynamicsError> {
    check_len("q", q.len(), model.nq())?;
    let n = n.min(model.n_bodies());
    let (att, pos) = base_pose(model, q);
    data.rotation[0] = att.to_rotation_matrix().into_inner();
    data.position[0] = pos;
    for i in 1..n {
        data.xup[i] = model.xup(i, q);
        let p = model.parent[i].expect("non-root body has a parent");
        // `forward_kinematics`' products, in its order (tested bit for bit). Written out rather
        // than shared: a shared helper moved the code layout of the kernel crates and cost one
        // orbit 24 % (docs/src/engineering/campaigns.md, "A lesson in measuring").
        let x = &data.xup[i];
        data.rotation[i] = data.rotation[p] * x.rot.transpose();
        data.position[i] = data.position[p] + data.rotation[p] * x.trans;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aba::{aba, aba_hybrid, aba_hybrid_with_kinematics, aba_with_kinematics};
    use crate::model::{Body, Hinge, ModelBuilder};
    use crate::samples::{SplitMix, random_inertia, random_tree_with_rotors};
    use crate::spatial::{Force, Mat3};

    /// A tree whose hinges take both paths: coordinate axes (positive and negative, hinge
    /// points off the child origin) and a general axis, plus a balanced rotor (a gyrostat).
    fn mixed(base: BaseKind, rng: &mut SplitMix) -> Model {
        let axes = [
            Vec3::x(),
            -Vec3::y(),
            Vec3::z(),
            Vec3::new(0.3, -0.4, 0.5).normalize(),
            -Vec3::x(),
        ];
        let mut b = ModelBuilder::new(base);
        b.push_body(Body::new("b0", 5.0, random_inertia(rng, 2.0)));
        for (k, axis) in axes.iter().enumerate() {
            let name = format!("b{}", k + 1);
            b.push_body(
                Body::new(name.clone(), rng.range(0.5, 2.0), random_inertia(rng, 1.0))
                    .with_com(rng.vec3(0.3)),
            );
            let parent = format!("b{}", k / 2);
            b.push_hinge(
                Hinge::revolute(format!("h{k}"), parent, name, *axis)
                    .at(rng.vec3(0.5))
                    .child_at(rng.vec3(0.5)),
            );
        }
        b.push_body(Body::new(
            "rotor",
            0.0,
            Mat3::from_diagonal(&Vec3::new(0.1, 0.1, 0.2)),
        ));
        b.push_hinge(Hinge::revolute("spin", "b0", "rotor", Vec3::z()).at(rng.vec3(0.5)));
        b.build().unwrap()
    }

    /// Forward kinematics leaves the transforms and velocities ABA computes, bit for bit,
    /// and ABA reusing them gives bit for bit the accelerations of plain ABA (hybrid too).
    #[test]
    fn kinematics_match_aba_and_its_reuse_is_exact() {
        let mut coordinate_paths = 0;
        for seed in 0..60u64 {
            let mut rng = SplitMix(seed ^ 0x7e57);
            let base = if seed % 4 == 0 {
                BaseKind::Fixed
            } else {
                BaseKind::Free
            };
            let model = if seed % 2 == 0 {
                mixed(base, &mut rng)
            } else {
                random_tree_with_rotors(3 + (seed % 9) as usize, base, true, 2, seed)
            };
            coordinate_paths += model.coord_axis.iter().flatten().count();
            let mut q = model.neutral();
            let nb = model.base_nq();
            if base == BaseKind::Free {
                let a = Quaternion::new(0.4, rng.range(-1.0, 1.0), -0.3, 0.2).normalize();
                q[..4].copy_from_slice(&[a.w, a.i, a.j, a.k]);
            }
            for x in &mut q[nb..] {
                *x = rng.range(-3.0, 3.0);
            }
            let v: Vec<f64> = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
            let tau: Vec<f64> = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
            let fext: Vec<Force> = (0..model.n_bodies())
                .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
                .collect();
            let locked: Vec<bool> = (0..model.n_hinges())
                .map(|_| rng.next_f64() < 0.3)
                .collect();
            let mut data = Data::new(&model);
            let Ok(plain) = aba(&model, &mut data, &q, &v, &tau, Some(&fext)).cloned() else {
                continue; // a singular gimbal of massless links
            };
            let aba_v = data.v.clone();
            // Fresh buffers: the transforms come from kinematics, not from that ABA call.
            let mut data = Data::new(&model);
            let stale = aba_with_kinematics(&model, &mut data, &q, &v, &tau, Some(&fext))
                .map(|a| a != &plain);
            assert!(
                stale.unwrap_or(true),
                "seed {seed}: the transforms were recomputed"
            );
            forward_kinematics(&model, &mut data, &q, &v).unwrap();
            let mut poses = Data::new(&model);
            forward_poses(&model, &mut poses, &q).unwrap();
            assert_eq!(
                (&poses.rotation, &poses.position, &poses.xup),
                (&data.rotation, &data.position, &data.xup),
                "seed {seed}: the poses alone"
            );
            // The first bodies' alone: theirs bit for bit, the rest untouched.
            let n = 1 + seed as usize % model.n_bodies();
            let mut first = Data::new(&model);
            forward_poses_of(&model, &mut first, &q, n).unwrap();
            let fresh = Data::new(&model);
            for i in 0..model.n_bodies() {
                let want = if i < n { &data } else { &fresh };
                assert_eq!(
                    (first.rotation[i], first.position[i], &first.xup[i]),
                    (want.rotation[i], want.position[i], &want.xup[i]),
                    "seed {seed}: the first {n} poses, body {i}"
                );
            }
            for (i, aba_vi) in aba_v.iter().enumerate().skip(1) {
                assert_eq!(data.xup[i], model.xup(i, &q), "seed {seed} body {i}");
                if !model.is_gyrostat[i] {
                    assert_eq!(&data.v[i], aba_vi, "seed {seed} body {i}");
                }
            }
            let reused = aba_with_kinematics(&model, &mut data, &q, &v, &tau, Some(&fext))
                .unwrap()
                .clone();
            assert_eq!(reused, plain, "seed {seed}");
            let Ok(hybrid) = aba_hybrid(&model, &mut data, &q, &v, &tau, None, &locked).cloned()
            else {
                continue;
            };
            let mut data = Data::new(&model);
            forward_kinematics(&model, &mut data, &q, &v).unwrap();
            let reused =
                aba_hybrid_with_kinematics(&model, &mut data, &q, &v, &tau, None, &locked).unwrap();
            assert_eq!(reused, &hybrid, "seed {seed}");
        }
        assert!(
            coordinate_paths > 50,
            "{coordinate_paths} coordinate-axis hinges"
        );
    }
}
