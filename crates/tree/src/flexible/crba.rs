//! The mass matrix of a tree with flexible bodies (CRBA extended by the modal columns).

use super::data::{FlexData, check_state, velocities};
use super::model::FlexModel;
use crate::error::DynamicsError;
use crate::model::BaseKind;
use crate::spatial::Force;
use nalgebra::DMatrix;

/// Computes `M(q)` into `data.mass_matrix` (full, symmetric) and returns it.
///
/// Composite inertias `Icᵢ` as in the rigid CRBA, through the deformed transforms. Each
/// coordinate is a column of momentum `F` held at a body `j`: a hinge's `Icⱼ Sⱼ`; a mode `k`
/// of body `j`, `Pₖ + Σ_children Xupᵀ Ic_c G_c,k` (the body's own modal momentum and its
/// subtrees carried by the node). Walking up, each ancestor hinge takes `Sᵀ F`, each
/// flexible ancestor's mode the node column `G_c,kᵀ F` of the child `c` on the path, the
/// free base `F`. A body's mode-mode block is `1 + Σ_children G_cᵀ Ic_c G_c`.
pub fn crba<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
) -> Result<&'d DMatrix<f64>, DynamicsError> {
    // The transforms and node subspaces do not depend on v: any v of the right length.
    data.ddq.fill(0.0);
    let zero = std::mem::take(&mut data.ddq);
    let checked = check_state(model, q, zero.as_slice());
    if checked.is_ok() {
        velocities(model, data, q, zero.as_slice());
    }
    data.ddq = zero;
    checked?;
    mass_matrix(model, data, q);
    Ok(&data.mass_matrix)
}

/// Writes column `col` (momentum `f` held at body `j`) into the rows of `j`'s hinge (or the
/// free base) and of every ancestor coordinate, and their mirror entries.
fn walk(model: &FlexModel, data: &FlexData, m: &mut DMatrix<f64>, col: usize, j: usize, f: Force) {
    let rigid = &model.rigid;
    let nv = rigid.nv();
    let (mut f, mut j) = (f, j);
    loop {
        match &rigid.joints[j] {
            Some(jj) => {
                let x = jj.s.dot(&f);
                if jj.dof != col {
                    m[(jj.dof, col)] = x;
                    m[(col, jj.dof)] = x;
                }
            }
            None if rigid.base == BaseKind::Free => {
                let v = [f.ang.x, f.ang.y, f.ang.z, f.lin.x, f.lin.y, f.lin.z];
                for (r, x) in v.into_iter().enumerate() {
                    m[(r, col)] = x;
                    m[(col, r)] = x;
                }
            }
            None => {}
        }
        let Some(p) = rigid.parent[j] else { break };
        let (op, mp) = (model.offset[p], model.modes[p]);
        for (k, g) in data.g[data.g_offset[j]..][..mp].iter().enumerate() {
            let x = g.dot(&f);
            m[(nv + op + k, col)] = x;
            m[(col, nv + op + k)] = x;
        }
        f = data.xup[j].inv_apply_force(&f);
        j = p;
    }
}

fn mass_matrix(model: &FlexModel, data: &mut FlexData, q: &[f64]) {
    let rigid = &model.rigid;
    let n = rigid.n_bodies();
    let nv = rigid.nv();
    for i in 0..n {
        data.ic[i] = data.inertia[i];
    }
    for i in (1..n).rev() {
        let p = rigid.parent[i].expect("parent");
        let moved = data.ic[i].inv_transform(&data.xup[i]);
        data.ic[p] += moved;
    }
    // Out of `data` while it is written (an empty matrix allocates nothing).
    let mut m = std::mem::replace(&mut data.mass_matrix, DMatrix::zeros(0, 0));
    for i in 1..n {
        let ji = rigid.joints[i].as_ref().expect("joint");
        let f = data.ic[i].mul_motion(&ji.s);
        m[(ji.dof, ji.dof)] = ji.s.dot(&f) + ji.armature();
        walk(model, data, &mut m, ji.dof, i, f);
    }
    for j in 0..n {
        let (o, mj) = (model.offset[j], model.modes[j]);
        if mj == 0 {
            continue;
        }
        // The modal columns of body j: its own momentum plus its children's subtrees.
        for k in 0..mj {
            data.cols[k] = model.momentum_at(j, q, k);
            for r in 0..mj {
                m[(nv + o + r, nv + o + k)] = if r == k { 1.0 } else { 0.0 };
            }
        }
        for &c in &model.children[j] {
            let off = data.g_offset[c];
            for k in 0..mj {
                let h = data.ic[c].mul_motion(&data.g[off + k]);
                let moved = data.xup[c].inv_apply_force(&h);
                data.cols[k] += moved;
                // The upper triangle, mirrored: M exactly symmetric.
                for r in 0..=k {
                    let x = data.g[off + r].dot(&h);
                    m[(nv + o + r, nv + o + k)] += x;
                    if r != k {
                        m[(nv + o + k, nv + o + r)] += x;
                    }
                }
            }
        }
        for k in 0..mj {
            let f = data.cols[k];
            walk(model, data, &mut m, nv + o + k, j, f);
        }
    }
    if rigid.base == BaseKind::Free {
        let m6 = data.ic[0].to_matrix();
        m.fixed_view_mut::<6, 6>(0, 0).copy_from(&m6);
    }
    data.mass_matrix = m;
}
