//! [`Simulation`] as a [`System`] for the integrators: the right-hand side, the quaternion's
//! projection, the event functions and the handling of their crossings.

use super::Simulation;
use super::rhs::{Hold, kernel_for};
use crate::effects::Power;
use satsim_integrate::{EventAction, EventDirection, System, SystemError};
use satsim_tree::{
    aba, aba_hybrid, aba_hybrid_with_kinematics, aba_with_kinematics, forward_kinematics,
};

impl System for Simulation {
    fn dim(&self) -> usize {
        self.layout.len
    }

    /// `dx = f(t, x)`; slices of the wrong length are an error, not a panic.
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.check_len(x.len(), "rhs")?;
        self.check_len(dx.len(), "rhs (derivative)")?;
        self.rhs_evals += 1;
        self.unpack(x);
        if self.needs_kinematics {
            forward_kinematics(&self.model, &mut self.data, &self.q, &self.v)
                .map_err(|e| SystemError::new(e.to_string()))?;
        }
        let kin = self.needs_kinematics;
        let track = !self.work.is_empty();
        let nb = self.model.base_nv();
        let power = self.with_context(t, x, kin, |ctx, h| {
            h.forces.reset_to(h.base_tau);
            // Energy budget: the constant torques are an actuator's; each effect's forces
            // are measured by the change of the total power it makes.
            let mut hinges = if track {
                h.forces.hinge_power(ctx.v, nb)
            } else {
                0.0
            };
            let (mut wrenches, mut added) = (0.0, 0);
            let mut power = Power::actuator(hinges);
            for ((e, r), c) in h.effects.iter_mut().zip(h.own).zip(h.calls.iter_mut()) {
                *c += 1;
                e.apply(ctx, h.forces, &x[r.clone()], &mut dx[r.clone()])?;
                if track {
                    let now = h.forces.hinge_power(ctx.v, nb);
                    let mut applied = now - hinges;
                    hinges = now;
                    if h.forces.wrenches_added() != added {
                        added = h.forces.wrenches_added();
                        let now = h.forces.wrench_power(&ctx.data.v);
                        applied += now - wrenches;
                        wrenches = now;
                    }
                    let p = e.power(ctx, &x[r.clone()], applied);
                    power.actuator += p.actuator;
                    power.dissipated += p.dissipated;
                }
            }
            Ok::<Power, SystemError>(power)
        })?;
        if track && !kin && self.forces.has_wrench {
            // A wrench's power needs the bodies' velocities: an effect wrote one without
            // asking for kinematics, so they are computed from now on (this evaluation again).
            self.needs_kinematics = true;
            self.rhs_evals -= 1;
            return self.rhs(t, x, dx);
        }
        if track {
            dx[self.work.start] = power.actuator;
            dx[self.work.start + 1] = power.dissipated;
        }
        self.tau[nb..].copy_from_slice(&self.forces.hinge_torque);
        let fext = if self.forces.has_wrench {
            Some(self.forces.body_wrench.as_slice())
        } else {
            None
        };
        // After kinematics `data.xup` holds this state's transforms (the effects only read
        // `data`): the generic ABA reuses them, with bit for bit the same result. The
        // unrolled kernel computes its own and writes only `q̈`, into `dx` or `data.ddq`
        // (nothing after this reads `data`'s other buffers that the generic ABA would have
        // written); it takes locked rotors and serial hinges, not a locked gimbal hinge.
        let locked = (self.n_locked > 0).then_some(self.locked.as_slice());
        let kernel = kernel_for(&self.unrolled, locked);
        let l = &self.layout;
        let n = self.n_user;
        if l.free {
            // x = [attitude, angles, ω, v, rates, ...] (`StateLayout`).
            let (a, w) = (&x[..4], &x[l.omega.start..l.omega.start + 3]);
            // q̇ = ½ q ⊗ (0, ω)
            let qd = crate::effects::quat_mul(&[a[0], a[1], a[2], a[3]], &[0.0, w[0], w[1], w[2]]);
            for (d, q) in dx[..4].iter_mut().zip(qd) {
                *d = 0.5 * q;
            }
        }
        dx[l.angles.clone()].copy_from_slice(&x[l.rates.clone()]);
        let (q, v, tau) = (&self.q, &self.v, &self.tau);
        if let (Some((k, locks)), Some(s)) = (kernel, self.velocity_at) {
            // The kernel writes `q̈` straight into the derivative of the velocity run.
            return k
                .aba_hybrid_with_forces_into(q, v, tau, fext, locks, &mut dx[s..s + v.len()])
                .map_err(|e| SystemError::new(e.to_string()));
        }
        let (model, data) = (&self.model, &mut self.data);
        let ddq = match (kernel, self.n_locked > 0, kin) {
            (Some((k, locks)), _, _) => k.aba_hybrid_with_forces(data, q, v, tau, fext, locks),
            (None, true, true) => {
                aba_hybrid_with_kinematics(model, data, q, v, tau, fext, &self.locked)
            }
            (None, true, false) => aba_hybrid(model, data, q, v, tau, fext, &self.locked),
            (None, false, true) => aba_with_kinematics(model, data, q, v, tau, fext),
            (None, false, false) => aba(model, data, q, v, tau, fext),
        }
        .map_err(|e| SystemError::new(e.to_string()))?;
        let ddq = ddq.as_slice();
        if let Some(s) = self.velocity_at {
            // `q̈` in the velocity vector's order is the derivative of that run: one copy.
            dx[s..s + ddq.len()].copy_from_slice(ddq);
            return Ok(());
        }
        if l.free {
            dx[l.omega.start..l.omega.start + 6 + n].copy_from_slice(&ddq[..6 + n]);
        } else {
            dx[l.rates.clone()].copy_from_slice(&ddq[..n]);
        }
        if let Some(i) = self.rotor_effect {
            let r = self.own[i].clone();
            dx[r].copy_from_slice(&ddq[nb + n..nb + n + self.n_rotors]);
        }
        Ok(())
    }

    /// The energy budget's work states are bookkeeping: they stay out of the error control,
    /// so that tracking them leaves the steps (and every other state) as they were.
    fn error_weights(&self, w: &mut [f64]) {
        w.fill(1.0);
        w[self.work.clone()].fill(0.0);
    }

    fn project(&mut self, x: &mut [f64]) {
        if self.layout.free {
            let a = self.layout.attitude.clone();
            let norm = x[a.clone()].iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > 0.0 {
                for v in &mut x[a] {
                    *v /= norm;
                }
            }
        }
    }

    fn n_events(&self) -> usize {
        self.n_events
    }

    /// The effects' event functions, computing first only what they read
    /// ([`Effect::event_reads`](crate::effects::Effect::event_reads)). A state on which the
    /// effects or the hold torques cannot be evaluated is an error (an event is never
    /// skipped silently).
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        if self.n_events == 0 {
            return Ok(());
        }
        self.check_len(x.len(), "events")?;
        if g.len() != self.n_events {
            return Err(SystemError::new(format!(
                "events: g has length {} but the simulation has {} event functions",
                g.len(),
                self.n_events
            )));
        }
        let kin = self.prepare_events(t, x)?;
        self.with_context(t, x, kin, |ctx, h| {
            for (i, (e, r)) in h.effects.iter().zip(h.own).enumerate() {
                let s = h.event_start[i];
                e.events(ctx, h.forces, &x[r.clone()], &mut g[s..s + e.n_events()]);
            }
        });
        Ok(())
    }

    fn event_direction(&self, k: usize) -> EventDirection {
        let i = self.event_owner(k);
        self.effects[i].event_direction(k - self.event_start[i])
    }

    fn on_event(&mut self, k: usize, t: f64, x: &mut [f64]) -> EventAction {
        match self.on_events(&[k], t, x) {
            Ok(a) => a,
            Err(_) => EventAction::Stop,
        }
    }

    /// Handles simultaneous events together: every owning effect's `on_event` sees the same
    /// state (the one at the event), then all their requests are carried out at once, with
    /// one impulse solve for all the impacts (see `Simulation::apply_requests`), so that a
    /// symmetric pair of impacts stays symmetric to round-off.
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        self.check_len(x.len(), "on_events")?;
        let before = self.mechanical_energy(t, x)?;
        if let Err(e) = self.prepare_with(t, x, false, Hold::All) {
            let why = format!("event handling failed: {e}");
            self.log.push((t, why.clone()));
            self.log_effect
                .push(ks.first().map_or(0, |&k| self.event_owner(k)));
            return Err(SystemError::new(why));
        }
        let kin = self.needs_kinematics;
        let mut action = EventAction::Continue;
        let mut own_state = Vec::new();
        for &k in ks {
            let i = self.event_owner(k);
            let local = k - self.event_start[i];
            let r = self.own[i].clone();
            own_state.clear();
            own_state.extend_from_slice(&x[r.clone()]);
            let a = self.with_context(t, x, kin, |ctx, h| {
                h.effects[i].on_event(local, ctx, h.forces, &mut own_state, h.requests)
            });
            x[r].copy_from_slice(&own_state);
            action = action.combine(a);
            let what = self.effects[i].describe_event(local);
            if !what.is_empty() {
                self.log.push((t, what));
                self.log_effect.push(i);
            }
        }
        let reqs = std::mem::take(&mut self.requests);
        let changed = !reqs.is_empty();
        let result = self.apply_requests(&reqs, x);
        self.requests = reqs;
        self.requests.clear();
        if let Err(e) = result {
            let why = format!("impact failed: {e}");
            self.log.push((t, why.clone()));
            self.log_effect
                .push(ks.first().map_or(0, |&k| self.event_owner(k)));
            return Err(SystemError::new(why));
        }
        self.book_jump(t, x, before)?;
        Ok(if changed {
            action.combine(EventAction::Reset)
        } else {
            action
        })
    }
}
