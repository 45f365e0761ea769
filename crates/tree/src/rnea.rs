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
        motion_at(model, data, i, v, a);
        force_at(model, data, i, fext);
    }
    // Pass 2, inward: hinge forces and torques.
    for i in (1..n).rev() {
        let p = torque_at(model, data, i, a);
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

/// [`rnea`]'s torques of the hinges `which` only (`which[k]`: hinge `k`, the entry
/// `τ[base_nv + k]`), for a caller that reads a few of them (the hold torques of locked
/// reaction wheels). Only the bodies those torques depend on are visited: the subtree below
/// each hinge asked for (every entry of which is written) and its ancestors (velocities and
/// accelerations only). Each visited body takes `rnea`'s own steps, in the same order, so
/// the torques written are `rnea`'s bit for bit; the other entries of `data.tau` (a free
/// base's wrench among them) keep whatever they held.
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, rnea, rnea_for, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 10.0, Mat3::identity()))
///     .body(Body::new("arm", 1.0, Mat3::identity()))
///     .body(Body::new("wheel", 0.5, Mat3::from_diagonal(&Vec3::new(0.1, 0.1, 0.2))))
///     .hinge(Hinge::revolute("shoulder", "bus", "arm", Vec3::y()).child_at(Vec3::new(-1.0, 0.0, 0.0)))
///     .hinge(Hinge::revolute("spin", "bus", "wheel", Vec3::z()))
///     .build()?;
/// let (q, v, a) = (model.neutral(), [0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 0.5, 2.0], [0.3; 8]);
/// let mut data = Data::new(&model);
/// let all = rnea(&model, &mut data, &q, &v, &a, None)?.clone();
/// let some = rnea_for(&model, &mut data, &q, &v, &a, None, &[false, true])?;
/// assert_eq!(some[7].to_bits(), all[7].to_bits());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn rnea_for<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    fext: Option<&[Force]>,
    which: &[bool],
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_some(model, q, v, a, fext, which)?;
    let nb = model.base_nv();
    let n = model.n_bodies();
    // Which bodies: below a hinge asked for (parents come first), then their ancestors.
    const ABOVE: u8 = 1;
    const BELOW: u8 = 2;
    let reach = &mut data.rnea_reach;
    reach[0] = 0;
    for i in 1..n {
        let joint = model.joints[i].as_ref().expect("joint");
        let p = model.parent[i].expect("parent");
        reach[i] = if which[joint.dof - nb] || reach[p] == BELOW {
            BELOW
        } else {
            0
        };
    }
    for i in (1..n).rev() {
        let p = model.parent[i].expect("parent");
        if reach[i] != 0 && reach[p] == 0 {
            reach[p] = ABOVE;
        }
    }
    if reach.iter().all(|&r| r == 0) {
        return Ok(&data.tau);
    }
    // Pass 1, outward, as `rnea`'s.
    data.v[0] = base_motion(model, v);
    data.a[0] = base_motion(model, a);
    for i in 0..n {
        if data.rnea_reach[i] == 0 {
            continue;
        }
        if i > 0 {
            data.xup[i] = model.xup(i, q);
        }
        motion_at(model, data, i, v, a);
        if data.rnea_reach[i] == BELOW {
            force_at(model, data, i, fext);
        }
    }
    // Pass 2, inward, within the subtrees (a body below a hinge asked for has all its
    // children below it too, so its force sums them in `rnea`'s order).
    for i in (1..n).rev() {
        if data.rnea_reach[i] != BELOW {
            continue;
        }
        let p = torque_at(model, data, i, a);
        if data.rnea_reach[p] == BELOW {
            let fp = data.xup[i].inv_apply_force(&data.f[i]);
            data.f[p] += fp;
        }
    }
    Ok(&data.tau)
}

/// [`rnea_for`] where every hinge asked for is a [`Gyrostat`](crate::Gyrostat) rotor's
/// (a balanced axisymmetric leaf on a hinge without armature): its torque by the rotor's
/// closed form instead of the rotor's own pass, to round-off the same (tested).
///
/// The axial part of the rotor's Euler equation about its centre of mass (which lies on
/// the axis, so the hinge's reaction force has no moment about it) is
/// `τ + aᵀ n_ext = aᵀ (I ω̇ + ω × I ω)` with `ω = ω_c + a q̇` its angular velocity. For
/// `I = J a aᵀ + Iₜ (1 − a aᵀ)`, `aᵀ (ω × I ω) = 0`, and `aᵀ ω̇ = aᵀ ω̇_c + q̈` (the axis
/// turns with the carrier, `ȧ = ω_c × a ⟂ a`), so
///
/// `τ = J (aᵀ ω̇_c + q̈) − Sᵀ f_ext`,
///
/// `ω̇_c` the carrier's angular acceleration (its axes: the angular part of its spatial
/// acceleration) and `Sᵀ f_ext` the rotor's external moment about the axis. Only the
/// carriers and their ancestors are visited (velocities and accelerations); no rotor
/// transform (a `sin_cos`) or inertia. Returns `None`, with nothing written, where a hinge
/// asked for is not a gyrostat rotor's (then use [`rnea_for`]); the entries not asked for
/// keep whatever they held.
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, gyrostat_torques, rnea, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 10.0, Mat3::identity()))
///     .body(Body::new("wheel", 0.5, Mat3::from_diagonal(&Vec3::new(0.1, 0.1, 0.2))))
///     .hinge(Hinge::revolute("spin", "bus", "wheel", Vec3::z()))
///     .build()?;
/// let (q, v, a) = (model.neutral(), [0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 50.0], [0.3; 7]);
/// let mut data = Data::new(&model);
/// let all = rnea(&model, &mut data, &q, &v, &a, None)?[6];
/// let closed = gyrostat_torques(&model, &mut data, &q, &v, &a, None, &[true])?.expect("a gyrostat");
/// assert!((closed[6] - all).abs() < 1e-14);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn gyrostat_torques<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    fext: Option<&[Force]>,
    which: &[bool],
) -> Result<Option<&'d DVector<f64>>, DynamicsError> {
    check_some(model, q, v, a, fext, which)?;
    let nb = model.base_nv();
    let n = model.n_bodies();
    // The bodies to visit: each asked rotor's carrier and its ancestors.
    const ABOVE: u8 = 1;
    let reach = &mut data.rnea_reach;
    reach.fill(0);
    for i in 1..n {
        let joint = model.joints[i].as_ref().expect("joint");
        if which[joint.dof - nb] {
            if !model.is_gyrostat[i] {
                return Ok(None);
            }
            let mut c = model.parent[i];
            while let Some(p) = c {
                reach[p] = ABOVE;
                c = model.parent[p];
            }
        }
    }
    // Pass 1, outward, as `rnea`'s, over those bodies.
    data.v[0] = base_motion(model, v);
    data.a[0] = base_motion(model, a);
    for i in 1..n {
        if data.rnea_reach[i] == ABOVE {
            data.xup[i] = model.xup(i, q);
            motion_at(model, data, i, v, a);
        }
    }
    for g in &model.gyrostats {
        let joint = model.joints[g.body].as_ref().expect("joint");
        if which[joint.dof - nb] {
            let n_ext = fext.map_or(0.0, |f| joint.s.dot(&f[g.body]));
            data.tau[joint.dof] =
                g.axial * (g.axis.dot(&data.a[g.parent].ang) + a[joint.dof]) - n_ext;
        }
    }
    Ok(Some(&data.tau))
}

/// The lengths [`rnea_for`] and [`gyrostat_torques`] check.
fn check_some(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    fext: Option<&[Force]>,
    which: &[bool],
) -> Result<(), DynamicsError> {
    if let Some(f) = fext {
        check_len("fext", f.len(), model.n_bodies())?;
    }
    check_len("a", a.len(), model.nv())?;
    check_len("v", v.len(), model.nv())?;
    check_len("q", q.len(), model.nq())?;
    check_len("which", which.len(), model.nv() - model.base_nv())
}

/// Pass 1 at body `i` (its transform current): its velocity and acceleration from its
/// parent's. One body's step, shared by [`rnea`] and [`rnea_for`], so that they agree bit
/// for bit by construction.
#[inline(always)]
fn motion_at(model: &Model, data: &mut Data, i: usize, v: &[f64], a: &[f64]) {
    if let Some(joint) = &model.joints[i] {
        let p = model.parent[i].expect("parent");
        let x = &data.xup[i];
        let vj = joint.s * v[joint.dof];
        data.v[i] = x.apply_motion(&data.v[p]) + vj;
        data.a[i] =
            x.apply_motion(&data.a[p]) + joint.s * a[joint.dof] + data.v[i].cross_motion(&vj);
    }
}

/// Pass 1 at body `i`: the force that produces its motion, less the external one.
#[inline(always)]
fn force_at(model: &Model, data: &mut Data, i: usize, fext: Option<&[Force]>) {
    let inertia = &model.bodies[i].inertia;
    let vi = data.v[i];
    data.f[i] = inertia.mul_motion(&data.a[i]) + vi.cross_force(&inertia.mul_motion(&vi));
    if let Some(f) = fext {
        data.f[i] -= f[i];
    }
}

/// Pass 2 at body `i` (`i > 0`, its force complete): its hinge's torque. Returns its parent.
#[inline(always)]
fn torque_at(model: &Model, data: &mut Data, i: usize, a: &[f64]) -> usize {
    let joint = model.joints[i].as_ref().expect("joint");
    data.tau[joint.dof] = joint.s.dot(&data.f[i]) + joint.armature * a[joint.dof];
    model.parent[i].expect("parent")
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples::{SplitMix, random_q, random_tree};

    /// A free base for even seeds, fixed for odd ones.
    fn base_of(seed: u64) -> BaseKind {
        if seed.is_multiple_of(2) {
            BaseKind::Free
        } else {
            BaseKind::Fixed
        }
    }

    /// A random state of `model`: `q`, rates within `±rate`, accelerations within ±2 and a
    /// wrench on every body.
    fn random_motion(
        model: &Model,
        rng: &mut SplitMix,
        rate: f64,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Force>) {
        let nv = model.nv();
        let q = random_q(model, rng, 2.0);
        let v = (0..nv).map(|_| rng.range(-rate, rate)).collect();
        let a = (0..nv).map(|_| rng.range(-2.0, 2.0)).collect();
        let fext = (0..model.n_bodies())
            .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
            .collect();
        (q, v, a, fext)
    }

    /// Every torque `rnea_for` writes is `rnea`'s bit for bit, and it writes the hinges
    /// asked for and only entries below them: random trees (free and fixed, with massless
    /// links), states, external forces and masks.
    #[test]
    fn rnea_for_is_rnea_on_the_hinges_asked_for() {
        let mut rng = SplitMix(29);
        let mut checked = 0;
        for seed in 0..40 {
            let model = random_tree(2 + seed as usize % 7, base_of(seed), seed % 3 == 0, seed);
            let (nv, nb) = (model.nv(), model.base_nv());
            let (q, v, a, fext) = random_motion(&model, &mut rng, 2.0);
            for with_fext in [false, true] {
                let fext = with_fext.then_some(fext.as_slice());
                let mut data = Data::new(&model);
                let all = rnea(&model, &mut data, &q, &v, &a, fext).unwrap().clone();
                for _ in 0..4 {
                    let which: Vec<bool> = (0..nv - nb).map(|_| rng.next_f64() < 0.3).collect();
                    let mut data = Data::new(&model);
                    data.tau.fill(f64::NAN);
                    let some = rnea_for(&model, &mut data, &q, &v, &a, fext, &which).unwrap();
                    for (k, &asked) in which.iter().enumerate() {
                        let t = some[nb + k];
                        if asked {
                            assert_eq!(t.to_bits(), all[nb + k].to_bits(), "seed {seed} hinge {k}");
                            checked += 1;
                        } else {
                            assert!(t.is_nan() || t.to_bits() == all[nb + k].to_bits());
                        }
                    }
                    assert!(some.as_slice()[..nb].iter().all(|t| t.is_nan()));
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }

    /// The gyrostat rotors' closed form gives `rnea`'s torques to round-off (random trees with
    /// rotors of random mass, axis and hinge point, free and fixed bases, with and without
    /// external wrenches on every body), writes only the hinges asked for, and declines a
    /// hinge that is not a gyrostat rotor's.
    #[test]
    fn gyrostat_torques_are_rneas() {
        use crate::samples::random_tree_with_rotors;
        let mut rng = SplitMix(31);
        let mut checked = 0;
        for seed in 0..40 {
            let model = random_tree_with_rotors(
                2 + seed as usize % 6,
                base_of(seed),
                seed % 3 == 0,
                3,
                seed,
            );
            assert!(!model.gyrostats().is_empty(), "seed {seed}");
            let (nv, nb) = (model.nv(), model.base_nv());
            let (q, v, a, fext) = random_motion(&model, &mut rng, 20.0);
            let rotor_hinge = |i: usize| model.joints[i].as_ref().unwrap().dof - nb;
            for with_fext in [false, true] {
                let fext = with_fext.then_some(fext.as_slice());
                let mut data = Data::new(&model);
                let all = rnea(&model, &mut data, &q, &v, &a, fext).unwrap().clone();
                let scale = all.amax().max(1.0);
                let mut which = vec![false; nv - nb];
                for g in model.gyrostats() {
                    which[rotor_hinge(g.body())] = true;
                }
                let mut data = Data::new(&model);
                data.tau.fill(f64::NAN);
                let closed = gyrostat_torques(&model, &mut data, &q, &v, &a, fext, &which)
                    .unwrap()
                    .expect("every hinge asked is a rotor's");
                for (k, &asked) in which.iter().enumerate() {
                    if asked {
                        let err = (closed[nb + k] - all[nb + k]).abs();
                        assert!(err < 1e-12 * scale, "seed {seed} hinge {k}: {err:e}");
                        checked += 1;
                    } else {
                        assert!(closed[nb + k].is_nan(), "seed {seed} hinge {k} written");
                    }
                }
                // A hinge that is no rotor's: declined, nothing written.
                if let Some(k) = (0..nv - nb).find(|&k| !which[k]) {
                    which[k] = true;
                    let mut data = Data::new(&model);
                    data.tau.fill(f64::NAN);
                    let none = gyrostat_torques(&model, &mut data, &q, &v, &a, fext, &which);
                    assert!(none.unwrap().is_none(), "seed {seed}");
                    assert!(data.tau.iter().all(|t| t.is_nan()));
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }
}
