//! What events do to the state: momentum-conserving impulses, the energy booked at a jump.

use super::{SimError, Simulation};
use nalgebra::{DMatrix, DVector};
use satsim_integrate::SystemError;
use satsim_tree::crba;

impl Simulation {
    /// Index in `x` of tree hinge `h`'s rate.
    pub(super) fn rate_index(&self, h: usize) -> usize {
        match self.rotor_effect {
            Some(i) if h >= self.n_user => self.own[i].start + (h - self.n_user),
            _ => self.layout.rates.start + h,
        }
    }

    /// One momentum-conserving impulse solve that sets each hinge `h` of `targets` to its
    /// rate: impulses `λ_j` between each target hinge's two bodies, over the free degrees of
    /// freedom (base, unlocked hinges and the targets; other locked hinges stay rigid):
    /// `Δv = M_ff⁻¹ E λ` with `(Eᵀ M_ff⁻¹ E) λ = target − v_E`. Simultaneous impacts are
    /// thus resolved together, symmetric ones symmetrically.
    pub(super) fn impulses(
        &mut self,
        targets: &[(usize, f64)],
        x: &mut [f64],
    ) -> Result<(), SimError> {
        self.unpack(x);
        crba(&self.model, &mut self.data, &self.q)?;
        let nb = self.model.base_nv();
        let nv = self.model.nv();
        let is_target = |d: usize| d >= nb && targets.iter().any(|&(h, _)| h == d - nb);
        let free: Vec<usize> = (0..nv)
            .filter(|&d| d < nb || is_target(d) || !self.locked[d - nb])
            .collect();
        let m = DMatrix::from_fn(free.len(), free.len(), |r, c| {
            self.data.mass_matrix[(free[r], free[c])]
        });
        let singular = || SimError::State("singular mass matrix at an impact".into());
        let chol = m.cholesky().ok_or_else(singular)?;
        // Positions of the targets among the free dofs.
        let pos: Vec<usize> = targets
            .iter()
            .map(|&(h, _)| free.iter().position(|&d| d == nb + h).unwrap_or(0))
            .collect();
        let mut e = DMatrix::zeros(free.len(), targets.len());
        for (j, &p) in pos.iter().enumerate() {
            e[(p, j)] = 1.0;
        }
        let col = chol.solve(&e);
        let a = DMatrix::from_fn(targets.len(), targets.len(), |r, c| col[(pos[r], c)]);
        let b = DVector::from_fn(targets.len(), |r, _| {
            targets[r].1 - x[self.rate_index(targets[r].0)]
        });
        let lambda = a.cholesky().ok_or_else(singular)?.solve(&b);
        let dv = &col * &lambda;
        if !dv.iter().all(|v| v.is_finite()) {
            return Err(SimError::State(
                "an impact produced non-finite velocities".into(),
            ));
        }
        for (c, &d) in free.iter().enumerate() {
            let idx = if d < nb {
                if d < 3 {
                    self.layout.omega.start + d
                } else {
                    self.layout.velocity.start + d - 3
                }
            } else {
                self.rate_index(d - nb)
            };
            x[idx] += dv[c];
        }
        for &(h, target) in targets {
            x[self.rate_index(h)] = target;
        }
        Ok(())
    }
}

impl Simulation {
    /// An error unless a state slice has the layout's length (`what` names the caller).
    pub(super) fn check_len(&self, got: usize, what: &str) -> Result<(), SystemError> {
        if got == self.layout.len {
            Ok(())
        } else {
            Err(SystemError::new(format!(
                "{what}: state has length {got}, expected {}",
                self.layout.len
            )))
        }
    }

    /// `T + V` at `(t, x)` (0 when the energy budget is not tracked).
    pub(super) fn mechanical_energy(&mut self, t: f64, x: &[f64]) -> Result<f64, SystemError> {
        if self.work.is_empty() {
            return Ok(0.0);
        }
        let d = self.diagnostics(t, x)?;
        Ok(d.kinetic + d.potential)
    }

    /// Books the jump of `T + V` from `before` to its value at `(t, x)` (an impact's
    /// impulse, an effect's own reset) into the energy budget's states: a loss as
    /// dissipated, a gain as actuator work.
    pub(super) fn book_jump(
        &mut self,
        t: f64,
        x: &mut [f64],
        before: f64,
    ) -> Result<(), SystemError> {
        if self.work.is_empty() {
            return Ok(());
        }
        let jump = self.mechanical_energy(t, x)? - before;
        if jump < 0.0 {
            x[self.work.start + 1] -= jump;
        } else {
            x[self.work.start] += jump;
        }
        Ok(())
    }

    pub(super) fn event_owner(&self, k: usize) -> usize {
        (0..self.effects.len())
            .rev()
            .find(|&i| self.event_start[i] <= k && self.effects[i].n_events() > 0)
            .unwrap_or(0)
    }
}
