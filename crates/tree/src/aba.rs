//! The articulated-body algorithm (Featherstone §7.3): O(n) forward dynamics, the default.

use crate::axis::CoordAxis;
use crate::data::Data;
use crate::error::DynamicsError;
use crate::kinematics::{base_motion, check_len, update_transforms};
use crate::model::{BaseKind, Model};
use crate::spatial::{ArticulatedInertia, Force, Motion, Transform};
use nalgebra::DVector;

/// Pivots `Dᵢ` below this fraction of the articulated inertia's scale are singular.
pub const SINGULAR_PIVOT_RELATIVE: f64 = 1e-13;

/// Forward dynamics: the accelerations `q̈` produced by generalised forces `tau` and external
/// body forces `fext` (conventions of [`crate::rnea()`]), into `data.ddq`.
///
/// A free base's accelerations are the body-frame derivatives of `[ω; v]`.
///
/// Balanced axisymmetric rotors ([`crate::Gyrostat`], e.g. reaction wheels) are not processed
/// as bodies but as gyrostat terms of their carriers (same accelerations to round-off, a third
/// less work for a bus with three wheels); their `data.xup`, `data.v`, `data.a` are then left
/// as they were. [`Model::without_gyrostats`] gives the plain tree form. Fails with
/// [`DynamicsError::SingularHinge`] where a hinge's articulated inertia vanishes (gimbal lock
/// of massless links).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, aba, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 4.0, Mat3::from_diagonal(&Vec3::new(1.0, 2.0, 3.0))))
///     .build()?;
/// let mut data = Data::new(&model);
/// let tau = [0.0, 0.0, 6.0, 8.0, 0.0, 0.0]; // a torque about z and a force along x
/// let ddq = aba(&model, &mut data, &model.neutral(), &[0.0; 6], &tau, None)?;
/// assert!((ddq[2] - 2.0).abs() < 1e-12 && (ddq[3] - 2.0).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn aba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    if model.gyrostats.is_empty() {
        articulated::<false>(model, data, q, v, tau, fext, None, false)
    } else {
        articulated::<true>(model, data, q, v, tau, fext, None, false)
    }
}

/// Hybrid dynamics (Featherstone §9.2) with locked hinges: as [`aba`], except that a hinge
/// whose entry in `locked` (one per hinge, in the order of addition) is `true` has zero
/// acceleration and passes its child's inertia rigidly to its parent; its `τ` is ignored.
/// This is how a latched hinge stop is simulated without rebuilding the model. O(n).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, aba_hybrid, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 4.0, Mat3::identity()))
///     .body(Body::new("arm", 1.0, Mat3::identity()).with_com(Vec3::x()))
///     .hinge(Hinge::revolute("h", "bus", "arm", Vec3::z()))
///     .build()?;
/// let mut data = Data::new(&model);
/// let tau = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 5.0]; // the hinge torque is ignored when locked
/// let ddq = aba_hybrid(&model, &mut data, &model.neutral(), &[0.0; 7], &tau, None, &[true])?;
/// assert_eq!(ddq[6], 0.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn aba_hybrid<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: &[bool],
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_len("locked", locked.len(), model.n_hinges())?;
    articulated::<false>(model, data, q, v, tau, fext, Some(locked), false)
}

/// As [`aba`], reusing the hinge transforms in `data.xup`: **`data.xup` must hold the
/// transforms of this `q`**, as [`crate::forward_kinematics`] leaves them (Pinocchio's
/// convention for algorithms that follow kinematics). The caller that has just run
/// kinematics for the effects saves ABA one `sin_cos` and one transform per hinge; the
/// result is bit for bit that of [`aba`]. Stale transforms give wrong accelerations
/// silently: call [`aba`] when unsure.
///
/// ```
/// use satsim_tree::{aba, aba_with_kinematics, forward_kinematics, samples::chain, BaseKind, Data};
/// let model = chain(4, BaseKind::Free);
/// let mut data = Data::new(&model);
/// let mut q = model.neutral();
/// q[7] = 0.3;
/// let (v, tau) = (vec![0.1; model.nv()], vec![0.2; model.nv()]);
/// let plain = aba(&model, &mut data, &q, &v, &tau, None)?.clone();
/// forward_kinematics(&model, &mut data, &q, &v)?;
/// assert_eq!(aba_with_kinematics(&model, &mut data, &q, &v, &tau, None)?, &plain);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn aba_with_kinematics<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    if model.gyrostats.is_empty() {
        articulated::<false>(model, data, q, v, tau, fext, None, true)
    } else {
        articulated::<true>(model, data, q, v, tau, fext, None, true)
    }
}

/// As [`aba_hybrid`], reusing the hinge transforms in `data.xup`, which must hold those of
/// this `q` (see [`aba_with_kinematics`]).
pub fn aba_hybrid_with_kinematics<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: &[bool],
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_len("locked", locked.len(), model.n_hinges())?;
    articulated::<false>(model, data, q, v, tau, fext, Some(locked), true)
}

/// ABA proper; `GYRO`: the gyrostat form (a separate instance, so that the plain form has no
/// branches for it); `xup_ready`: `data.xup` already holds this `q`'s transforms.
#[allow(clippy::too_many_arguments)]
fn articulated<'d, const GYRO: bool>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: Option<&[bool]>,
    xup_ready: bool,
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_len("v", v.len(), model.nv())?;
    check_len("tau", tau.len(), model.nv())?;
    if let Some(f) = fext {
        check_len("fext", f.len(), model.n_bodies())?;
    }
    // Gyrostat form (plain ABA only; hybrid dynamics keeps every rotor a body so that a
    // rotor can be locked): balanced rotors ride on their parents, see `Gyrostat`.
    let gyro = GYRO;
    let n = model.n_bodies();
    if xup_ready {
        // The caller's forward kinematics left `data.xup` at this `q` (`aba_with_kinematics`).
        check_len("q", q.len(), model.nq())?;
    } else if gyro {
        check_len("q", q.len(), model.nq())?;
        for i in 1..n {
            if !model.is_gyrostat[i] {
                data.xup[i] = model.xup(i, q);
            }
        }
    } else {
        update_transforms(model, data, q)?;
    }
    // Pass 1, outward: velocities, velocity-product accelerations, rigid inertias, bias forces.
    data.v[0] = base_motion(model, v);
    data.c[0] = Motion::zero();
    for i in 0..n {
        if gyro && model.is_gyrostat[i] {
            continue;
        }
        if let Some(joint) = &model.joints[i] {
            let p = model.parent[i].expect("parent");
            let vj = joint.s * v[joint.dof];
            data.v[i] = apply_motion(&model.coord_axis[i], &data.xup[i], &data.v[p]) + vj;
            data.c[i] = data.v[i].cross_motion(&vj);
        }
        let vi = data.v[i];
        let inertia = if gyro {
            &model.carrier_inertia[i]
        } else {
            &model.bodies[i].inertia
        };
        // IAᵢ starts from the rigid inertia (`start` below), written by the first child.
        data.ia_started[i] = false;
        data.pa[i] = vi.cross_force(&inertia.mul_motion(&vi));
        if let Some(f) = fext {
            data.pa[i] -= f[i];
        }
    }
    if gyro {
        // Each rotor adds to its carrier's bias the gyroscopic couple of its spin momentum,
        // ω × (J Ω a), and the reaction a τ of its axial torque (the carrier's articulated
        // inertia already lacks J a aᵀ: the rotor is free about its axis).
        for g in &model.gyrostats {
            let joint = model.joints[g.body].as_ref().expect("joint");
            let mut tau_axial = tau[joint.dof];
            if let Some(f) = fext {
                // An external wrench on the rotor: its axial moment drives the spin, the
                // rest acts on the carrier through the bearing.
                let fr = f[g.body];
                tau_axial += joint.s.dot(&fr);
                let x = model.xup(g.body, q);
                data.pa[g.parent] -= x.inv_apply_force(&fr);
            }
            let w = data.v[g.parent].ang;
            let spin = w.cross(&g.axis) * (g.axial * v[joint.dof]) + g.axis * tau_axial;
            data.pa[g.parent].ang += spin;
            data.u[g.body] = tau_axial;
            data.d[g.body] = g.axial;
        }
    }
    // Pass 2, inward: articulated inertias and bias forces.
    let start = if gyro {
        &model.carrier_ia
    } else {
        &model.rigid_ia
    };
    for i in (1..n).rev() {
        if gyro && model.is_gyrostat[i] {
            continue;
        }
        let joint = model.joints[i].as_ref().expect("joint");
        let p = model.parent[i].expect("parent");
        let x = &data.xup[i];
        let axis = &model.coord_axis[i];
        // λ(i) < i: the child's inertia and the parent's, borrowed together, so that the
        // projection and the accumulation happen in place (no 216-byte copies).
        let (head, tail) = data.ia.split_at_mut(i);
        let (ia_i, ia_parent) = (&mut tail[0], &mut head[p]);
        // A leaf (no child started it) reads its start in place of a copy.
        let started = data.ia_started[i];
        let ia: &ArticulatedInertia = if started { ia_i } else { &start[i] };
        let parent_start = (!data.ia_started[p]).then(|| &start[p]);
        data.ia_started[p] = true;
        if locked.is_some_and(|l| l[joint.hinge]) {
            // Known (zero) acceleration: the child rides rigidly on its parent.
            let pa = data.pa[i] + ia.mul_motion(&data.c[i]);
            add_inv_transform(axis, ia, x, ia_parent, parent_start);
            data.pa[p] += inv_apply_force(axis, x, &pa);
            continue;
        }
        let (u_col, d) = match axis {
            Some(a) => {
                let u_col = a.mul_subspace(ia, &joint.s.lin);
                (u_col, a.dot_subspace(&joint.s.lin, &u_col))
            }
            None => {
                let u_col = ia.mul_motion(&joint.s);
                (u_col, joint.s.dot(&u_col))
            }
        };
        let d = d + joint.armature;
        let scale = ia.a.trace() + ia.c.trace() * joint.child_at.norm_squared();
        // Written so that a NaN pivot counts as singular too.
        let regular = d.is_finite() && d > SINGULAR_PIVOT_RELATIVE * scale;
        if !regular {
            return Err(DynamicsError::SingularHinge {
                hinge: model.hinge_names[joint.hinge].clone(),
                through: massless_hinges_below(model, i),
                pivot: d,
                relative: if scale > 0.0 { d / scale } else { 0.0 },
            });
        }
        let u = tau[joint.dof]
            - match axis {
                Some(a) => a.dot_subspace(&joint.s.lin, &data.pa[i]),
                None => joint.s.dot(&data.pa[i]),
            };
        data.u_col[i] = u_col;
        data.d[i] = d;
        data.u[i] = u;
        let inv_d = 1.0 / d;
        // IAᵢ becomes its projection IAᵢ − Uᵢ Dᵢ⁻¹ Uᵢᵀ, the inertia the parent sees.
        if started {
            ia_i.sub_outer(&u_col, inv_d);
        } else {
            ia_i.set_sub_outer(&start[i], &u_col, inv_d);
        }
        let ia = &*ia_i;
        let pa = data.pa[i] + ia.mul_motion(&data.c[i]) + u_col * (u * inv_d);
        add_inv_transform(axis, ia, x, ia_parent, parent_start);
        data.pa[p] += inv_apply_force(axis, x, &pa);
    }
    if !data.ia_started[0] {
        data.ia[0] = start[0]; // a root without hinged children (other than rotors)
    }
    // Pass 3, outward: accelerations.
    data.a[0] = match model.base {
        BaseKind::Free => {
            // a₀ = IA₀⁻¹ (τ₀ − pA₀)
            let a0 = data.ia[0]
                .solve(&(Force::from_slice(&tau[..6]) - data.pa[0]))
                .ok_or(DynamicsError::SingularBase)?;
            for (r, x) in a0.to_array().into_iter().enumerate() {
                data.ddq[r] = x;
            }
            a0
        }
        BaseKind::Fixed => Motion::zero(),
    };
    for i in 1..n {
        let joint = model.joints[i].as_ref().expect("joint");
        let p = model.parent[i].expect("parent");
        if gyro && model.is_gyrostat[i] {
            // Ω̇ = τ / J − a · α_parent (the rotor's axial equation; a in parent coordinates).
            data.ddq[joint.dof] = data.u[i] / data.d[i] - joint.axis.dot(&data.a[p].ang);
            continue;
        }
        let a = apply_motion(&model.coord_axis[i], &data.xup[i], &data.a[p]) + data.c[i];
        if locked.is_some_and(|l| l[joint.hinge]) {
            data.ddq[joint.dof] = 0.0;
            data.a[i] = a;
            continue;
        }
        let qdd =
            (data.u[i] - data.u_col[i].ang.dot(&a.ang) - data.u_col[i].lin.dot(&a.lin)) / data.d[i];
        data.ddq[joint.dof] = qdd;
        data.a[i] = a + joint.s * qdd;
    }
    Ok(&data.ddq)
}

/// `X m`, by the coordinate-axis fast path where the hinge has one.
#[inline]
fn apply_motion(axis: &Option<CoordAxis>, x: &Transform, m: &Motion) -> Motion {
    match axis {
        Some(a) => a.apply_motion(x, m),
        None => x.apply_motion(m),
    }
}

/// `Xᵀ f`, by the coordinate-axis fast path where the hinge has one.
#[inline]
fn inv_apply_force(axis: &Option<CoordAxis>, x: &Transform, f: &Force) -> Force {
    match axis {
        Some(a) => a.inv_apply_force(x, f),
        None => x.inv_apply_force(f),
    }
}

/// `out += Xᵀ IA X` (`out = start + Xᵀ IA X` with `Some(start)`), by the coordinate-axis
/// fast path where the hinge has one.
#[inline]
fn add_inv_transform(
    axis: &Option<CoordAxis>,
    ia: &ArticulatedInertia,
    x: &Transform,
    out: &mut ArticulatedInertia,
    start: Option<&ArticulatedInertia>,
) {
    match axis {
        Some(a) => a.add_inv_transform(ia, x, out, start),
        None => ia.add_inv_transform_to(x, out, start),
    }
}

/// The hinges reached from body `i` downwards through massless bodies: the other axes of a
/// multi-axis hinge made of massless links (named in a singular-configuration error).
fn massless_hinges_below(model: &Model, i: usize) -> Vec<String> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Body, Hinge, ModelBuilder};
    use crate::samples::{SplitMix, random_tree_with_rotors};
    use crate::spatial::Vec3;
    use nalgebra::Quaternion;

    /// `model` with every hinge axis snapped to the nearest signed coordinate axis and no
    /// fixed rotations, plus `rotors` balanced rotors about coordinate axes (gyrostats): every
    /// hinge takes the coordinate-axis path.
    fn snapped(model: &Model, rotors: usize, rng: &mut SplitMix) -> Model {
        let mut b = ModelBuilder::new(model.base);
        for body in &model.bodies {
            b.push_body(
                Body::new(body.name.clone(), body.mass, body.inertia_com).with_com(body.com),
            );
        }
        for (k, name) in model.hinge_names.iter().enumerate() {
            let i = model.hinge_body[k];
            let joint = model.joints[i].as_ref().unwrap();
            let m = joint.axis.iamax();
            let mut axis = Vec3::zeros();
            axis[m] = joint.axis[m].signum();
            let p = model.parent[i].unwrap();
            b.push_hinge(
                Hinge::revolute(
                    name.clone(),
                    model.bodies[p].name.clone(),
                    model.bodies[i].name.clone(),
                    axis,
                )
                .at(joint.at)
                .child_at(joint.child_at)
                .rotation(Quaternion::identity())
                .armature(joint.armature),
            );
        }
        for r in 0..rotors {
            let k = r % 3;
            let (j, it) = (rng.range(0.05, 0.2), rng.range(0.1, 0.2));
            let mut diag = Vec3::repeat(it);
            diag[k] = j;
            let mass = if r % 2 == 0 { rng.range(0.5, 3.0) } else { 0.0 };
            let name = format!("axial_rotor{r}");
            let p = (rng.next_f64() * model.n_bodies() as f64) as usize;
            let e = Vec3::ith(k, if r % 2 == 0 { 1.0 } else { -1.0 });
            b.push_body(
                Body::new(name.clone(), mass, nalgebra::Matrix3::from_diagonal(&diag))
                    .with_com(e * rng.range(-0.3, 0.3)),
            );
            b.push_hinge(
                Hinge::revolute(name.clone(), model.bodies[p].name.clone(), name, e)
                    .at(rng.vec3(0.5))
                    .child_at(e * rng.range(-0.3, 0.3)),
            );
        }
        b.build().unwrap()
    }

    fn rel(a: &nalgebra::DVector<f64>, b: &nalgebra::DVector<f64>) -> f64 {
        (a - b).amax() / a.amax().max(b.amax()).max(1.0)
    }

    #[test]
    fn coordinate_axis_path_equals_the_general_path() {
        let (mut worst, mut compared): (f64, usize) = (0.0, 0);
        for seed in 0..200u64 {
            let mut rng = SplitMix(seed ^ 0x51ed);
            let base = if seed % 3 == 0 {
                BaseKind::Fixed
            } else {
                BaseKind::Free
            };
            let n = 2 + (seed % 20) as usize;
            let rotors = (seed % 3) as usize;
            let tree = random_tree_with_rotors(n, base, seed % 2 == 0, rotors, seed);
            let fast = snapped(&tree, rotors, &mut rng);
            assert!(fast.coord_axis.iter().skip(1).all(Option::is_some));
            assert!(fast.gyrostats.len() >= rotors);
            // Some snapped axes are negative, some hinge points off the child origin.
            let mut general = fast.clone();
            general.coord_axis.iter_mut().for_each(|a| *a = None);
            let mut q = fast.neutral();
            let nb = fast.base_nq();
            if base == BaseKind::Free {
                let a = Quaternion::new(0.3, -0.5, rng.range(-1.0, 1.0), 0.2).normalize();
                q[..4].copy_from_slice(&[a.w, a.i, a.j, a.k]);
            }
            for x in &mut q[nb..] {
                *x = rng.range(-3.0, 3.0);
            }
            let v: Vec<f64> = (0..fast.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
            let tau: Vec<f64> = (0..fast.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
            let fext: Vec<Force> = (0..fast.n_bodies())
                .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
                .collect();
            let locked: Vec<bool> = (0..fast.n_hinges()).map(|_| rng.next_f64() < 0.3).collect();
            let (mut df, mut dg) = (Data::new(&fast), Data::new(&general));
            let (Ok(a), Ok(b)) = (
                aba(&fast, &mut df, &q, &v, &tau, Some(&fext)).cloned(),
                aba(&general, &mut dg, &q, &v, &tau, Some(&fext)).cloned(),
            ) else {
                continue; // a singular snapped tree (parallel hinges through massless links)
            };
            compared += 1;
            worst = worst.max(rel(&a, &b));
            let (Ok(a), Ok(b)) = (
                aba_hybrid(&fast, &mut df, &q, &v, &tau, None, &locked).cloned(),
                aba_hybrid(&general, &mut dg, &q, &v, &tau, None, &locked).cloned(),
            ) else {
                continue;
            };
            worst = worst.max(rel(&a, &b));
            for i in 1..fast.n_bodies() {
                let (xf, xg) = (fast.xup(i, &q), general.xup(i, &q));
                assert!((xf.rot - xg.rot).amax() < 1e-15 && (xf.trans - xg.trans).amax() < 1e-14);
            }
        }
        assert!(compared > 150, "only {compared} regular trees");
        assert!(worst < 1e-12, "worst relative difference {worst:e}");
    }
}
