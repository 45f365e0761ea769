//! What events do to the state: momentum-conserving impulses, the energy booked at a jump.

use super::hold::Hold;
use super::{SimError, Simulation};
use crate::effects::{EventReads, Request};
use nalgebra::{DMatrix, DVector};
use satsim_integrate::SystemError;
use satsim_tree::{crba, flexible};

impl Simulation {
    /// Before the event functions: what they read, and no more (the union of the
    /// effects' [`Effect::event_reads`]). Returns whether they read the poses (which are
    /// then current).
    pub(super) fn prepare_events(&mut self, t: f64, x: &[f64]) -> Result<bool, SystemError> {
        let wrap = |e: SystemError| SystemError::new(format!("event functions: {e}"));
        if let Some(reads) = self.event_reads_ahead() {
            // The hold torques' solve is the right-hand side's: evaluate that, and keep it
            // for the next step (`ahead.rs`).
            self.evaluate_ahead(t, x).map_err(wrap)?;
            return Ok(reads.kinematics);
        }
        let reads = self.event_reads();
        let hold = reads.hold_torques && self.model.needs_hold && self.data.n_locked > 0;
        if reads.forces || hold {
            let h = if hold { Hold::Locked } else { Hold::None };
            self.prepare_with(t, x, reads.kinematics, h).map_err(wrap)?;
            return Ok(reads.kinematics);
        }
        self.unpack(x);
        self.data.hold.fill(f64::NAN);
        if reads.kinematics {
            self.kinematics(true).map_err(wrap)?;
        }
        Ok(reads.kinematics)
    }

    /// What the event functions read (the union of the effects' [`Effect::event_reads`]).
    ///
    /// [`Effect::event_reads`]: crate::effects::Effect::event_reads
    fn event_reads(&self) -> EventReads {
        self.effects
            .iter()
            .filter(|e| e.n_events() > 0)
            .fold(EventReads::STATE, |r, e| r.union(e.event_reads()))
    }

    /// What the event functions read, where they take the hold torques from the
    /// right-hand side evaluated ahead (`ahead.rs`); `None` where they do not.
    pub(super) fn event_reads_ahead(&self) -> Option<EventReads> {
        let reads = self.event_reads();
        let hold = reads.hold_torques && self.model.needs_hold && self.data.n_locked > 0;
        (hold && self.can_evaluate_ahead(reads.kinematics)).then_some(reads)
    }

    /// Carries out requests made together (at one event instant, or at the start) on the
    /// state `x`: unlocks first, then one momentum-conserving impulse solve for every hinge
    /// whose rate must change (a `Lock` wants rate 0, a `Hold` or a `SetRate` its rate; a
    /// `Lock` or `Hold` wins over a `SetRate` of the same hinge), then the locks.
    pub(crate) fn apply_requests(
        &mut self,
        reqs: &[Request],
        x: &mut [f64],
    ) -> Result<(), SimError> {
        self.forget_ahead();
        let mut targets: Vec<(usize, f64)> = Vec::new();
        let mut locks: Vec<usize> = Vec::new();
        for r in reqs {
            match *r {
                Request::Unlock(h) => {
                    if self.data.locked[h] {
                        self.data.locked[h] = false;
                        self.data.n_locked -= 1;
                    }
                }
                Request::Lock(h) => {
                    locks.push(h);
                    targets.retain(|&(g, _)| g != h);
                    targets.push((h, 0.0));
                }
                Request::Hold { hinge, rate } => {
                    locks.push(hinge);
                    targets.retain(|&(g, _)| g != hinge);
                    targets.push((hinge, rate));
                }
                Request::SetRate { hinge, rate } => {
                    if !locks.contains(&hinge) {
                        targets.retain(|&(g, _)| g != hinge);
                        targets.push((hinge, rate));
                    }
                }
            }
        }
        if !targets.is_empty() {
            self.impulses(&targets, x)?;
        }
        for h in locks {
            if !self.data.locked[h] {
                self.data.locked[h] = true;
                self.data.n_locked += 1;
            }
        }
        Ok(())
    }

    /// Index in `x` of tree hinge `h`'s rate.
    pub(super) fn rate_index(&self, h: usize) -> usize {
        match self.model.rotor_effect {
            Some(i) if h >= self.model.n_user => self.model.own[i].start + (h - self.model.n_user),
            _ => self.model.layout.rates.start + h,
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
        // The flexible tree's mass matrix has the modes after the rigid coordinates: they
        // are always free (an impact excites them).
        let mass = match (&self.model.flex, &mut self.data.flex) {
            (Some(f), Some(w)) => flexible::crba(f, &mut w.data, &w.q)?,
            _ => crba(&self.model.tree, &mut self.data.tree, &self.data.q)?,
        };
        let nb = self.model.tree.base_nv();
        let nv = self.model.tree.nv();
        let is_target = |d: usize| d >= nb && targets.iter().any(|&(h, _)| h == d - nb);
        let free: Vec<usize> = (0..mass.nrows())
            .filter(|&d| d < nb || d >= nv || is_target(d) || !self.data.locked[d - nb])
            .collect();
        let m = DMatrix::from_fn(free.len(), free.len(), |r, c| mass[(free[r], free[c])]);
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
            let idx = if d >= nv {
                self.model.layout.etadot.start + d - nv
            } else if d < nb {
                if d < 3 {
                    self.model.layout.omega.start + d
                } else {
                    self.model.layout.velocity.start + d - 3
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
    /// Inlined: the right-hand side makes two at every call; the error is built apart.
    #[inline]
    pub(super) fn check_len(&self, got: usize, what: &str) -> Result<(), SystemError> {
        if got == self.model.layout.len {
            Ok(())
        } else {
            Err(self.len_error(got, what))
        }
    }

    #[cold]
    #[inline(never)]
    fn len_error(&self, got: usize, what: &str) -> SystemError {
        SystemError::new(format!(
            "{what}: state has length {got}, expected {}",
            self.model.layout.len
        ))
    }

    /// `T + V` at `(t, x)` (0 when the energy budget is not tracked).
    pub(super) fn mechanical_energy(&mut self, t: f64, x: &[f64]) -> Result<f64, SystemError> {
        if self.model.work.is_empty() {
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
        if self.model.work.is_empty() {
            return Ok(());
        }
        let jump = self.mechanical_energy(t, x)? - before;
        if jump < 0.0 {
            x[self.model.work.start + 1] -= jump;
        } else {
            x[self.model.work.start] += jump;
        }
        Ok(())
    }

    /// The effect that owns event function `k` (from the table made when it was built).
    pub(super) fn event_owner(&self, k: usize) -> usize {
        self.model.event_owner.get(k).copied().unwrap_or(0)
    }
}
