//! Forward dynamics of a tree with flexible bodies: the articulated-body algorithm with each
//! body's hinge and modes eliminated together as one `(1 + m)`-DOF joint. O(n) in bodies.

use super::chain;
use super::data::{FlexData, check_state, velocities_on};
use super::dense;
use super::model::FlexModel;
use crate::aba::{apply_motion, inv_apply_force};
use crate::axis::CoordAxis;
use crate::error::DynamicsError;
use crate::kinematics::check_len;
use crate::model::BaseKind;
use crate::spatial::{ArticulatedInertia, Force, Motion, Transform};
use nalgebra::DVector;

/// The generalised accelerations `M⁻¹ (τ − b)` into `data.ddq` (conventions of
/// [`super::rnea()`]), in O(n).
///
/// A flexible body's velocity is extended to `[vᵢ; η̇ᵢ]` with the inertia
/// `[[I, P], [Pᵀ, 1]]`; a child on its node moves with `Xupᵢ v + Gᵢ η̇`. Pass 2 carries the
/// extended articulated inertia `[[IA, B], [Bᵀ, C]]` and bias `[pA; pₑ]` inward and
/// eliminates each body's hinge and modes together (subspace `[[S, 0], [0, 1]]`, pivot
/// `D = [[Sᵀ IA S, Sᵀ B], [Bᵀ S, C]]`); what is left acts only on the frame (`6 x 6`) and
/// reaches the parent through `[Xupᵢ, Gᵢ]`. The root solves its `6 + m₀` system (free) or
/// its modes (fixed). See the theory page "Flexible bodies".
///
/// Balanced rotors ([`crate::Gyrostat`], e.g. reaction wheels) on rigid carriers are folded
/// into their carriers as the rigid [`crate::aba::aba`] folds them, in hybrid dynamics too (a
/// locked rotor rides rigidly on its carrier): same accelerations to round-off, 12 % fewer
/// instructions a call on the flexible deployment's bus with three wheels (31.7 k to
/// 28.0 k, with the fast path below). Where a rotor rides on a flexible body every rotor
/// stays a body. Bodies on their parent's frame move by the coordinate-axis fast path of their
/// hinge's transform where it has one. A spherical gimbal of massless links
/// ([`FlexModel::folded_chains`]) is eliminated at its tip as one joint with the tip's modes
/// (`chain.rs`), as the rigid ABA eliminates it: 15.9 k instructions a call on the flexible
/// deployment where the links as bodies took 17.0 k.
pub fn aba<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    articulated(model, data, Call::new(q, v, tau, fext, None, false))
}

/// As [`aba`], reusing the first pass (deformed inertias, `Xup`, `G`, velocities, velocity
/// products) that [`super::forward_kinematics`] (or another flexible algorithm) left in
/// `data`, which must be that of this `q` and `v`: the simulation's right-hand side
/// computes the poses for its effects first, and this spares it a second pass (about 6 % of
/// the flexible deployment's instructions). The result is bit for bit [`aba`]'s.
///
/// ```
/// use satsim_tree::flexible::{aba, aba_with_kinematics, forward_kinematics, Beam, FlexData, FlexModel, Flexible, Modes};
/// use satsim_tree::{samples::chain, BaseKind, Data};
/// use satsim_tree::spatial::Vec3;
/// let beam = Beam { root: Vec3::zeros(), axis: Vec3::x(), bend: Vec3::z(), length: 1.0, ei: 50.0, rho_a: 2.0, modes: 2 };
/// let flex = [Flexible { body: "b1".into(), modes: Modes::Beam(beam), damping: 0.01, stiffening: true }];
/// let model = FlexModel::build(chain(3, BaseKind::Free).to_builder(), &flex)?;
/// let (mut data, mut poses) = (FlexData::new(&model), Data::new(model.rigid()));
/// let mut q = model.neutral();
/// q[7] = 0.3;
/// q[model.rigid().nq()] = 0.01;
/// let (v, tau) = (vec![0.1; model.nv()], vec![0.2; model.nv()]);
/// let plain = aba(&model, &mut data, &q, &v, &tau, None)?.clone();
/// forward_kinematics(&model, &mut data, &mut poses, &q, &v)?;
/// assert_eq!(aba_with_kinematics(&model, &mut data, &q, &v, &tau, None)?, &plain);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn aba_with_kinematics<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    articulated(model, data, Call::new(q, v, tau, fext, None, true))
}

/// Hybrid dynamics with locked hinges (as the rigid [`crate::aba::aba_hybrid`]): a hinge
/// whose entry in `locked` (one per hinge, in the order of addition) is `true` has zero
/// acceleration and its torque is ignored; the modes stay free. Each body eliminates its
/// modes alone where its hinge is locked (pivot `C`, columns `B`), nothing where it also has
/// no modes (welded to its parent). O(n), no allocation.
pub fn aba_hybrid<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: &[bool],
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_len("locked", locked.len(), model.rigid.n_hinges())?;
    articulated(model, data, Call::new(q, v, tau, fext, Some(locked), false))
}

/// As [`aba_hybrid`], reusing the first pass in `data`, which must be that of this `q` and
/// `v` (see [`aba_with_kinematics`]).
pub fn aba_hybrid_with_kinematics<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: &[bool],
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_len("locked", locked.len(), model.rigid.n_hinges())?;
    articulated(model, data, Call::new(q, v, tau, fext, Some(locked), true))
}

/// The inputs of one call: the public functions' and the two switches between them.
#[derive(Clone, Copy)]
pub(super) struct Call<'a> {
    pub q: &'a [f64],
    pub v: &'a [f64],
    pub tau: &'a [f64],
    pub fext: Option<&'a [Force]>,
    pub locked: Option<&'a [bool]>,
    pub first_pass_current: bool,
}

impl<'a> Call<'a> {
    fn new(
        q: &'a [f64],
        v: &'a [f64],
        tau: &'a [f64],
        fext: Option<&'a [Force]>,
        locked: Option<&'a [bool]>,
        first_pass_current: bool,
    ) -> Self {
        Self {
            q,
            v,
            tau,
            fext,
            locked,
            first_pass_current,
        }
    }
}

fn articulated<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    call: Call,
) -> Result<&'d DVector<f64>, DynamicsError> {
    articulated_on(crate::wide::avx2(), model, data, call)
}

/// [`articulated`] on the instance compiled for AVX2 where `wide` and the CPU has it, else
/// on the baseline's: the same operations, so the same bits (`crate::wide`). On the
/// flexible deployment the AVX2 instances of this and the first pass take 5 % off the
/// run's time (8 % of its instructions).
#[allow(unsafe_code)]
pub(super) fn articulated_on<'d>(
    wide: bool,
    model: &FlexModel,
    data: &'d mut FlexData,
    call: Call,
) -> Result<&'d DVector<f64>, DynamicsError> {
    #[cfg(target_arch = "x86_64")]
    if wide && crate::wide::cpu_avx2() {
        // SAFETY: `articulated_avx2` requires only a CPU with AVX2, which `cpu_avx2` found.
        return unsafe { articulated_avx2(model, data, call) };
    }
    articulated_in(false, model, data, call)
}

/// [`articulated_in`] compiled for AVX2, everything it inlines with it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn articulated_avx2<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    call: Call,
) -> Result<&'d DVector<f64>, DynamicsError> {
    articulated_in(true, model, data, call)
}

// The index loops run over several arrays at once (coordinates, buffers, offsets).
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn articulated_in<'d>(
    wide: bool,
    model: &FlexModel,
    data: &'d mut FlexData,
    call: Call,
) -> Result<&'d DVector<f64>, DynamicsError> {
    let Call {
        q,
        v,
        tau,
        fext,
        locked,
        first_pass_current,
    } = call;
    check_state(model, q, v)?;
    check_len("tau", tau.len(), model.nv())?;
    let rigid = &model.rigid;
    let n = rigid.n_bodies();
    if let Some(f) = fext {
        check_len("fext", f.len(), n)?;
    }
    if !first_pass_current {
        velocities_on(wide, model, data, q, v);
    }
    let nv = rigid.nv();
    set_chain_folds(model, data, locked);
    // Balanced rotors ride on their rigid carriers as gyrostats (see `crate::aba::aba`):
    // not bodies here, their carriers start from the inertias with the rotors locked.
    let fold = model.fold_rotors;
    // Pass 1 (after the velocities): each body's own extended inertia and bias, an instance
    // for the body's mode count as pass 2's.
    for i in 0..n {
        if fold && rigid.is_gyrostat[i] {
            continue;
        }
        if let Some(k) = model.chain_of[i].filter(|&k| data.chain_folds[k]) {
            // A folded chain's link has no inertia: only its external wrench, which the
            // chain's elimination takes from its bias.
            if rigid.chains[k].order[0] != i {
                data.pa[i] = fext.map_or(Force::zero(), |f| Force::zero() - f[i]);
                continue;
            }
        }
        match model.modes[i] {
            0 => own_terms(model, data, i, 0, q, v, fext),
            1 => own_terms(model, data, i, 1, q, v, fext),
            2 => own_terms(model, data, i, 2, q, v, fext),
            3 => own_terms(model, data, i, 3, q, v, fext),
            4 => own_terms(model, data, i, 4, q, v, fext),
            m => own_terms(model, data, i, m, q, v, fext),
        }
    }
    if fold {
        fold_gyrostats(model, data, v, tau, fext, locked);
    }
    // Pass 2, inward. Each body's elimination and its parent's update are instances for
    // the common mode counts, the loops unrolled (same operations, same bits).
    for i in (1..n).rev() {
        if fold && rigid.is_gyrostat[i] {
            continue;
        }
        if let Some(k) = model.chain_of[i].filter(|&k| data.chain_folds[k]) {
            // A spherical chain: eliminated at its tip, its links with it.
            if rigid.chains[k].order[0] == i {
                match model.modes[i] {
                    0 => chain::inward(model, data, k, 0, tau, fext.is_some())?,
                    3 => chain::inward(model, data, k, 3, tau, fext.is_some())?,
                    m => chain::inward(model, data, k, m, tau, fext.is_some())?,
                }
            }
            continue;
        }
        let (ia, pa) = match model.modes[i] {
            0 => eliminate(model, data, i, 0, tau, locked)?,
            1 => eliminate(model, data, i, 1, tau, locked)?,
            2 => eliminate(model, data, i, 2, tau, locked)?,
            3 => eliminate(model, data, i, 3, tau, locked)?,
            4 => eliminate(model, data, i, 4, tau, locked)?,
            m => eliminate(model, data, i, m, tau, locked)?,
        };
        let p = rigid.parent[i].expect("parent");
        match model.modes[p] {
            0 => to_parent(model, data, i, 0, &ia, &pa),
            1 => to_parent(model, data, i, 1, &ia, &pa),
            2 => to_parent(model, data, i, 2, &ia, &pa),
            3 => to_parent(model, data, i, 3, &ia, &pa),
            4 => to_parent(model, data, i, 4, &ia, &pa),
            mp => to_parent(model, data, i, mp, &ia, &pa),
        }
    }
    // The root.
    let (m0, c0) = (model.modes[0], data.c_offset[0]);
    match rigid.base {
        BaseKind::Free => {
            let r = 6 + m0;
            let ia = data.ia[0].to_matrix();
            let root = &mut data.root[..r * r];
            for a in 0..6 {
                for b in 0..6 {
                    root[a * r + b] = ia[(a, b)];
                }
            }
            for k in 0..m0 {
                let bk = data.b[k].to_array();
                for (a, x) in bk.into_iter().enumerate() {
                    root[a * r + 6 + k] = x;
                    root[(6 + k) * r + a] = x;
                }
                for l in 0..m0 {
                    root[(6 + k) * r + 6 + l] = data.cm[c0 + k * m0 + l];
                }
            }
            if dense::factor(root, r).is_err() {
                return Err(DynamicsError::SingularBase);
            }
            let pa = data.pa[0].to_array();
            let rhs = &mut data.tmp[..r];
            for a in 0..6 {
                rhs[a] = tau[a] - pa[a];
            }
            for k in 0..m0 {
                rhs[6 + k] = tau[nv + k] - data.pe[k];
            }
            dense::solve(&data.root[..r * r], r, rhs);
            for a in 0..6 {
                data.ddq[a] = rhs[a];
            }
            for k in 0..m0 {
                data.ddq[nv + k] = rhs[6 + k];
            }
            data.a[0] = Motion::from_slice(&rhs[..6]);
        }
        BaseKind::Fixed => {
            data.a[0] = Motion::zero();
            if m0 > 0 {
                let root = &mut data.root[..m0 * m0];
                root.copy_from_slice(&data.cm[c0..c0 + m0 * m0]);
                if dense::factor(root, m0).is_err() {
                    return Err(DynamicsError::SingularBase);
                }
                let rhs = &mut data.tmp[..m0];
                for k in 0..m0 {
                    rhs[k] = tau[nv + k] - data.pe[k];
                }
                dense::solve(&data.root[..m0 * m0], m0, rhs);
                for k in 0..m0 {
                    data.ddq[nv + k] = rhs[k];
                }
            }
        }
    }
    // Pass 3, outward (instances for the body's mode count, as pass 2's).
    for i in 1..n {
        let p = rigid.parent[i].expect("parent");
        if fold && rigid.is_gyrostat[i] {
            let joint = rigid.joints[i].as_ref().expect("joint");
            let a = apply_motion(model.frame_axis(i), &data.xup[i], &data.a[p]) + data.c[i];
            // The rotor's axial equation, `Ω̇ = τ / J − a · α_carrier` (zero when locked).
            let qdd = if h_free(locked, joint.hinge()) {
                data.u[data.u_offset[i]] / data.d[data.d_offset[i]] - joint.axis.dot(&data.a[p].ang)
            } else {
                0.0
            };
            data.ddq[joint.dof] = qdd;
            data.a[i] = a + joint.s * qdd;
            continue;
        }
        if let Some(k) = model.chain_of[i].filter(|&k| data.chain_folds[k]) {
            // Its links come first in this order and are set with it.
            let chain = &rigid.chains[k];
            if chain.order[0] == i {
                match model.modes[i] {
                    0 => chain::outward(model, data, k, 0),
                    3 => chain::outward(model, data, k, 3),
                    m => chain::outward(model, data, k, m),
                }
            }
            continue;
        }
        match model.modes[i] {
            0 => outward(model, data, i, 0, locked),
            1 => outward(model, data, i, 1, locked),
            2 => outward(model, data, i, 2, locked),
            3 => outward(model, data, i, 3, locked),
            4 => outward(model, data, i, 4, locked),
            m => outward(model, data, i, m, locked),
        }
    }
    Ok(&data.ddq)
}

/// Pass 1 for body `i` with `m` modes: its extended inertia `[[I, P], [Pᵀ, 1]]` at its
/// deformation and its bias `[pA; pₑ]` (velocity products, stiffening, springs, dampers,
/// the external wrench). Inlined with `m` known where the caller dispatches on it.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn own_terms(
    model: &FlexModel,
    data: &mut FlexData,
    i: usize,
    m: usize,
    q: &[f64],
    v: &[f64],
    fext: Option<&[Force]>,
) {
    let rigid = &model.rigid;
    let (nq, nv) = (rigid.nq(), rigid.nv());
    let carrier = model.fold_rotors && m == 0;
    let inertia = &if carrier {
        rigid.carrier_inertia[i]
    } else {
        data.inertia[i]
    };
    let o = model.offset[i];
    let (eta, etad) = (&q[nq + o..][..m], &v[nv + o..][..m]);
    // Read in place: a copy on the stack was read back across its stores' halves, a
    // stalled store forwarding at every body (`perf`).
    let vi = &data.v[i];
    let mut h = inertia.mul_motion(vi);
    let co = data.c_offset[i];
    // The body's entries as slices of their length (`m` known in the instances): indexed
    // without bounds checks, here and in the passes below.
    let (b, pe) = (&mut data.b[o..][..m], &mut data.pe[o..][..m]);
    let cm = &mut data.cm[co..][..m * m];
    let (damping, stiffness) = (&model.damping[o..][..m], &model.stiffness[o..][..m]);
    for k in 0..m {
        let pk = model.momentum_of(i, eta, k);
        h += pk * etad[k];
        b[k] = pk;
        pe[k] = damping[k] * etad[k] + stiffness[k] * eta[k];
        for l in 0..m {
            cm[k * m + l] = if k == l { 1.0 } else { 0.0 };
        }
    }
    data.ia[i] = if carrier {
        rigid.carrier_ia[i]
    } else {
        ArticulatedInertia::from(*inertia)
    };
    // Built in a local, stored once: the wrench's subtraction read `data.pa[i]` back from
    // the stiffening's fresh stores (a stalled store forwarding, `perf`).
    let mut pa = vi.cross_force(&h);
    model.add_stiffening_of(i, eta, etad, vi, &mut pa, pe);
    if let Some(fe) = fext {
        pa -= fe[i];
    }
    data.pa[i] = pa;
}

/// Pass 2 for body `i` with `m` modes: its hinge (unless locked) and modes eliminated
/// together, `IA − U D⁻¹ Uᵀ` and `pA + IAᵃ c + U D⁻¹ u` returned (what the parent receives,
/// in `i`'s coordinates). Inlined with `m` known where the caller dispatches on it.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn eliminate(
    model: &FlexModel,
    data: &mut FlexData,
    i: usize,
    m: usize,
    tau: &[f64],
    locked: Option<&[bool]>,
) -> Result<(ArticulatedInertia, Force), DynamicsError> {
    let rigid = &model.rigid;
    let nv = rigid.nv();
    let joint = rigid.joints[i].as_ref().expect("joint");
    let o = model.offset[i];
    // The hinge's column, unless locked: then only the modes are eliminated.
    let h = usize::from(h_free(locked, joint.hinge()));
    let d = h + m;
    let (uo, dof, co) = (data.u_offset[i], data.d_offset[i], data.c_offset[i]);
    let s = joint.s;
    let dm = &mut data.d[dof..][..d * d];
    let (u_col, u) = (&mut data.u_col[uo..][..d], &mut data.u[uo..][..d]);
    if h == 1 {
        let u0 = data.ia[i].mul_motion(&s);
        u_col[0] = u0;
        u[0] = tau[joint.dof] - s.dot(&data.pa[i]);
        dm[0] = s.dot(&u0) + joint.armature();
    }
    let (b, pe) = (&data.b[o..][..m], &data.pe[o..][..m]);
    let (cm, tau_e) = (&data.cm[co..][..m * m], &tau[nv + o..][..m]);
    for k in 0..m {
        let bk = b[k];
        u_col[h + k] = bk;
        u[h + k] = tau_e[k] - pe[k];
        if h == 1 {
            let sb = s.dot(&bk);
            dm[(1 + k) * d] = sb;
            dm[1 + k] = sb;
        }
        for l in 0..m {
            dm[(h + k) * d + h + l] = cm[k * m + l];
        }
    }
    if d > 0
        && let Err((j, pivot)) = dense::factor(dm, d)
    {
        // Column `j`: the hinge's (first, unless locked), else mode `j − h`.
        return Err(DynamicsError::NotPositiveDefinite {
            index: if j < h { joint.dof } else { nv + o + j - h },
            pivot,
        });
    }
    // IA − U D⁻¹ Uᵀ = IA − Σⱼ wⱼ wⱼᵀ / dⱼ with W Lᵀ = U (forward substitution on the
    // columns, `D = L diag(d) Lᵀ`).
    let l = &data.d[dof..][..d * d];
    let (u_col, cols) = (&data.u_col[uo..][..d], &mut data.cols[..d]);
    let mut ia = data.ia[i];
    for j in 0..d {
        let mut w = u_col[j];
        for k in 0..j {
            w -= cols[k] * l[j * d + k];
        }
        cols[j] = w;
        ia.sub_outer(&w, l[j * d + j]);
    }
    // pa = pA + IAᵃ c + U D⁻¹ u.
    let y = &mut data.tmp[..d];
    y.copy_from_slice(&data.u[uo..][..d]);
    if d > 0 {
        dense::solve(l, d, y);
    }
    let mut pa = data.pa[i] + ia.mul_motion(&data.c[i]);
    for j in 0..d {
        pa += u_col[j] * y[j];
    }
    Ok((ia, pa))
}

/// Pass 2's update of body `i`'s parent (with `mp` modes) from what `i` passes on: the
/// frame block through `Xupᵢ`, the parent's coupling columns, modal block and bias through
/// `Gᵢ`. Inlined with `mp` known where the caller dispatches on it.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn to_parent(
    model: &FlexModel,
    data: &mut FlexData,
    i: usize,
    mp: usize,
    ia: &ArticulatedInertia,
    pa: &Force,
) {
    let p = model.rigid.parent[i].expect("parent");
    let x = data.xup[i];
    // A body on its parent's frame (not on a node) moves by the rigid hinge's `Xup`: the
    // coordinate-axis fast path where the hinge has one, as the rigid ABA's.
    let axis = model.frame_axis(i);
    accumulate_inv_transform(axis, ia, &x, &mut data.ia[p]);
    data.pa[p] += inv_apply_force(axis, &x, pa);
    let (op, cp) = (model.offset[p], data.c_offset[p]);
    let g = &data.g[data.g_offset[i]..][..mp];
    let (b, pe) = (&mut data.b[op..][..mp], &mut data.pe[op..][..mp]);
    let cm = &mut data.cm[cp..][..mp * mp];
    for k in 0..mp {
        let h = ia.mul_motion(&g[k]);
        b[k] += inv_apply_force(axis, &x, &h);
        pe[k] += g[k].dot(pa);
        for l in 0..mp {
            cm[l * mp + k] += g[l].dot(&h);
        }
    }
}

/// Pass 3 for body `i` (`m` modes): its frame's acceleration from the parent's and the
/// parent's modes, then its hinge's and modes' accelerations. Inlined with `m` known where
/// the caller dispatches on it.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn outward(model: &FlexModel, data: &mut FlexData, i: usize, m: usize, locked: Option<&[bool]>) {
    let rigid = &model.rigid;
    let nv = rigid.nv();
    let joint = rigid.joints[i].as_ref().expect("joint");
    let p = rigid.parent[i].expect("parent");
    let o = model.offset[i];
    let h = usize::from(h_free(locked, joint.hinge()));
    let d = h + m;
    let (uo, dof) = (data.u_offset[i], data.d_offset[i]);
    let (op, mp, go) = (model.offset[p], model.modes[p], data.g_offset[i]);
    let mut a = apply_motion(model.frame_axis(i), &data.xup[i], &data.a[p]) + data.c[i];
    let (g, ddq_p) = (&data.g[go..][..mp], &data.ddq.as_slice()[nv + op..][..mp]);
    for k in 0..mp {
        a += g[k] * ddq_p[k];
    }
    let y = &mut data.tmp[..d];
    let (u, u_col) = (&data.u[uo..][..d], &data.u_col[uo..][..d]);
    for j in 0..d {
        y[j] = u[j] - a.dot(&u_col[j]);
    }
    if d > 0 {
        dense::solve(&data.d[dof..][..d * d], d, y);
    }
    if h == 1 {
        data.ddq[joint.dof] = y[0];
        data.a[i] = a + joint.s * y[0];
    } else {
        data.ddq[joint.dof] = 0.0;
        data.a[i] = a;
    }
    for k in 0..m {
        data.ddq[nv + o + k] = y[h + k];
    }
}

/// Which chains are eliminated as one spherical joint in this call, into `data.chain_folds`:
/// those that fold ([`FlexModel`]'s `fold_chain`) with none of their hinges locked.
fn set_chain_folds(model: &FlexModel, data: &mut FlexData, locked: Option<&[bool]>) {
    let rigid = &model.rigid;
    for (k, chain) in rigid.chains.iter().enumerate() {
        let hinge = |b: usize| rigid.joints[b].as_ref().expect("joint").hinge();
        data.chain_folds[k] = model.fold_chain[k]
            && chain.order[..chain.k]
                .iter()
                .all(|&b| h_free(locked, hinge(b)));
    }
}

/// Whether `hinge` moves (not locked).
#[inline(always)]
fn h_free(locked: Option<&[bool]>, hinge: usize) -> bool {
    !locked.is_some_and(|l| l[hinge])
}

/// The rotors' gyrostat terms on their carriers (after pass 1; the rigid ABA's, with a
/// locked rotor too). A free rotor adds the gyroscopic couple of its spin momentum
/// `ω × (J Ω a)` and the reaction `a τ` of its axial torque to its carrier's bias, whose
/// articulated inertia already lacks `J a aᵀ` (the rotor is free about its axis); an external
/// wrench on it spins it by its axial moment and acts on the carrier with the rest. A
/// locked rotor is rigid with its carrier: `J a aᵀ` back in the carrier's inertia, the
/// couple of its spin, the whole wrench on the carrier, and its torque held by the lock.
/// Stores `τ` (with the axial moment) in `u` and `J` in `d` for the rotor's acceleration.
fn fold_gyrostats(
    model: &FlexModel,
    data: &mut FlexData,
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: Option<&[bool]>,
) {
    let rigid = &model.rigid;
    for g in &rigid.gyrostats {
        let joint = rigid.joints[g.body].as_ref().expect("joint");
        let free = h_free(locked, joint.hinge());
        let mut tau_axial = tau[joint.dof];
        if let Some(f) = fext {
            let fr = f[g.body];
            if free {
                tau_axial += joint.s.dot(&fr);
            }
            data.pa[g.parent] -= data.xup[g.body].inv_apply_force(&fr);
        }
        let w = data.v[g.parent].ang;
        let mut couple = w.cross(&g.axis) * (g.axial * v[joint.dof]);
        if free {
            couple += g.axis * tau_axial;
        } else {
            data.ia[g.parent].a += g.axis * g.axis.transpose() * g.axial;
        }
        data.pa[g.parent].ang += couple;
        data.u[data.u_offset[g.body]] = tau_axial;
        data.d[data.d_offset[g.body]] = g.axial;
    }
}

/// `out += Xᵀ IA X` in place, by the coordinate-axis fast path where `axis` is given: the
/// rigid ABA's `add_inv_transform` without its `start`, written here always inlined (that one
/// stays out of line in this function, +0.5 % of the flexible deployment's instructions; made
/// always inline there, it costs the rigid ABA 1.3 % on `two_wings.toml`).
#[inline(always)]
fn accumulate_inv_transform(
    axis: &Option<CoordAxis>,
    ia: &ArticulatedInertia,
    x: &Transform,
    out: &mut ArticulatedInertia,
) {
    match axis {
        Some(a) => a.add_inv_transform(ia, x, out, None),
        None => ia.add_inv_transform_to(x, out, None),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Beam, FlexData, FlexModel, Flexible, Modes};
    use super::{Call, articulated_on};
    use crate::BaseKind;
    use crate::samples::{SplitMix, chain};
    use crate::spatial::{Force, Vec3};

    /// The instance compiled for AVX2 (the ABA and its first pass) gives the baseline's bits:
    /// free and hybrid, with and without external wrenches, three beams of 1, 3 and 4 modes
    /// on a free chain (where the CPU has AVX2; elsewhere both calls are the baseline's).
    #[test]
    fn the_avx2_instance_gives_the_baselines_bits() {
        let beam = |modes| Beam {
            root: Vec3::zeros(),
            axis: Vec3::x(),
            bend: Vec3::z(),
            length: 1.0,
            ei: 50.0,
            rho_a: 2.0,
            modes,
        };
        let flex: Vec<Flexible> = [("b0", 1), ("b1", 3), ("b3", 4)]
            .into_iter()
            .map(|(body, m)| Flexible {
                body: body.into(),
                modes: Modes::Beam(beam(m)),
                damping: 0.01,
                stiffening: true,
            })
            .collect();
        let model = FlexModel::build(chain(5, BaseKind::Free).to_builder(), &flex).expect("model");
        let mut rng = SplitMix(7);
        let mut r = |s: f64| s * (2.0 * rng.next_f64() - 1.0);
        let mut data = [FlexData::new(&model), FlexData::new(&model)];
        for case in 0..8 {
            let mut q = model.neutral();
            let nq = model.rigid().nq();
            for (k, x) in q.iter_mut().enumerate().skip(3) {
                if k >= 7 {
                    *x = r(if k >= nq { 0.05 } else { 1.0 });
                }
            }
            let v: Vec<f64> = (0..model.nv()).map(|_| r(1.0)).collect();
            let tau: Vec<f64> = (0..model.nv()).map(|_| r(2.0)).collect();
            let fext: Vec<Force> = (0..model.rigid().n_bodies())
                .map(|_| {
                    Force::new(
                        Vec3::new(r(1.0), r(1.0), r(1.0)),
                        Vec3::new(r(1.0), r(1.0), r(1.0)),
                    )
                })
                .collect();
            let locked: Vec<bool> = (0..model.rigid().n_hinges())
                .map(|h| (h + case) % 3 == 0)
                .collect();
            let fext = (case % 2 == 1).then_some(&fext[..]);
            let locked = (case >= 4).then_some(&locked[..]);
            let [d0, d1] = &mut data;
            let call = Call::new(&q, &v, &tau, fext, locked, false);
            let base = articulated_on(false, &model, d0, call)
                .expect("baseline")
                .clone();
            let wide = articulated_on(true, &model, d1, call).expect("avx2");
            let bits = |x: &[f64]| x.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(base.as_slice()), bits(wide.as_slice()), "case {case}");
            assert!(base.iter().all(|a| a.is_finite()) && base.iter().any(|a| *a != 0.0));
        }
    }
}
