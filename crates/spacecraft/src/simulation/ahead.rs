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
//!
//! Where the integrator holds a slope of its own at the step's end (Radau IIA's collocation
//! polynomial, `f` at its last stage to within the Newton iteration's convergence; see
//! [`System::events_at_step_end`](satsim_integrate::System::events_at_step_end)), the event
//! functions there take the rotors' hold torques from it instead: the effects are applied
//! (the motor commands), the forward dynamics is not, and the next step's error estimate
//! takes the same slope. On the flexible deployment that is one flexible ABA fewer a step,
//! 2.5 % of the instructions over tolerances 0.95e-5 to 1.45e-5. Where the event functions
//! locate a crossing inside the step they evaluate `f` as above.

use super::data::FlexWork;
use super::hold::Hold;
use super::solve::flexible_forces;
use super::{SimModel, Simulation};
use crate::effects::HoldReads;
use satsim_integrate::SystemError;
use satsim_tree::{flexible, gyrostat_torques, rnea_for};

/// The velocities' derivatives in a state derivative `dx` into `ddq` (the tree's order),
/// where they are not one run of the state: the inverse of the right-hand side's
/// `pack_accelerations`.
fn unpack_accelerations(m: &SimModel, dx: &[f64], ddq: &mut [f64]) {
    let (l, n, nb) = (&m.layout, m.n_user, m.tree.base_nv());
    if l.free {
        ddq[..6 + n].copy_from_slice(&dx[l.omega.start..l.omega.start + 6 + n]);
    } else {
        ddq[..n].copy_from_slice(&dx[l.rates.clone()]);
    }
    if let Some(i) = m.rotor_effect {
        ddq[nb + n..nb + n + m.n_rotors].copy_from_slice(&dx[m.own[i].clone()]);
    }
}

/// Whether the forward dynamics ran on the state whose hold torques are asked for.
#[derive(Clone, Copy)]
enum Solved {
    /// It did: the carriers' accelerations and the first pass are in the tree's data.
    Yes,
    /// It did not (the accelerations are an integrator's slope); `first_pass`: the
    /// kinematics' first pass of this state is current.
    No { first_pass: bool },
}

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
        let dx = std::mem::take(&mut self.data.ahead.dx);
        let result = self.hold_torques_of_slope(&dx, Solved::Yes);
        self.data.ahead.dx = dx;
        result
    }

    /// Whether the event functions at a step's end may take the locked rotors' hold torques
    /// from the integrator's slope there ([`Self::prepare_events_from_slope`]): they read
    /// only those of the hinges locked now, and only the rotors'; the slope has the state's
    /// length; no batch's lanes evaluated the right-hand side for them.
    pub(super) fn can_hold_from_slope(&self, slope: &[f64]) -> bool {
        self.model.n_events > 0
            && slope.len() == self.model.layout.len
            && self.data.ahead.given.is_none()
            && self.event_reads_ahead().is_some()
            && self.rotors_only()
    }

    /// Whether every event function that reads hold torques reads only the rotors'.
    fn rotors_only(&self) -> bool {
        self.effects
            .iter()
            .filter(|e| e.n_events() > 0 && e.event_reads().hold_torques)
            .all(|e| e.hold_reads() == HoldReads::Rotors)
    }

    /// The effects applied at `(t, x)` (as the right-hand side applies them) and the locked
    /// rotors' hold torques from `slope`, an integrator's approximation of `f(t, x)`, in
    /// place of the right-hand side [`Self::evaluate_ahead`] would evaluate: no forward
    /// dynamics. Returns whether the poses are current. Only where
    /// [`Self::can_hold_from_slope`].
    pub(super) fn prepare_events_from_slope(
        &mut self,
        t: f64,
        x: &[f64],
        slope: &[f64],
    ) -> Result<bool, SystemError> {
        let wrap = |e: SystemError| SystemError::new(format!("event functions: {e}"));
        let reads = self.event_reads();
        self.prepare_with(t, x, reads.kinematics, Hold::None)
            .map_err(wrap)?;
        let kin = reads.kinematics || self.data.needs_kinematics;
        self.hold_torques_of_slope(slope, Solved::No { first_pass: kin })
            .map_err(wrap)?;
        Ok(kin)
    }

    /// The locked hinges' hold torques from the accelerations in `dx` (the state's
    /// derivative), into `data.hold` (NaN for the others): the rotors' alone where every
    /// reader reads only theirs, a gyrostat rotor's in closed form, RNEA's where any other is
    /// asked for. `solved`: whether the forward dynamics just ran on this state (its
    /// carriers' accelerations and first pass are then in the tree's data).
    fn hold_torques_of_slope(&mut self, dx: &[f64], solved: Solved) -> Result<(), SystemError> {
        let rotors_only = self.rotors_only();
        let (m, d) = (&self.model, &mut self.data);
        match m.velocity_at {
            Some(s) => {
                let nv = d.v.len();
                d.hold_ddq.copy_from_slice(&dx[s..s + nv]);
            }
            None => match solved {
                Solved::Yes => d.hold_ddq.copy_from_slice(&d.ddq),
                Solved::No { .. } => unpack_accelerations(m, dx, &mut d.hold_ddq),
            },
        }
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
                let eta_ddot = &dx[m.layout.etadot.clone()];
                let nv = d.hold_ddq.len();
                w.a[..nv].copy_from_slice(&d.hold_ddq);
                w.a[nv..].copy_from_slice(eta_ddot);
                let mask = &d.hold_mask;
                // A wheel's in closed form, from the carriers' accelerations the solve just
                // left (or, with no solve, from the slope's where they ride the base); RNEA
                // where any other is asked for, on the first pass of this state where one is
                // current.
                let closed = rotors_only.then(|| match solved {
                    Solved::Yes => flexible::gyrostat_torques(f, &mut w.data, &w.a, fext, mask),
                    Solved::No { .. } => {
                        flexible::gyrostat_torques_on_base(f, &mut w.data, &w.a, fext, mask)
                    }
                });
                match (closed, solved) {
                    (Some(Ok(Some(_))), _) => Ok(w.data.tau.as_slice()),
                    (Some(Err(e)), _) => Err(e),
                    (_, Solved::No { first_pass: false }) => {
                        let FlexWork { data, q, v, a, .. } = w;
                        flexible::rnea(f, data, q, v, a, fext).map(|t| t.as_slice())
                    }
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
