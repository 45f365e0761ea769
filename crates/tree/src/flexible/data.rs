//! [`FlexData`]: the reusable workspace of the flexible algorithms, and their shared first
//! pass (transforms, velocities, the node subspaces `G`, velocity-product accelerations).

use super::chain::ChainWork;
use super::model::FlexModel;
use crate::aba::apply_motion;
use crate::error::DynamicsError;
use crate::kinematics::{base_motion, check_len};
use crate::spatial::{ArticulatedInertia, Force, Motion, RigidInertia, Transform};
use nalgebra::{DMatrix, DVector};

/// Scratch buffers and results for one [`FlexModel`], allocated once by [`FlexData::new`].
/// Per-body vectors are indexed like the rigid model's bodies, in each body's own frame.
/// As [`crate::Data`], scratch and not state.
#[derive(Clone, Debug)]
pub struct FlexData {
    /// `Xup[i]`: from `λ(i)`'s coordinates to body `i`'s, the parent's deformation included.
    pub xup: Vec<Transform>,
    /// Spatial velocity of each body's frame.
    pub v: Vec<Motion>,
    /// Spatial acceleration of each body's frame (RNEA, ABA).
    pub a: Vec<Motion>,
    /// Velocity-product acceleration of each body's frame (its node's and its hinge's).
    pub c: Vec<Motion>,
    /// Spatial force across each body's hinge (RNEA).
    pub f: Vec<Force>,
    /// Per body whose parent is flexible: `G`, the body's motion per unit parent `η̇ₖ`
    /// (body coordinates), at `g_offset[i]`.
    pub(crate) g: Vec<Motion>,
    pub(crate) g_offset: Vec<usize>,
    /// Each body's rigid inertia at the deformation of the last first pass: a stiffened
    /// beam's [`FlexModel::deformed_inertia`], made once a pass for every algorithm and
    /// effect that reads it ([`FlexData::inertias`]); the rigid model's otherwise.
    pub(crate) inertia: Vec<RigidInertia>,
    /// Composite rigid inertias (CRBA).
    pub(crate) ic: Vec<RigidInertia>,
    /// Articulated inertias' frame block `IA` (ABA).
    pub(crate) ia: Vec<ArticulatedInertia>,
    /// Articulated bias forces' frame part `pA` (ABA).
    pub(crate) pa: Vec<Force>,
    /// Articulated coupling columns `B` (frame x modes), at the model's `offset`.
    pub(crate) b: Vec<Force>,
    /// Articulated modal blocks `C` (modes x modes, row-major), at `c_offset`.
    pub(crate) cm: Vec<f64>,
    pub(crate) c_offset: Vec<usize>,
    /// Articulated modal bias `pₑ`, at the model's `offset`.
    pub(crate) pe: Vec<f64>,
    /// Per body: the `L D Lᵀ` factor of its `(1 + m)` pivot `D` (`flexible/dense.rs`), at
    /// `d_offset`; a rotor folded into its carrier keeps its axial moment `J` there instead
    /// (`fold_gyrostats`), which pass 3 divides by.
    pub(crate) d: Vec<f64>,
    pub(crate) d_offset: Vec<usize>,
    /// Per body: the frame rows of `U` (`1 + m` columns) and `u`, at `u_offset`.
    pub(crate) u_col: Vec<Force>,
    pub(crate) u: Vec<f64>,
    pub(crate) u_offset: Vec<usize>,
    /// Per chain of the rigid model: its elimination at the tip where the ABA folds it
    /// (`flexible/chain.rs`).
    pub(crate) chains: Vec<ChainWork>,
    /// Per chain: whether the ABA's current call eliminates it at its tip (none of its hinges
    /// locked).
    pub(crate) chain_folds: Vec<bool>,
    /// The root's `(6 + m₀)` system (ABA, free base).
    pub(crate) root: Vec<f64>,
    /// Scratch of `6 + max modes` entries.
    pub(crate) tmp: Vec<f64>,
    /// Scratch columns, `3 + max modes` (CRBA, ABA, a folded chain's three hinges).
    pub(crate) cols: Vec<Force>,
    /// Mass matrix `M`, `nv x nv` (CRBA).
    pub mass_matrix: DMatrix<f64>,
    /// Generalised forces, `nv` (RNEA).
    pub tau: DVector<f64>,
    /// Generalised accelerations, `nv` (ABA; zero acceleration for the bias).
    pub ddq: DVector<f64>,
    /// Bias forces `b = τ(q, v, 0)`, `nv`.
    pub bias: DVector<f64>,
}

impl FlexData {
    /// Allocates the workspace for `model`.
    pub fn new(model: &FlexModel) -> Self {
        let n = model.rigid.n_bodies();
        let nv = model.nv();
        let mut g_offset = vec![0; n];
        let mut c_offset = vec![0; n];
        let mut d_offset = vec![0; n];
        let mut u_offset = vec![0; n];
        let (mut ng, mut nc, mut nd, mut nu) = (0, 0, 0, 0);
        for i in 0..n {
            g_offset[i] = ng;
            if let Some(p) = model.rigid.parent()[i] {
                ng += model.modes[p];
            }
            let m = model.modes[i];
            c_offset[i] = nc;
            nc += m * m;
            d_offset[i] = nd;
            nd += (1 + m) * (1 + m);
            u_offset[i] = nu;
            nu += 1 + m;
        }
        let mm = model.max_modes();
        let r = 6 + model.modes[0];
        Self {
            xup: vec![Transform::identity(); n],
            v: vec![Motion::zero(); n],
            a: vec![Motion::zero(); n],
            c: vec![Motion::zero(); n],
            f: vec![Force::zero(); n],
            g: vec![Motion::zero(); ng],
            g_offset,
            inertia: model.rigid.bodies.iter().map(|b| b.inertia).collect(),
            ic: vec![RigidInertia::default(); n],
            ia: vec![ArticulatedInertia::default(); n],
            pa: vec![Force::zero(); n],
            b: vec![Force::zero(); model.n_elastic],
            cm: vec![0.0; nc],
            c_offset,
            pe: vec![0.0; model.n_elastic],
            d: vec![0.0; nd],
            d_offset,
            u_col: vec![Force::zero(); nu],
            u: vec![0.0; nu],
            u_offset,
            chains: (0..model.rigid.chains.len())
                .map(|k| {
                    let tip = model.rigid.chains[k].order[0];
                    ChainWork::new(if model.fold_chain[k] {
                        3 + model.modes[tip]
                    } else {
                        0
                    })
                })
                .collect(),
            chain_folds: vec![false; model.rigid.chains.len()],
            root: vec![0.0; r * r],
            tmp: vec![0.0; 6 + mm],
            cols: vec![Force::zero(); 3 + mm],
            mass_matrix: DMatrix::zeros(nv, nv),
            tau: DVector::zeros(nv),
            ddq: DVector::zeros(nv),
            bias: DVector::zeros(nv),
        }
    }
}

impl FlexData {
    /// Each body's inertia (mass, first moment and rotational inertia about its frame's
    /// origin, body axes) at the elastic coordinates of the last call of a flexible
    /// algorithm or [`super::forward_kinematics`]: [`FlexModel::deformed_inertia`] of
    /// those coordinates, made once by their first pass (a simulation's effects read it
    /// after the kinematics, as the dynamics do).
    pub fn inertias(&self) -> &[RigidInertia] {
        &self.inertia
    }
}

/// Checks the lengths of `q` and `v`.
pub(crate) fn check_state(model: &FlexModel, q: &[f64], v: &[f64]) -> Result<(), DynamicsError> {
    check_len("q", q.len(), model.nq())?;
    check_len("v", v.len(), model.nv())
}

/// Pass 1 of every flexible algorithm: the stiffened bodies' inertias at `η`, `Xup`, `G`,
/// body velocities `v` and velocity-product accelerations `c` (`aᵢ = Xupᵢ a_λ + Gᵢ η̈_λ + Sᵢ φ̈ᵢ + cᵢ`). A body on a rigid parent gets
/// exactly the rigid algorithms' `Xup`, `v` and `c`.
pub(crate) fn velocities(model: &FlexModel, data: &mut FlexData, q: &[f64], v: &[f64]) {
    velocities_on(crate::wide::avx2(), model, data, q, v);
}

/// [`velocities`] on the instance compiled for AVX2 where `wide` and the CPU has it, else on
/// the baseline's: the same bits (`crate::wide`).
#[allow(unsafe_code)]
pub(crate) fn velocities_on(
    wide: bool,
    model: &FlexModel,
    data: &mut FlexData,
    q: &[f64],
    v: &[f64],
) {
    #[cfg(target_arch = "x86_64")]
    if wide && crate::wide::cpu_avx2() {
        // SAFETY: `velocities_avx2` requires only a CPU with AVX2, which `cpu_avx2` found.
        unsafe { velocities_avx2(model, data, q, v) };
        return;
    }
    velocities_in(model, data, q, v);
}

/// [`velocities_in`] compiled for AVX2, everything it inlines with it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn velocities_avx2(model: &FlexModel, data: &mut FlexData, q: &[f64], v: &[f64]) {
    velocities_in(model, data, q, v);
}

#[inline(always)]
fn velocities_in(model: &FlexModel, data: &mut FlexData, q: &[f64], v: &[f64]) {
    let rigid = &model.rigid;
    let (nq, nv) = (rigid.nq(), rigid.nv());
    let (eta, etad) = (&q[nq..], &v[nv..]);
    // Instances for the common mode counts (the loops unrolled, the same sums).
    for (i, s) in model.stiffening.iter().enumerate() {
        if s.is_some() {
            let (o, m) = (model.offset[i], model.modes[i]);
            data.inertia[i] = match m {
                1 => model.deformed_of(i, &eta[o..][..1]),
                2 => model.deformed_of(i, &eta[o..][..2]),
                3 => model.deformed_of(i, &eta[o..][..3]),
                4 => model.deformed_of(i, &eta[o..][..4]),
                _ => model.deformed_of(i, &eta[o..][..m]),
            };
        }
    }
    data.v[0] = base_motion(rigid, v);
    data.c[0] = Motion::zero();
    for i in 1..rigid.n_bodies() {
        let p = rigid.parent[i].expect("non-root body has a parent");
        let joint = rigid.joints[i].as_ref().expect("joint");
        let x = rigid.xup(i, q);
        let vj = joint.s * v[joint.dof];
        match &model.nodes[i] {
            // The velocity kept in registers for `c`: read back from `data.v`, it waited on
            // its own stores (a stalled store forwarding, `perf`).
            None => {
                data.xup[i] = x;
                let vi = apply_motion(model.frame_axis(i), &x, &data.v[p]) + vj;
                data.v[i] = vi;
                data.c[i] = vi.cross_motion(&vj);
            }
            Some(node) => {
                let (o, m) = (model.offset[p], model.modes[p]);
                let g = &mut data.g[data.g_offset[i]..][..m];
                let (eta, etad, vp) = (&eta[o..], &etad[o..], &data.v[p]);
                // Instances for the common mode counts, as the deformed inertias above.
                let st = match m {
                    1 => node.state(&eta[..1], &etad[..1], vp, g),
                    2 => node.state(&eta[..2], &etad[..2], vp, g),
                    3 => node.state(&eta[..3], &etad[..3], vp, g),
                    4 => node.state(&eta[..4], &etad[..4], vp, g),
                    _ => node.state(&eta[..m], &etad[..m], vp, g),
                };
                // The hinge from the node frame (its origin the hinge point) to the child,
                // by its coordinate-axis fast path where it has one.
                let xc = Transform::new(x.rot, x.trans - node.at);
                let hinge_axis = &rigid.coord_axis[i];
                for gk in g.iter_mut() {
                    *gk = apply_motion(hinge_axis, &xc, gk);
                }
                data.xup[i] = match &model.node_axis[i] {
                    Some(a) => a.compose(&xc, &st.x),
                    None => xc.compose(&st.x),
                };
                let vi = apply_motion(hinge_axis, &xc, &st.w) + vj;
                data.v[i] = vi;
                data.c[i] = apply_motion(hinge_axis, &xc, &st.c) + vi.cross_motion(&vj);
            }
        }
    }
}

/// Pass 1's `Xup` alone, at `q` (the same transforms as [`velocities`]'s): what the bodies'
/// poses need, for a caller that reads no motion (a view).
pub(crate) fn transforms(model: &FlexModel, data: &mut FlexData, q: &[f64]) {
    let rigid = &model.rigid;
    let eta = &q[rigid.nq()..];
    for i in 1..rigid.n_bodies() {
        let x = rigid.xup(i, q);
        data.xup[i] = match &model.nodes[i] {
            None => x,
            Some(node) => {
                let p = rigid.parent[i].expect("non-root body has a parent");
                let (o, m) = (model.offset[p], model.modes[p]);
                let node_x = node.pose(&eta[o..o + m]);
                let xc = Transform::new(x.rot, x.trans - node.at);
                match &model.node_axis[i] {
                    Some(a) => a.compose(&xc, &node_x),
                    None => xc.compose(&node_x),
                }
            }
        };
    }
}
