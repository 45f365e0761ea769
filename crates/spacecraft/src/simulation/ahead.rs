//! The right-hand side evaluated ahead, by the event functions.
//!
//! A stuck reaction wheel's event function reads the hold torques of the locked hinges
//! (`hold.rs`): forward dynamics with exactly the hinges locked now, then RNEA. That solve is
//! the right-hand side's own at the same state, and the integrator evaluates the event
//! functions at the end of every step, where the next step's first stage (RK4's `k1`, or
//! the Hermite slope of the dense output) then asks for `f(t, x)` again. So the event
//! functions evaluate the whole right-hand side there, keep it, and take the hold torques
//! from its accelerations; the next `rhs` at the same `(t, x)` (bit for bit) returns the
//! kept slope instead of computing it again: one evaluation of the kinematics, the effects
//! and the dynamics where there were two. The slope is bit for bit what the two passes gave
//! apart: the same solve (`forward_dynamics`, or the flexible tree's `flexible_dynamics`,
//! with the same inputs and lock mask) feeds both.
//! The hold torques are RNEA's on those accelerations (the flexible tree's on `[q̈; η̈]`), bit
//! for bit; a stuck wheel's alone (every reader reads only the rotors') comes from the
//! gyrostat rotor's closed form, RNEA's to round-off: in the rigid tree
//! ([`satsim_tree::gyrostat_torques`]) without the rotor's pass, in the flexible tree
//! ([`satsim_tree::flexible::gyrostat_torques`]) from the carrier's acceleration its solve
//! just left, without RNEA's two passes (2 % of the flexible deployment's instructions).
//!
//! The kept slope is used once, and only while nothing but the continuous state could
//! change `f`: every change of the discrete state (locks, an effect's event or sample, the
//! inputs, the constant torques, the dynamics chosen) forgets it
//! ([`Simulation::forget_ahead`]).

use super::Simulation;
use super::solve::flexible_forces;
use crate::effects::HoldReads;
use satsim_integrate::SystemError;
use satsim_tree::{flexible, gyrostat_torques, rnea_for};

/// The slope kept by [`Simulation::evaluate_ahead`]: `dx = f(t, x)`, while `valid`.
pub(super) struct Ahead {
    /// Whether the slope is reused at all ([`Simulation::reuse_event_slopes`]).
    enabled: bool,
    valid: bool,
    t: f64,
    x: Vec<f64>,
    dx: Vec<f64>,
    /// The right-hand side at `(t, x)` was evaluated before the event functions asked for
    /// it, with this result, by the lanes of a batch ([`Simulation::keep_ahead`]); until
    /// the event functions take it.
    given: Option<Result<(), SystemError>>,
}

impl Ahead {
    /// Room for a state of `n` values (allocated once, by the builder).
    pub(super) fn new(n: usize) -> Self {
        Self {
            enabled: true,
            valid: false,
            t: f64::NAN,
            x: vec![0.0; n],
            dx: vec![0.0; n],
            given: None,
        }
    }
}

impl Simulation {
    /// Whether the event functions' hold torques can come from the right-hand side itself:
    /// the hold torques asked for are those of the hinges locked now. `kinematics`: the event
    /// functions read the poses, which the right-hand side computes only when an effect needs
    /// them.
    pub(super) fn can_evaluate_ahead(&self, kinematics: bool) -> bool {
        self.model.needs_hold
            && self.data.n_locked > 0
            && (!kinematics || self.data.needs_kinematics)
    }

    /// The right-hand side at `(t, x)`, kept for the next [`Self::reuse_ahead`], and the
    /// locked hinges' hold torques from its accelerations, as
    /// [`Self::hold_torques_after_effects`] gives them with `Hold::Locked`: by RNEA over the
    /// bodies they depend on, and only the rotors' where the event functions read no other
    /// ([`Effect::hold_reads`](crate::effects::Effect::hold_reads); the others NaN), those of
    /// gyrostat rotors in closed form (the same to round-off).
    /// The right-hand side itself may have been evaluated already, at this very `(t, x)`, by
    /// the lanes of a batch ([`Self::keep_ahead`]): then its result is taken, as it stands.
    pub(super) fn evaluate_ahead(&mut self, t: f64, x: &[f64]) -> Result<(), SystemError> {
        let a = &mut self.data.ahead;
        match a.given.take() {
            Some(result) if a.same_state(t, x) => {
                self.log.lane_ahead += 1;
                result?
            }
            _ => {
                self.forget_ahead();
                let mut dx = std::mem::take(&mut self.data.ahead.dx);
                let result = self.right_hand_side(t, x, &mut dx);
                let a = &mut self.data.ahead;
                a.dx = dx;
                a.valid = result.is_ok();
                result?;
                a.t = t;
                a.x.copy_from_slice(x);
            }
        }
        let (m, d) = (&self.model, &mut self.data);
        match m.velocity_at {
            Some(s) => {
                let nv = d.v.len();
                d.hold_ddq.copy_from_slice(&d.ahead.dx[s..s + nv]);
            }
            None => d.hold_ddq.copy_from_slice(&d.ddq),
        }
        // Only the hold torques read: the rotors' when every reader reads only theirs.
        let rotors_only = self
            .effects
            .iter()
            .filter(|e| e.n_events() > 0 && e.event_reads().hold_torques)
            .all(|e| e.hold_reads() == HoldReads::Rotors);
        for (k, (w, &locked)) in d.hold_mask.iter_mut().zip(&d.locked).enumerate() {
            *w = locked && (!rotors_only || k >= m.n_user);
        }
        let fext = d
            .forces
            .has_wrench
            .then_some(d.forces.body_wrench.as_slice());
        let need = match (&m.flex, &mut d.flex) {
            // The flexible tree's: RNEA over `[q̈; η̈]`, on the first pass the right-hand
            // side's dynamics left for this state (as `hold.rs` gives them after its solve).
            (Some(f), Some(w)) => {
                let eta_ddot = &d.ahead.dx[m.layout.etadot.clone()];
                let nv = d.hold_ddq.len();
                w.a[..nv].copy_from_slice(&d.hold_ddq);
                w.a[nv..].copy_from_slice(eta_ddot);
                let mask = &d.hold_mask;
                // A wheel's in closed form, from the carriers' accelerations the solve just
                // left; RNEA where any other is asked for.
                match rotors_only
                    .then(|| flexible::gyrostat_torques(f, &mut w.data, &w.a, fext, mask))
                {
                    Some(Ok(Some(_))) => Ok(w.data.tau.as_slice()),
                    Some(Err(e)) => Err(e),
                    _ => flexible_forces(f, w, &d.hold_ddq, eta_ddot, fext),
                }
            }
            // A gyrostat rotor's (a reaction wheel's) in closed form; RNEA where any other is
            // asked for.
            _ => {
                let (tree, data, q, v, ddq, mask) =
                    (&m.tree, &mut d.tree, &d.q, &d.v, &d.hold_ddq, &d.hold_mask);
                match gyrostat_torques(tree, data, q, v, ddq, fext, mask) {
                    Ok(Some(_)) => Ok(data.tau.as_slice()),
                    Ok(None) => rnea_for(tree, data, q, v, ddq, fext, mask).map(|t| t.as_slice()),
                    Err(e) => Err(e),
                }
            }
        }
        .map_err(SystemError::from_error)?;
        let nb = m.tree.base_nv();
        for ((h, &w), n) in d.hold.iter_mut().zip(&d.hold_mask).zip(&need[nb..]) {
            *h = if w { *n } else { f64::NAN };
        }
        Ok(())
    }

    /// `dx = f(t, x)` from the slope kept by [`Self::evaluate_ahead`] when it was taken at
    /// this very `(t, x)` (bit for bit) and nothing changed since; the slope is used once.
    /// Not counted as an evaluation: [`Self::evaluate_ahead`] counted it.
    #[inline]
    pub(super) fn reuse_ahead(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> bool {
        let a = &mut self.data.ahead;
        if !a.valid || !a.enabled {
            return false;
        }
        a.valid = false;
        let same = dx.len() == a.dx.len() && a.same_state(t, x);
        if same {
            dx.copy_from_slice(&a.dx);
            self.log.reused_rhs += 1;
        }
        same
    }

    /// Whether the event functions evaluated the right-hand side at this very `(t, x)`,
    /// reused or not ([`Self::reuse_event_slopes`]): the integrator asks for `f` there
    /// alike either way, so that the switch moves no bits.
    pub(super) fn holds_ahead(&self, t: f64, x: &[f64]) -> bool {
        let a = &self.data.ahead;
        a.valid && a.same_state(t, x)
    }

    /// Whether a right-hand side at the state where the event functions just evaluated it
    /// reuses it (the default), or computes it again: the results are the same bit for bit
    /// either way (tested), so this serves only to check that or to time the gain.
    pub fn reuse_event_slopes(&mut self, on: bool) {
        self.data.ahead.enabled = on;
        self.forget_ahead();
    }

    /// Forgets the kept slope: the discrete state changed, so `f` may have.
    #[inline]
    pub(super) fn forget_ahead(&mut self) {
        self.data.ahead.valid = false;
        self.data.ahead.given = None;
    }

    /// Whether the event functions at `(t, x)` evaluate the right-hand side there
    /// ([`Self::evaluate_ahead`], as [`Self::prepare_events`] decides), so that the lanes of
    /// a batch may evaluate it for them ([`Self::keep_ahead`]).
    pub(super) fn evaluates_ahead(&self, x: &[f64]) -> bool {
        self.model.n_events > 0
            && x.len() == self.data.ahead.x.len()
            && self.event_reads_ahead().is_some()
    }

    /// The slope's buffer, for the lanes to evaluate the right-hand side into; the kept
    /// slope is forgotten. Back with [`Self::keep_ahead`] or [`Self::return_ahead_slope`].
    pub(super) fn take_ahead_slope(&mut self) -> Vec<f64> {
        self.forget_ahead();
        std::mem::take(&mut self.data.ahead.dx)
    }

    /// The buffer of [`Self::take_ahead_slope`], unused.
    pub(super) fn return_ahead_slope(&mut self, dx: Vec<f64>) {
        self.data.ahead.dx = dx;
    }

    /// The right-hand side at `(t, x)`, `dx` (in the buffer of [`Self::take_ahead_slope`]),
    /// evaluated by the lanes of a batch with `result`, as the event functions' own
    /// [`Self::evaluate_ahead`] would have: kept for them, and, once they have taken it,
    /// for the next step's first stage.
    pub(super) fn keep_ahead(
        &mut self,
        t: f64,
        x: &[f64],
        dx: Vec<f64>,
        result: Result<(), SystemError>,
    ) {
        let a = &mut self.data.ahead;
        a.dx = dx;
        a.valid = result.is_ok();
        a.t = t;
        a.x.copy_from_slice(x);
        a.given = Some(result);
    }
}

impl Ahead {
    /// Whether `(t, x)` is the kept state, bit for bit.
    #[inline]
    fn same_state(&self, t: f64, x: &[f64]) -> bool {
        t.to_bits() == self.t.to_bits()
            && x.len() == self.x.len()
            && x.iter()
                .zip(&self.x)
                .all(|(p, q)| p.to_bits() == q.to_bits())
    }
}
