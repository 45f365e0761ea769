//! The recursive Newton-Euler algorithm (Featherstone §5.3): inverse dynamics.

use crate::data::Data;
use crate::error::DynamicsError;
use crate::kinematics::{base_motion, check_len, update_transforms};
use crate::model::{BaseKind, Model};
use crate::spatial::Force;
use nalgebra::DVector;

/// Inverse dynamics: the generalised forces `τ = M(q) a + C(q, v) − Jᵀ fext` that produce
/// accelerations `a`, into `data.tau`.
///
/// `fext`, when given, holds one spatial force per body (`model.bodies` order) in the body's
/// own coordinates about its frame origin, acting ON the body. For a free base the first six
/// entries of `τ` are the wrench `[n; f]` that would have to act on the root (zero for a
/// free-floating spacecraft); a hinge's entry is the torque about its axis acting on its
/// child and reacting on its parent. No gravity: a spacecraft is in free fall.
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, rnea, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Fixed)
///     .body(Body::new("table", 0.0, Mat3::zeros()))
///     .body(Body::new("wheel", 0.0, Mat3::from_diagonal(&Vec3::new(1.0, 1.0, 2.0))))
///     .hinge(Hinge::revolute("spin", "table", "wheel", Vec3::z()))
///     .build()?;
/// let mut data = Data::new(&model);
/// let tau = rnea(&model, &mut data, &[0.0], &[5.0], &[3.0], None)?;
/// assert!((tau[0] - 6.0).abs() < 1e-12); // I α
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn rnea<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    if let Some(f) = fext {
        check_len("fext", f.len(), model.n_bodies())?;
    }
    check_len("a", a.len(), model.nv())?;
    check_len("v", v.len(), model.nv())?;
    update_transforms(model, data, q)?;
    let n = model.n_bodies();
    // Pass 1, outward: velocities, accelerations and the forces that produce them (the
    // inertial poses of `forward_kinematics` are not needed).
    data.v[0] = base_motion(model, v);
    data.a[0] = base_motion(model, a);
    for i in 0..n {
        if let Some(joint) = &model.joints[i] {
            let p = model.parent[i].expect("parent");
            let x = &data.xup[i];
            let vj = joint.s * v[joint.dof];
            data.v[i] = x.apply_motion(&data.v[p]) + vj;
            data.a[i] =
                x.apply_motion(&data.a[p]) + joint.s * a[joint.dof] + data.v[i].cross_motion(&vj);
        }
        let inertia = &model.bodies[i].inertia;
        let vi = data.v[i];
        data.f[i] = inertia.mul_motion(&data.a[i]) + vi.cross_force(&inertia.mul_motion(&vi));
        if let Some(f) = fext {
            data.f[i] -= f[i];
        }
    }
    // Pass 2, inward: hinge forces and torques.
    for i in (1..n).rev() {
        let joint = model.joints[i].as_ref().expect("joint");
        data.tau[joint.dof] = joint.s.dot(&data.f[i]) + joint.armature * a[joint.dof];
        let p = model.parent[i].expect("parent");
        let fp = data.xup[i].inv_apply_force(&data.f[i]);
        data.f[p] += fp;
    }
    if model.base == BaseKind::Free {
        let f0: Force = data.f[0];
        for (r, x) in [f0.ang.x, f0.ang.y, f0.ang.z, f0.lin.x, f0.lin.y, f0.lin.z]
            .into_iter()
            .enumerate()
        {
            data.tau[r] = x;
        }
    }
    Ok(&data.tau)
}

/// The bias forces `C(q, v) − Jᵀ fext` (RNEA with zero acceleration), into `data.bias`.
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, bias, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 1.0, Mat3::from_diagonal(&Vec3::new(1.0, 2.0, 3.0))))
///     .build()?;
/// let mut data = Data::new(&model);
/// // Euler's equations: the gyroscopic term ω × Iω.
/// let c = bias(&model, &mut data, &model.neutral(), &[1.0, 1.0, 0.0, 0.0, 0.0, 0.0], None)?;
/// assert!((c[2] - 1.0).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn bias<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    // Borrow the (unused) ddq buffer as the zero acceleration to avoid an allocation.
    data.ddq.fill(0.0);
    let zero = std::mem::take(&mut data.ddq);
    let result = rnea(model, data, q, v, zero.as_slice(), fext).map(|_| ());
    data.ddq = zero;
    result?;
    data.bias.copy_from(&data.tau);
    Ok(&data.bias)
}
