//! The flexible ABA's passes 2 and 3 for a spherical [`Chain`] (three hinges through two
//! massless, zero-length links: the preprint's gimbal), whose tip may be flexible: the three
//! hinges and the tip's modes eliminated together at the common hinge point, as the rigid
//! `aba.rs` eliminates a chain's hinges (`chain_inward`, `chain_outward`), instead of the
//! links as three bodies.
//!
//! In the frame at the hinge point with the tip's axes, the joint's subspace is
//! `[[E, 0], [0, 0], [0, 1]]` over `[hinges; modes]` (`E`: the three axes), the pivot is
//! `D = [[Eᵀ A_h E, Eᵀ B_ang], [B_angᵀ E, C]]` (`A_h`: the tip's articulated inertia's
//! rotational block at the point, `B_ang`: its modal columns' moments there), eliminated
//! in the tree form's order (the tip's hinge, its modes, then the links' hinges outward),
//! so that its pivots are the tree form's. Three independent axes through the point leave
//! the parent only the linear block `C − …`: `[0 0; 0 C']` (as the rigid spherical chain;
//! a frame turning about the point is taken up by the hinges, the modes at rest).

use super::data::FlexData;
use super::dense;
use super::model::FlexModel;
use crate::aba::{ChainFrame, apply_motion, chain_frame, links_bias, to_point};
use crate::error::DynamicsError;
use crate::kernel_parts::add_linear_inv_transform;
use crate::spatial::{Force, Mat3, Motion, Transform};

/// A folded chain's elimination, kept for pass 3: `(3 + m)` columns in the order
/// `[tip hinge, tip modes, link hinges outward]`.
#[derive(Clone, Debug)]
pub(crate) struct ChainWork {
    /// From the chain parent's coordinates to the hinge point's frame (the tip's axes).
    x: Transform,
    /// The chain's velocity-product acceleration at the point.
    c: Motion,
    /// The `L D Lᵀ` factor of the pivot (`dense.rs`), row-major.
    d: Vec<f64>,
    /// `U`, the columns' forces at the point.
    u_col: Vec<Force>,
    /// `u = τ − Sᵀ pA` (and the links' external forces).
    u: Vec<f64>,
}

impl ChainWork {
    /// The workspace of a chain of `n = 3 + m` columns (0: not folded).
    pub(crate) fn new(n: usize) -> Self {
        Self {
            x: Transform::identity(),
            c: Motion::zero(),
            d: vec![0.0; n * n],
            u_col: vec![Force::zero(); n],
            u: vec![0.0; n],
        }
    }
}

/// Where column `j` of the elimination order sits among the chain's hinges (`Ok(t)`, `t` in
/// [`Chain`] order: the tip's first) or the tip's modes (`Err(k)`), for `m` modes.
#[inline(always)]
fn column(j: usize, m: usize) -> Result<usize, usize> {
    match j {
        0 => Ok(0),
        j if j <= m => Err(j - 1),
        j => Ok(j - m),
    }
}

/// Pass 2 for folded chain `k` (tip with `m` modes): the tip's hinges and modes eliminated at
/// the hinge point, the parent's inertia and bias updated. `loaded`: external forces were
/// given (the links' bias is zero otherwise).
#[inline(always)]
#[allow(clippy::needless_range_loop)]
pub(super) fn inward(
    model: &FlexModel,
    data: &mut FlexData,
    k: usize,
    m: usize,
    tau: &[f64],
    loaded: bool,
) -> Result<(), DynamicsError> {
    let rigid = &model.rigid;
    let chain = &rigid.chains[k];
    let (b, p, nv) = (&chain.order, chain.parent, rigid.nv());
    let tip = b[0];
    let n = 3 + m;
    let ChainFrame { e, rot, c, .. } = chain_frame::<3>(rigid, &data.xup, &data.c, chain);
    let r = chain.tip_at;
    // The tip's articulated inertia, bias and modal columns at the point: a force's moment
    // about it is `n − r × f`.
    let ia = data.ia[tip];
    let (ah, bh) = to_point(&ia, &r);
    let at_point = |f: Force| Force::new(f.ang - r.cross(&f.lin), f.lin);
    let pa = at_point(data.pa[tip]);
    let o = model.offset[tip];
    let (bcol, pe) = (&data.b[o..][..m], &data.pe[o..][..m]);
    let cm = &data.cm[data.c_offset[tip]..][..m * m];
    let mut du = [0.0; 3];
    if loaded && (1..3).any(|t| data.pa[b[t]] != Force::zero()) {
        let g;
        (du, g) = links_bias::<3>(rigid, &data.xup, &data.pa, chain);
        data.pa[p] += g;
    }
    let w = &mut data.chains[k];
    let (d, u_col, u) = (&mut w.d[..n * n], &mut w.u_col[..n], &mut w.u[..n]);
    for j in 0..n {
        match column(j, m) {
            Ok(t) => {
                u_col[j] = Force::new(ah * e[t], bh.tr_mul(&e[t]));
                u[j] = tau[chain.dof[t]] + du[t] - e[t].dot(&pa.ang);
            }
            Err(q) => {
                u_col[j] = at_point(bcol[q]);
                u[j] = tau[nv + o + q] - pe[q];
            }
        }
    }
    for i in 0..n {
        for j in 0..=i {
            d[i * n + j] = match (column(i, m), column(j, m)) {
                (Err(a), Err(q)) => cm[a * m + q],
                (Ok(t), _) => e[t].dot(&u_col[j].ang),
                (Err(_), Ok(t)) => e[t].dot(&u_col[i].ang),
            };
        }
    }
    if let Err((j, pivot)) = dense::factor(d, n) {
        return Err(DynamicsError::NotPositiveDefinite {
            index: match column(j, m) {
                Ok(t) => chain.dof[t],
                Err(q) => nv + o + q,
            },
            pivot,
        });
    }
    // C' = C − Σⱼ wⱼ.lin wⱼ.linᵀ / dⱼ with W Lᵀ = U (the linear block of `IA_h − U D⁻¹ Uᵀ`,
    // the rest zero), and pA' = pA_h + [0; C' c.lin] + U D⁻¹ u.
    let cols = &mut data.cols[..n];
    let mut cc: Mat3 = ia.c;
    for j in 0..n {
        let mut wj = u_col[j];
        for q in 0..j {
            wj -= cols[q] * d[j * n + q];
        }
        cols[j] = wj;
        cc -= (wj.lin * d[j * n + j]) * wj.lin.transpose();
    }
    let y = &mut data.tmp[..n];
    y.copy_from_slice(u);
    dense::solve(d, n, y);
    let mut pa = pa;
    pa.lin += cc * c.lin;
    for j in 0..n {
        pa += u_col[j] * y[j];
    }
    let x = Transform::new(rot, chain.point);
    add_linear_inv_transform(&cc, &x, &mut data.ia[p], None);
    data.pa[p] += x.inv_apply_force(&pa);
    w.x = x;
    w.c = c;
    Ok(())
}

/// Pass 3 for folded chain `k` (tip with `m` modes): the hinges' and modes' accelerations
/// from the point's, `D⁻¹ (u − Uᵀ a′)`, then the links' and the tip's frames as in the tree
/// form.
#[inline(always)]
pub(super) fn outward(model: &FlexModel, data: &mut FlexData, k: usize, m: usize) {
    let rigid = &model.rigid;
    let chain = &rigid.chains[k];
    let (b, p, nv) = (&chain.order, chain.parent, rigid.nv());
    let n = 3 + m;
    let w = &data.chains[k];
    let a = w.x.apply_motion(&data.a[p]) + w.c;
    let y = &mut data.tmp[..n];
    for (j, yj) in y.iter_mut().enumerate() {
        *yj = w.u[j] - a.dot(&w.u_col[j]);
    }
    dense::solve(&w.d[..n * n], n, y);
    let o = model.offset[b[0]];
    let mut qdd = [0.0; 3];
    for (j, &yj) in y.iter().enumerate() {
        match column(j, m) {
            Ok(t) => qdd[t] = yj,
            Err(q) => data.ddq[nv + o + q] = yj,
        }
    }
    let mut parent = p;
    for t in (0..3).rev() {
        let i = b[t];
        data.ddq[chain.dof[t]] = qdd[t];
        let s = rigid.joints[i].as_ref().expect("joint").s;
        data.a[i] = apply_motion(model.frame_axis(i), &data.xup[i], &data.a[parent])
            + data.c[i]
            + s * qdd[t];
        parent = i;
    }
}
