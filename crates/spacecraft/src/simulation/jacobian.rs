//! A Jacobian brought to a new state through the mass matrix
//! ([`System::update_jacobian`]), in place of the finite differences' right-hand side a
//! column.
//!
//! The rows of `J = ∂f/∂x` of the tree's velocity states are its accelerations'
//! derivatives. With the coordinates `F` free (the locked ones held at zero acceleration),
//! `M_FF a_F = τ_F − C_F`, so
//!
//! `B = M_FF J_F = ∂(τ − C)_F/∂x − (∂M/∂x a)_F`:
//!
//! the generalised forces' sensitivities. Springs, dampers and control laws keep them nearly
//! constant while the configuration, and with it `M`, moves (an array deploying, its strips
//! bending). At the new state `J_F' = M'_F'F'⁻¹ B_F'`, and a coordinate locked since has
//! rows of zeros, as the locked dynamics give it. The other rows (the kinematic ones, the
//! orbit's, the works') are kept as they were. A coordinate released since has no row of `B`
//! to start from: the Jacobian is then evaluated anew.
//!
//! Two mass matrices and an `|F| × |F|` Cholesky factorisation with `n` right-hand sides
//! cost about what two or three right-hand sides do, where a Jacobian by differences takes
//! one right-hand side per state (47 on the flexible deployment). Radau IIA uses the update
//! where its Newton iteration asks for a fresher Jacobian, and evaluates one where an updated
//! one failed it or two updates followed each other (`satsim_integrate`'s `radau5.rs`).
//!
//! Only trees with flexible bodies take it: their modal stiffness and damping, constant,
//! dominate `B`. On the flexible deployment a second of panel 2's swing moves the velocity
//! rows of the differenced Jacobian by 2.6e-2 (scaled as the integrator scales its errors),
//! the updated one is 1.2e-3 from it (`crates/tools/tests/it/jacobian_update.rs`). On the
//! rigid deployment the panels' Coriolis and inertial terms change `B` as much as `M`: over
//! 2 s to 2.5 s the updated Jacobian is no nearer than the one kept (1.37e-5 against
//! 1.35e-5), and a rigid tree's Jacobian is evaluated anew.
//!
//! [`System::update_jacobian`]: satsim_integrate::System::update_jacobian

use super::Simulation;
use super::model::SimModel;
use super::rhs::unpack_positions;
use satsim_integrate::SystemError;
use satsim_tree::DynamicsError;
use satsim_tree::flexible::{self, FlexData, FlexModel};

/// The workspace of the updates, made at the first (a mass matrix's transforms and
/// composite inertias, the coordinates, `M` at the Jacobian's state, `B`, `M'_F'F'`).
pub(super) struct JacobianUpdate {
    data: FlexData,
    q: Vec<f64>,
    /// Each tree coordinate's state row, and whether it was free where the Jacobian stands
    /// (its row not all zero) and is now.
    row: Vec<usize>,
    free_then: Vec<usize>,
    free_now: Vec<usize>,
    b: Vec<f64>,
    l: Vec<f64>,
}

impl JacobianUpdate {
    fn new(m: &SimModel, f: &FlexModel) -> Self {
        let (n, nt) = (m.layout.len, f.nv());
        Self {
            data: FlexData::new(f),
            q: f.neutral(),
            row: (0..nt).map(|k| state_row(m, k)).collect(),
            free_then: Vec::with_capacity(nt),
            free_now: Vec::with_capacity(nt),
            b: vec![0.0; nt * n],
            l: vec![0.0; nt * nt],
        }
    }
}

/// The state row of the tree coordinate `k`'s velocity (`StateLayout`; `rhs.rs` packs the
/// accelerations the same way).
fn state_row(m: &SimModel, k: usize) -> usize {
    let (l, nb, nu) = (&m.layout, m.tree.base_nv(), m.n_user);
    let nv = m.tree.nv();
    if k < nb + nu {
        if l.free {
            l.omega.start + k
        } else {
            l.rates.start + k
        }
    } else if k < nv {
        let i = m
            .rotor_effect
            .expect("the rotors' coordinates come with their effect");
        m.own[i].start + (k - nb - nu)
    } else {
        l.etadot.start + (k - nv)
    }
}

impl Simulation {
    /// [`System::update_jacobian`](satsim_integrate::System::update_jacobian): `jac`, the
    /// Jacobian at `x0`, brought to `x` (this module's page); false for a rigid tree, where a
    /// coordinate was released since, or where the free block of `M` is not positive
    /// definite.
    pub(super) fn jacobian_update(
        &mut self,
        x0: &[f64],
        x: &[f64],
        jac: &mut [f64],
    ) -> Result<bool, SystemError> {
        let (m, d) = (&self.model, &mut self.data);
        let Some(f) = &m.flex else {
            return Ok(false);
        };
        let n = m.layout.len;
        let (nb, nv, nt) = (m.tree.base_nv(), m.tree.nv(), f.nv());
        let u = d
            .jac_update
            .get_or_insert_with(|| Box::new(JacobianUpdate::new(m, f)));
        u.free_then.clear();
        u.free_now.clear();
        for k in 0..nt {
            let r = u.row[k];
            let was = jac[r * n..(r + 1) * n].iter().any(|&v| v != 0.0);
            let is = k < nb || k >= nv || !d.locked[k - nb];
            if is && !was {
                return Ok(false);
            }
            if was {
                u.free_then.push(k);
            }
            if is {
                u.free_now.push(k);
            }
        }
        let err = |e: DynamicsError| SystemError::new(format!("the Jacobian's update: {e}"));
        // M at the Jacobian's state, then B = M_FF J_F, row by row.
        positions(m, &d.q, x0, &mut u.q);
        let mass = flexible::crba(f, &mut u.data, &u.q).map_err(err)?;
        for &i in &u.free_then {
            let bi = &mut u.b[i * n..(i + 1) * n];
            bi.fill(0.0);
            for &k in &u.free_then {
                let mik = mass[(i, k)];
                if mik != 0.0 {
                    let r = u.row[k];
                    for (b, j) in bi.iter_mut().zip(&jac[r * n..(r + 1) * n]) {
                        *b += mik * j;
                    }
                }
            }
        }
        // M' at the new state: its free block factored, `L Lᵀ` (row-major, lower).
        positions(m, &d.q, x, &mut u.q);
        let mass = flexible::crba(f, &mut u.data, &u.q).map_err(err)?;
        let nf = u.free_now.len();
        for (a, &i) in u.free_now.iter().enumerate() {
            for (c, &k) in u.free_now.iter().enumerate().take(a + 1) {
                u.l[a * nf + c] = mass[(i, k)];
            }
        }
        if !cholesky(&mut u.l[..nf * nf], nf) {
            return Ok(false);
        }
        // The coordinates locked now, then J_F' = L⁻ᵀ L⁻¹ B_F', into J's rows in place.
        for k in 0..nt {
            if k >= nb && k < nv && d.locked[k - nb] {
                let r = u.row[k];
                jac[r * n..(r + 1) * n].fill(0.0);
            }
        }
        // Forward and back substitution on B's rows in place (the free coordinates ascend).
        let (l, b, free) = (&u.l, &mut u.b, &u.free_now);
        for a in 0..nf {
            let (done, rest) = b.split_at_mut(free[a] * n);
            let ya = &mut rest[..n];
            for c in 0..a {
                let yc = &done[free[c] * n..(free[c] + 1) * n];
                axpy(ya, -l[a * nf + c], yc);
            }
            let inv = 1.0 / l[a * nf + a];
            ya.iter_mut().for_each(|y| *y *= inv);
        }
        for a in (0..nf).rev() {
            let (head, later) = b.split_at_mut((free[a] + 1) * n);
            let xa = &mut head[free[a] * n..];
            for c in a + 1..nf {
                let at = (free[c] - free[a] - 1) * n;
                axpy(xa, -l[c * nf + a], &later[at..at + n]);
            }
            let inv = 1.0 / l[a * nf + a];
            xa.iter_mut().for_each(|y| *y *= inv);
            let r = u.row[free[a]];
            jac[r * n..(r + 1) * n].copy_from_slice(xa);
        }
        Ok(true)
    }
}

/// The flexible tree's coordinates at state `x` into `q`: the rigid ones as the right-hand
/// side unpacks them ([`unpack_positions`], over `template`'s, the rotors' angles), then `η`.
fn positions(m: &SimModel, template: &[f64], x: &[f64], q: &mut [f64]) {
    let nq = template.len();
    q[..nq].copy_from_slice(template);
    unpack_positions(m, x, &mut q[..nq]);
    q[nq..].copy_from_slice(&x[m.layout.eta.clone()]);
}

/// `y += a x`.
fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += a * x;
    }
}

/// `A = L Lᵀ` in place (`a`: `n × n` row-major, its lower triangle read and overwritten by
/// `L`); false where `A` is not positive definite.
fn cholesky(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let s = a[j * n + j] - a[j * n..j * n + j].iter().map(|x| x * x).sum::<f64>();
        // NaN too: not positive definite.
        if s.is_nan() || s <= 0.0 {
            return false;
        }
        let ljj = s.sqrt();
        a[j * n + j] = ljj;
        for i in j + 1..n {
            let dot: f64 = (0..j).map(|k| a[i * n + k] * a[j * n + k]).sum();
            a[i * n + j] = (a[i * n + j] - dot) / ljj;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::cholesky;

    #[test]
    fn cholesky_factors_and_refuses_an_indefinite_matrix() {
        let mut a = vec![4.0, 0.0, 0.0, 2.0, 5.0, 0.0, -2.0, 1.0, 6.0];
        assert!(cholesky(&mut a, 3));
        let l = |i: usize, j: usize| if j <= i { a[i * 3 + j] } else { 0.0 };
        let full = [[4.0, 2.0, -2.0], [2.0, 5.0, 1.0], [-2.0, 1.0, 6.0]];
        for (i, row) in full.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                let llt: f64 = (0..3).map(|k| l(i, k) * l(j, k)).sum();
                assert!((llt - v).abs() < 1e-14, "({i}, {j}): {llt} against {v}");
            }
        }
        let mut b = vec![1.0, 0.0, 2.0, 1.0];
        assert!(!cholesky(&mut b, 2));
    }
}
