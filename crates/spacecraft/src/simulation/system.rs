//! [`Simulation`] as a [`System`] for the integrators: the right-hand side (`rhs.rs`), the
//! quaternion's projection, the event functions and the handling of their crossings.

use super::Simulation;
use super::hold::Hold;
use satsim_integrate::{EventAction, EventDirection, System, SystemError};
use satsim_tree::flexible::SMALL_DEFLECTION;

impl System for Simulation {
    fn dim(&self) -> usize {
        self.model.layout.len
    }

    /// `dx = f(t, x)`: the pipeline of `rhs.rs`.
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.right_hand_side(t, x, dx)
    }

    /// The slope the event functions kept at this very state (`ahead.rs`).
    fn holds_rhs(&self, t: f64, x: &[f64]) -> bool {
        self.holds_ahead(t, x)
    }

    /// The energy budget's work states are bookkeeping: they stay out of the error control,
    /// so that tracking them leaves the steps (and every other state) as they were. So do the
    /// elastic coordinates where the builder says (`elastic_error(false)`).
    fn error_weights(&self, w: &mut [f64]) {
        w.fill(1.0);
        w[self.model.work.clone()].fill(0.0);
        if !self.model.elastic_error {
            w[self.model.layout.eta.clone()].fill(0.0);
            w[self.model.layout.etadot.clone()].fill(0.0);
        }
    }

    /// The energy budget's works are integrals of the effects' powers that no derivative
    /// reads: quadratures, left out of the implicit methods' Newton test and Jacobian.
    fn quadratures(&self, q: &mut [bool]) {
        q[self.model.work.clone()].fill(true);
    }

    /// Each watched flexible body's largest deflection so far
    /// ([`Simulation::deflection_peaks`]).
    fn step_accepted(&mut self, t: f64, x: &[f64]) {
        let Some(f) = &self.model.flex else {
            return;
        };
        let eta = &x[self.model.layout.eta.clone()];
        for p in &mut self.data.deflection_peaks {
            let Some(d) = f.deflection_of(p.body, eta) else {
                continue;
            };
            let fraction = d.fraction();
            if fraction > p.fraction() {
                (p.tip, p.length, p.point, p.t) = (d.offset, d.length, d.point, t);
            }
            if p.passed.is_none() && fraction > SMALL_DEFLECTION {
                p.passed = Some(t);
            }
        }
    }

    fn project(&mut self, x: &mut [f64]) {
        if self.model.layout.free {
            let a = self.model.layout.attitude.clone();
            let norm = x[a.clone()].iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > 0.0 {
                for v in &mut x[a] {
                    *v /= norm;
                }
            }
        }
    }

    fn n_events(&self) -> usize {
        self.model.n_events
    }

    /// The effects' event functions, computing first only what they read
    /// ([`Effect::event_reads`](crate::effects::Effect::event_reads)). A state on which the
    /// effects or the hold torques cannot be evaluated is an error (an event is never
    /// skipped silently).
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        if self.model.n_events == 0 {
            return Ok(());
        }
        self.check_len(x.len(), "events")?;
        if g.len() != self.model.n_events {
            return Err(SystemError::new(format!(
                "events: g has length {} but the simulation has {} event functions",
                g.len(),
                self.model.n_events
            )));
        }
        let kin = self.prepare_events(t, x)?;
        self.effects_events(t, x, kin, g);
        Ok(())
    }

    /// At a step's end where the integrator holds its slope (Radau IIA's), the locked
    /// rotors' hold torques are `J α` of the carrier's acceleration in that slope, where the
    /// event functions would otherwise evaluate the right-hand side for it (`ahead.rs`):
    /// the effects are applied, the forward dynamics is not. The crossings inside the step
    /// are located on [`Self::events`], the right-hand side's own.
    fn events_at_step_end(
        &mut self,
        t: f64,
        x: &[f64],
        slope: Option<&[f64]>,
        g: &mut [f64],
    ) -> Result<(), SystemError> {
        let Some(dx) = slope.filter(|dx| self.can_hold_from_slope(dx)) else {
            return self.events(t, x, g);
        };
        self.check_len(x.len(), "events")?;
        if g.len() != self.model.n_events {
            return self.events(t, x, g);
        }
        let kin = self.prepare_events_from_slope(t, x, dx)?;
        self.effects_events(t, x, kin, g);
        Ok(())
    }

    /// The next sample instant of the effects' discrete-time laws (`stepping.rs`).
    fn next_stop(&self) -> f64 {
        self.next_sample_stop()
    }

    /// The effects whose sample is due latch their laws' outputs (`stepping.rs`).
    fn on_stop(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
        self.forget_ahead();
        self.sample_effects(t, x)
    }

    /// The Jacobian survives events and stops that locked no hinge: a locked hinge's rate
    /// must see a zero row (the stage system then keeps it exactly zero); a friction torque
    /// changing sign, a hinge released, an impulse or a sampled law's new output leave a
    /// Jacobian Newton still converges with (and renews where it does not).
    fn update_jacobian(
        &mut self,
        _t0: f64,
        x0: &[f64],
        _t: f64,
        x: &[f64],
        jac: &mut [f64],
    ) -> Result<bool, SystemError> {
        self.jacobian_update(x0, x, jac)
    }

    fn jacobian_survives_restart(&mut self) -> bool {
        !std::mem::take(&mut self.data.newly_locked)
    }

    fn event_direction(&self, k: usize) -> EventDirection {
        let i = self.event_owner(k);
        self.effects[i].event_direction(k - self.model.event_start[i])
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
        self.forget_ahead();
        self.check_len(x.len(), "on_events")?;
        let before = self.mechanical_energy(t, x)?;
        if let Err(e) = self.prepare_with(t, x, false, Hold::All) {
            let why = format!("event handling failed: {e}");
            self.log.events.push((t, why.clone()));
            self.log
                .event_effects
                .push(ks.first().map_or(0, |&k| self.event_owner(k)));
            return Err(SystemError::new(why));
        }
        let kin = self.data.needs_kinematics;
        let mut action = EventAction::Continue;
        let mut own_state = std::mem::take(&mut self.data.impulse.own);
        for &k in ks {
            let i = self.event_owner(k);
            let local = k - self.model.event_start[i];
            let r = self.model.own[i].clone();
            own_state.clear();
            own_state.extend_from_slice(&x[r.clone()]);
            let a = self.with_context(t, x, kin, |ctx, h| {
                h.effects[i].on_event(local, ctx, h.forces, &mut own_state, h.requests)
            });
            x[r].copy_from_slice(&own_state);
            action = action.combine(a);
            // In a string the log reserved: no allocation for the first events.
            let mut what = self.log.spare.pop().unwrap_or_default();
            what.clear();
            self.effects[i].describe_event_into(local, &mut what);
            if what.is_empty() {
                self.log.spare.push(what);
            } else {
                self.log.events.push((t, what));
                self.log.event_effects.push(i);
            }
        }
        self.data.impulse.own = own_state;
        let reqs = std::mem::take(&mut self.data.requests);
        let changed = !reqs.is_empty();
        let result = self.apply_requests(&reqs, x);
        self.data.requests = reqs;
        self.data.requests.clear();
        if let Err(e) = result {
            let why = format!("impact failed: {e}");
            self.log.events.push((t, why.clone()));
            self.log
                .event_effects
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
