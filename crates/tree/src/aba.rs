//! The articulated-body algorithm (Featherstone §7.3): O(n) forward dynamics, the default
//! method of [`crate::ForwardDynamics`], the engine's entry, which calls these functions.
//!
//! This is the algorithm's page: [`aba`] (plain), [`aba_hybrid`] (locked hinges) and their
//! forms reusing current transforms, [`aba_with_kinematics`] and
//! [`aba_hybrid_with_kinematics`]; a caller describes its call by a
//! [`crate::forward_dynamics::Input`] and lets [`crate::ForwardDynamics`] pick the form.

use crate::axis::CoordAxis;
use crate::data::{ChainWork, Data};
use crate::error::DynamicsError;
use crate::kernel_parts::{add_linear_inv_transform, massless_hinges_below, offset_scale};
use crate::kinematics::{base_motion, check_len, update_transforms};
use crate::model::{BaseKind, Chain, ChainPart, Model};
use crate::spatial::{ArticulatedInertia, Force, Mat3, Motion, Transform, Vec3, cross_columns};
use nalgebra::DVector;

// The pivot test's bound, kept with the rest of the pivot test in `kernel_parts.rs`
// (which the kernels outside this crate read).
pub use crate::kernel_parts::SINGULAR_PIVOT_RELATIVE;

/// Forward dynamics: the accelerations `q̈` produced by generalised forces `tau` and external
/// body forces `fext` (conventions of [`crate::rnea()`]), into `data.ddq`.
///
/// A free base's accelerations are the body-frame derivatives of `[ω; v]`.
///
/// Balanced axisymmetric rotors ([`crate::Gyrostat`], e.g. reaction wheels) are not processed
/// as bodies but as gyrostat terms of their carriers (same accelerations to round-off, a third
/// less work for a bus with three wheels); their `data.xup`, `data.v`, `data.a` are then left
/// as they were. [`Model::without_gyrostats`] gives the plain tree form. Likewise a chain of
/// hinges through massless zero-length links ([`crate::Chain`], e.g. a 3-DOF gimbal) is
/// processed as one multi-axis joint at its tip (same accelerations to round-off, every body's
/// `data.a` and every hinge's `data.ddq` written; [`Model::without_chains`] gives the plain
/// form). Fails with
/// [`DynamicsError::SingularHinge`] where a hinge's articulated inertia vanishes (gimbal lock
/// of massless links).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, aba::aba, spatial::{Mat3, Vec3}};
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
    plain_or_chains(Instance::of(model), model, data, q, v, tau, fext, false)
}

/// Hybrid dynamics (Featherstone §9.2) with locked hinges: as [`aba`], except that a hinge
/// whose entry in `locked` (one per hinge, in the order of addition) is `true` has zero
/// acceleration and passes its child's inertia rigidly to its parent; its `τ` is ignored.
/// This is how a latched hinge stop is simulated without rebuilding the model. O(n).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, aba::aba_hybrid, spatial::{Mat3, Vec3}};
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
    hybrid(model, data, q, v, tau, fext, locked, false)
}

/// As [`aba`], reusing the hinge transforms in `data.xup`: **`data.xup` must hold the
/// transforms of this `q`**, as [`crate::forward_kinematics`] leaves them (Pinocchio's
/// convention for algorithms that follow kinematics). The caller that has just run
/// kinematics for the effects saves ABA one `sin_cos` and one transform per hinge; the
/// result is bit for bit that of [`aba`]. Stale transforms give wrong accelerations
/// silently: call [`aba`] when unsure.
///
/// ```
/// use satsim_tree::aba::{aba, aba_with_kinematics};
/// use satsim_tree::{forward_kinematics, samples::chain, BaseKind, Data};
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
    plain_or_chains(Instance::of(model), model, data, q, v, tau, fext, true)
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
    hybrid(model, data, q, v, tau, fext, locked, true)
}

/// ABA's instance for a model's forms: with or without the gyrostat terms of its
/// [`crate::Gyrostat`]s, with or without the multi-axis form of its [`Chain`]s (separate
/// monomorphic instances of the passes). [`aba`] picks it per call, [`crate::ForwardDynamics`]
/// once per model: the same instance for the same model, so bit for bit the same result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Instance {
    /// No gyrostats, no chains.
    Plain,
    /// Chains only.
    Chains,
    /// Gyrostats only.
    Gyro,
    /// Both.
    GyroChains,
}

impl Instance {
    /// The instance for `model`'s gyrostats and chains.
    pub(crate) fn of(model: &Model) -> Self {
        match (model.gyrostats.is_empty(), model.chains.is_empty()) {
            (true, true) => Self::Plain,
            (true, false) => Self::Chains,
            (false, true) => Self::Gyro,
            (false, false) => Self::GyroChains,
        }
    }
}

/// [`aba`] and [`aba_with_kinematics`] in `instance` (see [`Instance`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn plain_or_chains<'d>(
    instance: Instance,
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    xup_ready: bool,
) -> Result<&'d DVector<f64>, DynamicsError> {
    let x = xup_ready;
    match instance {
        Instance::Plain => articulated::<false, false>(model, data, q, v, tau, fext, None, x),
        Instance::Chains => articulated::<false, true>(model, data, q, v, tau, fext, None, x),
        Instance::Gyro => articulated::<true, false>(model, data, q, v, tau, fext, None, x),
        Instance::GyroChains => articulated::<true, true>(model, data, q, v, tau, fext, None, x),
    }
}

/// [`aba_hybrid`] and [`aba_hybrid_with_kinematics`]: the plain tree form (every rotor and
/// link a body, so that any hinge can be locked), `locked` checked.
#[allow(clippy::too_many_arguments)]
pub(crate) fn hybrid<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: &[bool],
    xup_ready: bool,
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_len("locked", locked.len(), model.n_hinges())?;
    articulated::<false, false>(model, data, q, v, tau, fext, Some(locked), xup_ready)
}

/// ABA proper; `GYRO`: the gyrostat form, `CHAINS`: the multi-axis form of [`crate::Chain`]s
/// (separate instances, so that the plain form has no branches for them); `xup_ready`:
/// `data.xup` already holds this `q`'s transforms.
#[allow(clippy::too_many_arguments)]
fn articulated<'d, const GYRO: bool, const CHAINS: bool>(
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
        if CHAINS {
            match model.chain_part[i] {
                ChainPart::Link => continue, // processed at its tip
                ChainPart::Tip(k) => {
                    let chain = &model.chains[k];
                    if chain.k == 3 {
                        chain_inward::<3>(model, data, chain, tau, fext.is_some(), start)?;
                    } else {
                        chain_inward::<2>(model, data, chain, tau, fext.is_some(), start)?;
                    }
                    continue;
                }
                ChainPart::None => {}
            }
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
        if CHAINS {
            match model.chain_part[i] {
                ChainPart::Link => continue, // processed at its tip
                ChainPart::Tip(k) => {
                    let chain = &model.chains[k];
                    if chain.k == 3 {
                        chain_outward::<3>(model, data, chain);
                    } else {
                        chain_outward::<2>(model, data, chain);
                    }
                    continue;
                }
                ChainPart::None => {}
            }
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
pub(crate) fn apply_motion(axis: &Option<CoordAxis>, x: &Transform, m: &Motion) -> Motion {
    match axis {
        Some(a) => a.apply_motion(x, m),
        None => x.apply_motion(m),
    }
}

/// `Xᵀ f`, by the coordinate-axis fast path where the hinge has one.
#[inline]
pub(crate) fn inv_apply_force(axis: &Option<CoordAxis>, x: &Transform, f: &Force) -> Force {
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

/// Pass 2 for a [`Chain`] of `K` hinges, at its tip `C` (body `order[0]`): the chain's hinges
/// as one multi-axis joint. In the frame at the common hinge point with `C`'s axes, its motion
/// subspace is `S = [E; 0]` (`E`: the hinge axes in `C`'s axes); with `IA_h`, `pA_h` the tip's
/// articulated inertia and bias there, `U = IA_h S`, `D = Sᵀ U + diag(armature)`,
/// `u = τ − Sᵀ pA_h` (less the massless links' own external forces), and the parent receives
/// `IA_h − U D⁻¹ Uᵀ` and `pA_h + IAᵃ c + U D⁻¹ u` through the composite transform. `D` is
/// factored `L Δ Lᵀ` eliminating the tip's hinge first and the outermost link's last: the
/// pivots `Δ` are then the tree form's `Dᵢ` (Schur complements), checked against the same
/// scales, so a singular chain fails at the same hinge with the same error. `loaded`: whether
/// external forces were given (the links' bias is zero otherwise).
fn chain_inward<const K: usize>(
    model: &Model,
    data: &mut Data,
    chain: &Chain,
    tau: &[f64],
    loaded: bool,
    start: &[ArticulatedInertia],
) -> Result<(), DynamicsError> {
    let (b, p) = (&chain.order, chain.parent);
    let tip = b[0];
    let r = chain.tip_at; // the hinge point in the tip's frame
    let ChainFrame { e, off, rot, c } = chain_frame::<K>(model, &data.xup, &data.c, chain);
    let mut u = [0.0; K];
    for t in 0..K {
        u[t] = tau[chain.dof[t]];
    }
    if loaded && (1..K).any(|t| data.pa[b[t]] != Force::zero()) {
        let (du, g) = links_bias::<K>(model, &data.xup, &data.pa, chain);
        for t in 1..K {
            u[t] += du[t];
        }
        data.pa[p] += g;
    }
    let (head, tail) = data.ia.split_at_mut(tip);
    let ia: &ArticulatedInertia = if data.ia_started[tip] {
        &tail[0]
    } else {
        &start[tip]
    };
    let ia_parent = &mut head[p];
    let parent_start = (!data.ia_started[p]).then(|| &start[p]);
    data.ia_started[p] = true;
    // The tip's inertia and bias at the hinge point (a translation by r):
    // B_h = B − [r]×C, A_h = A − [r]×Bᵀ + B_h [r]×.
    let (ah, bh) = to_point(ia, &r);
    let pa = data.pa[tip];
    let pa = Force::new(pa.ang - r.cross(&pa.lin), pa.lin);
    // D = L Δ Lᵀ, the tip's hinge first: w_t = U_t − Σ_{s<t} l_ts w_s (the columns of U L⁻ᵀ),
    // Δ_t = e_t · w_t + armature, and u ← L⁻¹ u.
    let mut w = [Force::zero(); K];
    let mut piv = [0.0; K];
    let mut inv = [0.0; 3]; // 1 / Δ: one division per hinge
    let mut l = [0.0; 3]; // l₁₀, l₂₀, l₂₁
    let mut tr = (ah.trace(), ia.c.trace()); // tr A, tr C of the projected inertia at the point
    for t in 0..K {
        let mut wt = match (t, &model.coord_axis[tip]) {
            (0, Some(a)) => Force::new(a.times_axis(&ah), a.tr_times_axis(&bh)),
            _ => Force::new(ah * e[t], bh.tr_mul(&e[t])),
        };
        u[t] -= e[t].dot(&pa.ang);
        for s in 0..t {
            let lts = e[t].dot(&w[s].ang) * inv[s];
            l[t + s - 1] = lts;
            wt -= w[s] * lts;
            u[t] -= lts * u[s];
        }
        let d = e[t].dot(&wt.ang) + chain.armature[t];
        // The tree form's scale: the body's articulated inertia about its own origin.
        let scale = if t == 0 {
            ia.a.trace() + ia.c.trace() * r.norm_squared()
        } else if chain.offset_links && off[t] != Vec3::zeros() {
            offset_scale(&off[t], &bh, &ia.c, &w[..t], &piv[..t], tr.0, tr.1)
        } else {
            tr.0
        };
        let regular = d.is_finite() && d > SINGULAR_PIVOT_RELATIVE * scale;
        if !regular {
            return Err(singular(model, b[t], d, scale));
        }
        let inv_d = 1.0 / d;
        if t + 1 < K {
            tr.0 -= wt.ang.norm_squared() * inv_d;
            tr.1 -= wt.lin.norm_squared() * inv_d;
        }
        w[t] = wt;
        piv[t] = d;
        inv[t] = inv_d;
    }
    // The projected inertia IAᵃ = IA_h − Σ w_t w_tᵀ / Δ_t and the bias the parent receives,
    // pA_h + IAᵃ c + Σ w_t (L⁻¹u)_t / Δ_t, moved by one transform (parent to hinge point).
    let x = Transform::new(rot, chain.point);
    let mut pa = pa;
    if K == 3 && chain.spherical {
        // Three independent axes, no armature: IAᵃ = [0 0; 0 C − Bᵀ A⁻¹ B] exactly.
        let mut cc = ia.c;
        for t in 0..K {
            cc -= (w[t].lin * inv[t]) * w[t].lin.transpose();
        }
        pa.lin += cc * c.lin;
        add_linear_inv_transform(&cc, &x, ia_parent, parent_start);
    } else {
        let iaa = ArticulatedInertia {
            a: ah,
            b: bh,
            c: ia.c,
        };
        pa += project(iaa, &w, &inv, &c, &x, ia_parent, parent_start);
    }
    for t in 0..K {
        pa += w[t] * (u[t] * inv[t]);
        data.u_col[b[t]] = w[t];
        data.d[b[t]] = piv[t];
        data.u[b[t]] = u[t];
    }
    data.pa[p] += x.inv_apply_force(&pa);
    data.chain[tip] = ChainWork { x, c, l, inv };
    Ok(())
}

/// A chain's geometry at its hinge point, in the tip's axes: what [`chain_frame`] returns.
pub(crate) struct ChainFrame<const K: usize> {
    /// The hinge axes, elimination order (the tip's hinge first).
    pub e: [Vec3; K],
    /// Link `order[t]`'s origin from the hinge point (zero unless the chain has offset
    /// links), for its pivot scale.
    pub off: [Vec3; K],
    /// The rotation from the chain parent's axes to the tip's.
    pub rot: Mat3,
    /// The chain's velocity-product acceleration at the hinge point:
    /// `c = X_C (X_L2 c_L1 + c_L2) + c_C`, moved to the point.
    pub c: Motion,
}

/// The geometry of `chain` from the bodies' `Xup` and velocity-product terms `c` (the rigid
/// ABA's and the flexible one's first passes both leave them).
#[inline(always)]
pub(crate) fn chain_frame<const K: usize>(
    model: &Model,
    xup: &[Transform],
    c: &[Motion],
    chain: &Chain,
) -> ChainFrame<K> {
    let b = &chain.order;
    let mut e = [Vec3::zeros(); K];
    let mut off = [Vec3::zeros(); K];
    e[0] = chain.axis[0];
    let mut rot = xup[b[0]].rot;
    for t in 1..K {
        let i = b[t];
        if chain.offset_links {
            off[t] = -(rot * chain.link_at[t]);
        }
        // Links about coordinate axes: a signed column, and two columns mixed.
        (e[t], rot) = match &model.coord_axis[i] {
            Some(a) => (a.times_axis(&rot), a.post_rotate(&rot, &xup[i].rot)),
            None => (rot * chain.axis[t], rot * xup[i].rot),
        };
    }
    let mut cc = c[b[K - 1]];
    for t in (0..K - 1).rev() {
        let i = b[t];
        cc = apply_motion(&model.coord_axis[i], &xup[i], &cc) + c[i];
    }
    let r = chain.tip_at;
    let c = Motion::new(cc.ang, cc.lin - r.cross(&cc.ang));
    ChainFrame { e, off, rot, c }
}

/// The links' own bias `pa` (external forces only: they have no inertia) reaches the chain's
/// parent rigidly and loads the hinges between them and the parent: returns what to add to
/// each hinge's `u` (elimination order; entry 0, the tip's, is zero) and to the parent's
/// bias, as in the tree form. Out of line: only calls with external forces on links come
/// here.
#[inline(never)]
pub(crate) fn links_bias<const K: usize>(
    model: &Model,
    xup: &[Transform],
    pa: &[Force],
    chain: &Chain,
) -> ([f64; K], Force) {
    let b = &chain.order;
    let mut du = [0.0; K];
    let mut g = Force::zero();
    for t in 1..K {
        if t > 1 {
            let i = b[t - 1];
            g = inv_apply_force(&model.coord_axis[i], &xup[i], &g);
        }
        g += pa[b[t]];
        let j = model.joints[b[t]].as_ref().expect("joint");
        du[t] = -j.s.dot(&g);
    }
    let i = b[K - 1];
    (du, inv_apply_force(&model.coord_axis[i], &xup[i], &g))
}

/// The singular-hinge error of body `i`'s hinge (the tree form's, see [`aba`]).
#[cold]
#[inline(never)]
fn singular(model: &Model, i: usize, d: f64, scale: f64) -> DynamicsError {
    let j = model.joints[i].as_ref().expect("joint");
    DynamicsError::SingularHinge {
        hinge: model.hinge_names[j.hinge].clone(),
        through: massless_hinges_below(model, i),
        pivot: d,
        relative: if scale > 0.0 { d / scale } else { 0.0 },
    }
}

/// The general projection of a chain at its hinge point: `IAᵃ = IA_h − Σ w wᵀ / Δ` (`inv`:
/// the `1 / Δ`) moved to the parent by `x` into `out` (`start` as in
/// `add_inv_transform_to`); returns `IAᵃ c`.
#[inline(never)]
fn project<const K: usize>(
    mut ia: ArticulatedInertia,
    w: &[Force; K],
    inv: &[f64; 3],
    c: &Motion,
    x: &Transform,
    out: &mut ArticulatedInertia,
    start: Option<&ArticulatedInertia>,
) -> Force {
    for t in 0..K {
        ia.sub_outer(&w[t], inv[t]);
    }
    ia.add_inv_transform_to(x, out, start);
    ia.mul_motion(c)
}

/// The rotational and cross blocks of `ia` (about a body's origin) about the point `r` of the
/// body's frame, same axes: `B_h = B − [r]×C`, `A_h = A − [r]×Bᵀ + B_h [r]×` (`C` is
/// unchanged).
#[inline(never)]
pub(crate) fn to_point(ia: &ArticulatedInertia, r: &Vec3) -> (Mat3, Mat3) {
    let bh = ia.b - cross_columns(r, &ia.c);
    let ah =
        ia.a - cross_columns(r, &ia.b.transpose()) - cross_columns(r, &bh.transpose()).transpose();
    (ah, bh)
}

/// Pass 3 for a [`Chain`] of `K` hinges, at its tip: `q̈ = D⁻¹ (u − Uᵀ a′)` with `a′` the
/// tip's acceleration at the hinge point before the hinges move
/// (`L⁻ᵀ Δ⁻¹ (L⁻¹u − Wᵀ a′)`, outermost hinge first), then the links' and the tip's
/// accelerations as in the tree form.
fn chain_outward<const K: usize>(model: &Model, data: &mut Data, chain: &Chain) {
    let (b, p) = (&chain.order, chain.parent);
    let work = &data.chain[b[0]];
    let a = work.x.apply_motion(&data.a[p]) + work.c;
    let mut qdd = [0.0; K];
    for t in 0..K {
        let i = b[t];
        qdd[t] = (data.u[i] - a.dot(&data.u_col[i])) * work.inv[t];
    }
    let l = &work.l;
    if K == 3 {
        qdd[1] -= l[2] * qdd[K - 1];
        qdd[0] -= l[1] * qdd[K - 1];
    }
    qdd[0] -= l[0] * qdd[1];
    let mut parent = p;
    for t in (0..K).rev() {
        let i = b[t];
        data.ddq[chain.dof[t]] = qdd[t];
        let s = Motion::new(
            chain.axis[t],
            model.joints[i].as_ref().expect("joint").s.lin,
        );
        data.a[i] = apply_motion(&model.coord_axis[i], &data.xup[i], &data.a[parent])
            + data.c[i]
            + s * qdd[t];
        parent = i;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Body, Hinge, ModelBuilder};
    use crate::samples::{SplitMix, random_q, random_tree_with_rotors};
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
            // CRBA's fast path too (composite inertias, the columns' forces).
            let mf = crate::crba(&fast, &mut df, &q).unwrap().clone();
            let mg = crate::crba(&general, &mut dg, &q).unwrap();
            worst = worst.max((&mf - mg).amax() / mg.amax());
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

    /// `model` rebuilt with, at random, armature on some hinges (`armature`) and the origins of
    /// some massless links moved off their hinge point (`offset`: the link's `child_at` and its
    /// child's `at` the same vector, so the link stays zero-length).
    fn chain_variant(model: &Model, rng: &mut SplitMix, armature: bool, offset: bool) -> Model {
        let mut b = model.to_builder();
        let names: Vec<String> = model.bodies.iter().map(|x| x.name.clone()).collect();
        for (body, name) in model.bodies.iter().zip(&names).skip(1) {
            if !(offset && body.mass == 0.0 && rng.next_f64() < 0.6) {
                continue;
            }
            let o = rng.vec3(0.5);
            for h in b.hinges_mut() {
                if h.child == *name {
                    h.child_at = o;
                }
                if h.parent == *name {
                    h.at = o;
                }
            }
        }
        if armature {
            for h in b.hinges_mut() {
                if rng.next_f64() < 0.5 {
                    h.armature = rng.range(0.0, 0.5);
                }
            }
        }
        b.build().unwrap()
    }

    /// A random state: attitude, position, angles, rates, torques and external forces on
    /// every body (links included).
    fn random_state(
        model: &Model,
        rng: &mut SplitMix,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Force>) {
        let q = random_q(model, rng, 3.0);
        let v = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
        let tau = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
        let fext = (0..model.n_bodies())
            .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
            .collect();
        (q, v, tau, fext)
    }

    /// The multi-axis form of massless-link chains against the tree form (every link a body):
    /// random trees with chains of 2 and 3 hinges, general and coordinate axes, with and
    /// without armature, link origins on and off the hinge point, gyrostat rotors, external
    /// forces on every body, free and fixed roots, tips with children. The accelerations of
    /// every body must agree too.
    #[test]
    fn chain_form_equals_the_tree_form() {
        let (mut worst, mut compared, mut refused) = (0.0f64, 0usize, 0usize);
        let mut seen = [0usize; 4]; // chains of k = 2, k = 3, spherical ones, offset links
        let mut tips_with_children = 0;
        let mut rotor_on_tip = 0;
        for seed in 0..1500u64 {
            let mut rng = SplitMix(seed ^ 0xc4a1);
            let base = if seed % 3 == 0 {
                BaseKind::Fixed
            } else {
                BaseKind::Free
            };
            let n = 3 + (seed % 18) as usize;
            let rotors = (seed % 3) as usize;
            let tree = random_tree_with_rotors(n, base, true, rotors, seed);
            let tree = if seed % 4 == 1 {
                snapped(&tree, rotors, &mut rng)
            } else {
                tree
            };
            let model = chain_variant(&tree, &mut rng, seed % 5 < 2, seed % 7 < 3);
            for c in &model.chains {
                seen[c.k - 2] += 1;
                seen[2] += c.spherical as usize;
                seen[3] += c.offset_links as usize;
                tips_with_children += model.children(c.tip()).count().min(1);
                rotor_on_tip += model.gyrostats.iter().any(|g| g.parent == c.tip()) as usize;
            }
            let plain = model.without_chains();
            assert!(plain.chains.is_empty());
            let (q, v, tau, fext) = random_state(&model, &mut rng);
            let (mut dc, mut dp) = (Data::new(&model), Data::new(&plain));
            for f in [None, Some(fext.as_slice())] {
                let a = aba(&model, &mut dc, &q, &v, &tau, f).cloned();
                let b = aba(&plain, &mut dp, &q, &v, &tau, f).cloned();
                let (a, b) = match (a, b) {
                    (Ok(a), Ok(b)) => (a, b),
                    (Err(x), Err(y)) => {
                        // Both refuse, naming the same hinges (the pivots agree to round-off).
                        let names = |e: DynamicsError| match e {
                            DynamicsError::SingularHinge { hinge, through, .. } => (hinge, through),
                            other => panic!("seed {seed}: {other}"),
                        };
                        assert_eq!(names(x), names(y), "seed {seed}");
                        refused += 1;
                        continue;
                    }
                    (a, b) => panic!("seed {seed}: chain form {a:?}, tree form {b:?}"),
                };
                compared += 1;
                let e = rel(&a, &b);
                assert!(e < 1e-12, "seed {seed}: chain vs tree form {e:e}");
                worst = worst.max(e);
                for i in 0..model.n_bodies() {
                    if model.is_gyrostat[i] {
                        continue;
                    }
                    let (x, y) = (dc.a[i].to_array(), dp.a[i].to_array());
                    let scale = b.amax().max(1.0) * 10.0;
                    for (x, y) in x.iter().zip(y) {
                        assert!((x - y).abs() < 1e-12 * scale, "seed {seed}: body {i} a");
                    }
                }
            }
        }
        eprintln!(
            "chain vs tree: {compared} compared, {refused} refused, worst {worst:e}; chains \
             k=2 {}, k=3 {}, spherical {}, offset {}, tips with children {tips_with_children}, \
             with rotors {rotor_on_tip}",
            seen[0], seen[1], seen[2], seen[3]
        );
        assert!(compared > 2500, "only {compared} regular cases");
        assert!(seen.iter().all(|&s| s > 30), "chains seen {seen:?}");
        assert!(tips_with_children > 40 && rotor_on_tip > 40);
    }

    /// The singular-pivot scale of a chain's link with its origin off the hinge point is the
    /// tree form's: `tr A + |d|² tr C` of the projected inertia moved to the link's origin.
    #[test]
    fn offset_scale_is_the_tree_forms_scale() {
        let mut rng = SplitMix(3);
        for _ in 0..50 {
            let m = rng.range(0.5, 5.0);
            let rigid = crate::spatial::RigidInertia::from_com(
                m,
                rng.vec3(0.5),
                crate::samples::random_inertia(&mut rng, m),
            );
            let mut ia = ArticulatedInertia::from(rigid);
            let w: Vec<Force> = (0..2)
                .map(|_| Force::new(rng.vec3(0.3), rng.vec3(0.3)))
                .collect();
            let piv = [rng.range(1.0, 2.0), rng.range(1.0, 2.0)];
            let (bh, c) = (ia.b, ia.c);
            for (w, p) in w.iter().zip(piv) {
                ia.sub_outer(w, 1.0 / p);
            }
            let d = rng.vec3(0.8);
            // The projected inertia about the link's origin, which lies at d from the point.
            let at_origin = ia.inv_transform(&Transform::new(Mat3::identity(), -d));
            let tree = at_origin.a.trace() + at_origin.c.trace() * d.norm_squared();
            let ours = offset_scale(&d, &bh, &c, &w, &piv, ia.a.trace(), ia.c.trace());
            assert!((tree - ours).abs() < 1e-13 * tree.abs(), "{tree} vs {ours}");
        }
    }
}
