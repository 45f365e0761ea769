//! `S` and `N` of equation (19) from the generic engine.
//!
//! The engine's free-base equations are `M a + b = τ` in `v = [ω, u, φ̇]` (root angular
//! velocity, velocity of the root ORIGIN, both root axes; hinge rates), with
//! `b = C(q, v) − Jᵀ f_ext`. Split the coordinates into `r = (ω, φ̇)` (the preprint's
//! `(ω1, ψ)`) and `l = u`. The three linear rows say `M_lr a_r + M_ll a_l + b_l = τ_l`;
//! solving them for `a_l` and substituting into the other rows gives
//!
//! `S a_r = N` with `S = M_rr − M_rl M_ll⁻¹ M_lr` (the Schur complement of `M_ll`) and
//! `N = τ_r − b_r − M_rl M_ll⁻¹ (τ_l − b_l)`.
//!
//! Why this is the preprint's `S`: the kinetic energy splits (König) into
//! `T = ½ m |ṙ_O|² + T_rel(q; ω1, ψ)`, where `ṙ_O` is the centre-of-mass velocity, affine in
//! `u` with an invertible coefficient. Minimising `T` over `u` (which is what the Schur
//! complement of a quadratic form does) sets `ṙ_O = 0` and leaves `T_rel`, the energy of the
//! motion relative to the centre of mass; its matrix is the preprint's `S`, which the
//! preprint obtains by substituting the centre of mass `r_O` (13) for `r_O1` and dropping
//! the translational equation (4)/(17). The elimination is exact for any root velocity `u`:
//! the relative motion does not depend on the centre of mass's uniform motion.

use nalgebra::{DMatrix, DVector, Matrix3};
use satsim_tree::spatial::Force;
use satsim_tree::{Data, DynamicsError, Model, bias, crba};

/// Rows of `v` kept (`r`): the root's angular velocity and the hinges, in that order.
fn kept(model: &Model) -> Vec<usize> {
    (0..3).chain(6..model.nv()).collect()
}

/// `M_ll⁻¹`, the inverse of the linear-velocity block (`m·1` rotated, `m` the total mass).
/// Solved by Cholesky (no determinant, which underflows for tiny masses); a block that is not
/// positive definite (a massless tree) is [`DynamicsError::SingularBase`].
fn m_ll_inv(m: &DMatrix<f64>) -> Result<Matrix3<f64>, DynamicsError> {
    let m_ll: Matrix3<f64> = m.fixed_view::<3, 3>(3, 3).into_owned();
    let inv = m_ll
        .cholesky()
        .ok_or(DynamicsError::SingularBase)?
        .inverse();
    if inv.iter().all(|x| x.is_finite()) {
        Ok(inv)
    } else {
        Err(DynamicsError::SingularBase)
    }
}

/// `S_tree`: the Schur complement of the linear-velocity block of the free-base mass matrix,
/// `(3 + n) x (3 + n)`, rows `(ω, hinges in file order)`.
pub fn s_tree(model: &Model, data: &mut Data, q: &[f64]) -> Result<DMatrix<f64>, DynamicsError> {
    let m = crba(model, data, q)?.clone();
    schur(&m, &kept(model))
}

fn schur(m: &DMatrix<f64>, r: &[usize]) -> Result<DMatrix<f64>, DynamicsError> {
    let inv = m_ll_inv(m)?;
    let n = r.len();
    let m_rl = DMatrix::from_fn(n, 3, |i, j| m[(r[i], 3 + j)]);
    let m_rr = DMatrix::from_fn(n, n, |i, j| m[(r[i], r[j])]);
    let inv = DMatrix::from_fn(3, 3, |i, j| inv[(i, j)]);
    let s = &m_rr - &m_rl * inv * m_rl.transpose();
    // Symmetric in exact arithmetic.
    Ok((&s + s.transpose()) * 0.5)
}

/// `N_tree = τ_r − b_r − M_rl M_ll⁻¹ (τ_l − b_l)`, with `b` from the engine's RNEA (`bias`)
/// including the external forces `fext` (one per body, body coordinates, about the body
/// frame origin, acting on the body; external couples are `Force { ang: M_i, lin: 0 }`).
pub fn n_tree(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
) -> Result<DVector<f64>, DynamicsError> {
    if tau.len() != model.nv() {
        return Err(DynamicsError::Dimension {
            what: "tau",
            expected: model.nv(),
            got: tau.len(),
        });
    }
    let m = crba(model, data, q)?.clone();
    let b = bias(model, data, q, v, fext)?.clone();
    let r = kept(model);
    let inv = m_ll_inv(&m)?;
    let rhs_l = nalgebra::Vector3::new(tau[3] - b[3], tau[4] - b[4], tau[5] - b[5]);
    let y = inv * rhs_l;
    Ok(DVector::from_fn(r.len(), |i, _| {
        let k = r[i];
        tau[k] - b[k] - (m[(k, 3)] * y[0] + m[(k, 4)] * y[1] + m[(k, 5)] * y[2])
    }))
}
