//! What events do to the state: momentum-conserving impulses, the energy booked at a jump.

use super::hold::Hold;
use super::{SimError, SimModel, Simulation};
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

    /// The effects' event functions into `g`, on the context of `(t, x)` that
    /// [`Self::prepare_events`] (or the slope's preparation) made; `kin`: the poses are
    /// current.
    pub(super) fn effects_events(&mut self, t: f64, x: &[f64], kin: bool, g: &mut [f64]) {
        self.with_context(t, x, kin, |ctx, h| {
            for (i, (e, r)) in h.effects.iter().zip(h.own).enumerate() {
                let s = h.event_start[i];
                e.events(ctx, h.forces, &x[r.clone()], &mut g[s..s + e.n_events()]);
            }
        });
    }

    /// What the event functions read (the union of the effects' [`Effect::event_reads`]).
    ///
    /// [`Effect::event_reads`]: crate::effects::Effect::event_reads
    pub(super) fn event_reads(&self) -> EventReads {
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
        // The buffers are reserved when the simulation is built: no allocation here.
        let mut targets = std::mem::take(&mut self.data.impulse.targets);
        let mut locks = std::mem::take(&mut self.data.impulse.locks);
        targets.clear();
        locks.clear();
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
        let solved = if targets.is_empty() {
            Ok(())
        } else {
            self.impulses(&targets, x)
        };
        if solved.is_ok() {
            for &h in &locks {
                if !self.data.locked[h] {
                    self.data.locked[h] = true;
                    self.data.n_locked += 1;
                    self.data.newly_locked = true;
                }
            }
        }
        self.data.impulse.targets = targets;
        self.data.impulse.locks = locks;
        solved
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
        let locked = &self.data.locked;
        let is_target = |d: usize| d >= nb && targets.iter().any(|&(h, _)| h == d - nb);
        // The matrices live in `data.impulse`'s storage, lent to nalgebra as `DMatrix`es of
        // the size at hand and taken back: handling an event allocates nothing (the values
        // and the operations are those of fresh matrices, so the same bits).
        let w = &mut self.data.impulse;
        w.free.clear();
        w.free.extend(
            (0..mass.nrows()).filter(|&d| d < nb || d >= nv || is_target(d) || !locked[d - nb]),
        );
        let (nf, nt) = (w.free.len(), targets.len());
        let free = &w.free;
        let mut m = std::mem::take(&mut w.m);
        m.clear();
        // Column-major, as `DMatrix::from_vec` reads it.
        m.extend((0..nf * nf).map(|i| mass[(free[i % nf], free[i / nf])]));
        let singular = || SimError::State("singular mass matrix at an impact".into());
        let chol = DMatrix::from_vec(nf, nf, m)
            .cholesky()
            .ok_or_else(singular)?;
        // Positions of the targets among the free dofs.
        w.pos.clear();
        w.pos.extend(
            targets
                .iter()
                .map(|&(h, _)| free.iter().position(|&d| d == nb + h).unwrap_or(0)),
        );
        let mut e = std::mem::take(&mut w.col);
        e.clear();
        e.resize(nf * nt, 0.0);
        for (j, &p) in w.pos.iter().enumerate() {
            e[j * nf + p] = 1.0;
        }
        let mut col = DMatrix::from_vec(nf, nt, e);
        chol.solve_mut(&mut col);
        w.m = chol.unpack().data.into();
        let mut a = std::mem::take(&mut w.a);
        a.clear();
        a.extend((0..nt * nt).map(|i| col[(w.pos[i % nt], i / nt)]));
        let mut b = std::mem::take(&mut w.b);
        b.clear();
        b.extend(
            targets
                .iter()
                .map(|&(h, rate)| rate - x[rate_index(&self.model, h)]),
        );
        let mut lambda = DVector::from_vec(b);
        let chol = DMatrix::from_vec(nt, nt, a)
            .cholesky()
            .ok_or_else(singular)?;
        chol.solve_mut(&mut lambda);
        w.a = chol.unpack().data.into();
        let mut dv = std::mem::take(&mut w.dv);
        dv.clear();
        dv.resize(nf, 0.0);
        let mut dv = DVector::from_vec(dv);
        col.mul_to(&lambda, &mut dv);
        w.col = col.data.into();
        w.b = lambda.data.into();
        let dv: Vec<f64> = dv.data.into();
        let finite = dv.iter().all(|v| v.is_finite());
        if finite {
            for (c, &d) in w.free.iter().enumerate() {
                let idx = if d >= nv {
                    self.model.layout.etadot.start + d - nv
                } else if d < nb {
                    if d < 3 {
                        self.model.layout.omega.start + d
                    } else {
                        self.model.layout.velocity.start + d - 3
                    }
                } else {
                    rate_index(&self.model, d - nb)
                };
                x[idx] += dv[c];
            }
            for &(h, target) in targets {
                x[rate_index(&self.model, h)] = target;
            }
        }
        w.dv = dv;
        if finite {
            Ok(())
        } else {
            Err(SimError::State(
                "an impact produced non-finite velocities".into(),
            ))
        }
    }
}

/// Index in `x` of tree hinge `h`'s rate ([`Simulation::rate_index`], from the model alone).
fn rate_index(model: &SimModel, h: usize) -> usize {
    match model.rotor_effect {
        Some(i) if h >= model.n_user => model.own[i].start + (h - model.n_user),
        _ => model.layout.rates.start + h,
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
