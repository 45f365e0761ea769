//! The [`System`] trait: what an integrator needs to know about an ODE.

use std::error::Error;
use std::fmt;
use std::sync::Arc;

/// A failure detected by a [`System`] while evaluating its right-hand side
/// (e.g. a singular configuration).
///
/// It carries the system's own error, typed: [`SystemError::from_error`] takes any
/// `std::error::Error + Send + Sync + 'static` (e.g. the engine's `DynamicsError`: this
/// crate depends on no engine, so the wrapping is generic); [`SystemError::new`] takes a
/// plain message (`SystemError::new(format!(...))`, or `"text".into()`). Its text is the
/// wrapped error's (`from_error(e)` displays exactly as `new(e.to_string())` did); the
/// typed error comes back by [`SystemError::downcast_ref`], [`SystemError::get_ref`] or
/// [`std::error::Error::source`] (`None` for a plain message).
///
/// ```
/// use satsim_integrate::SystemError;
/// use std::error::Error;
/// #[derive(Debug, PartialEq)]
/// struct Singular(usize);
/// impl std::fmt::Display for Singular {
///     fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
///         write!(f, "singular at hinge {}", self.0)
///     }
/// }
/// impl Error for Singular {}
/// let e = SystemError::from_error(Singular(3));
/// assert_eq!(e.to_string(), "singular at hinge 3");
/// assert_eq!(e.downcast_ref::<Singular>(), Some(&Singular(3)));
/// assert!(e.source().is_some());
/// let m = SystemError::new(format!("singular at hinge {}", 3));
/// assert_eq!(m.to_string(), "singular at hinge 3");
/// assert!(m.downcast_ref::<Singular>().is_none() && m.source().is_none());
/// assert_eq!(e, m); // equal messages (see `PartialEq`)
/// ```
#[derive(Clone)]
pub struct SystemError {
    /// The wrapped error (a [`Message`] for plain text). Shared, so that the error (and
    /// `IntegrateError`) stays `Clone`.
    inner: Arc<dyn Error + Send + Sync + 'static>,
}

/// A plain-text [`SystemError`]: no typed error behind it.
#[derive(Debug)]
struct Message(String);

impl fmt::Display for Message {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl Error for Message {}

impl SystemError {
    /// A plain message (`format!(...)`, a `&str`): no typed error behind it.
    pub fn new(msg: impl Into<String>) -> Self {
        Self {
            inner: Arc::new(Message(msg.into())),
        }
    }

    /// Wraps a typed error, kept as it is: its text is the error's text, and
    /// [`SystemError::downcast_ref`] gives it back (e.g. `.map_err(SystemError::from_error)`
    /// on the engine's `Result<_, DynamicsError>`).
    pub fn from_error<E: Error + Send + Sync + 'static>(error: E) -> Self {
        Self {
            inner: Arc::new(error),
        }
    }

    /// The wrapped error as a `T`, if it is one (`None` for a plain message).
    pub fn downcast_ref<T: Error + 'static>(&self) -> Option<&T> {
        self.inner.downcast_ref::<T>()
    }

    /// Whether the wrapped error is a `T`.
    pub fn is<T: Error + 'static>(&self) -> bool {
        self.inner.is::<T>()
    }

    /// The wrapped error (for a plain message, an error whose text is the message).
    pub fn get_ref(&self) -> &(dyn Error + Send + Sync + 'static) {
        &*self.inner
    }

    /// Whether this is a plain message, with no typed error behind it.
    pub fn is_message(&self) -> bool {
        self.inner.is::<Message>()
    }
}

impl fmt::Display for SystemError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&*self.inner, f)
    }
}

impl fmt::Debug for SystemError {
    /// `SystemError("text")` for a message, `SystemError(<the error's Debug>)` otherwise.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.inner.downcast_ref::<Message>() {
            Some(Message(m)) => f.debug_tuple("SystemError").field(m).finish(),
            None => f.debug_tuple("SystemError").field(&self.inner).finish(),
        }
    }
}

/// Two system errors are equal when their texts are (the wrapped errors' types and
/// contents are not compared: `dyn Error` has no equality). For plain messages this is the
/// equality of the messages, as before the errors were typed.
impl PartialEq for SystemError {
    fn eq(&self, other: &Self) -> bool {
        self.to_string() == other.to_string()
    }
}

impl Eq for SystemError {}

impl Error for SystemError {
    /// The wrapped typed error; `None` for a plain message.
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        if self.is_message() {
            None
        } else {
            Some(&*self.inner)
        }
    }
}

impl From<String> for SystemError {
    fn from(s: String) -> Self {
        Self::new(s)
    }
}

impl From<&str> for SystemError {
    fn from(s: &str) -> Self {
        Self::new(s)
    }
}

/// A boxed error, kept as it is (typed: it has a `source`, even when the box holds a
/// string: use [`SystemError::new`] for messages).
impl From<Box<dyn Error + Send + Sync + 'static>> for SystemError {
    fn from(error: Box<dyn Error + Send + Sync + 'static>) -> Self {
        Self {
            inner: Arc::from(error),
        }
    }
}

/// Which sign changes of an event function `g_k` trigger the event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EventDirection {
    /// `g` goes from negative to non-negative.
    Rising,
    /// `g` goes from positive to non-positive.
    Falling,
    /// Either of the above.
    #[default]
    Both,
}

impl EventDirection {
    /// Whether going from `g0` (start of an interval) to `g1` (its end) is a
    /// crossing in this direction. A start exactly on zero never counts, so an
    /// event that was just handled (or a reset that leaves `g = 0`) does not
    /// fire again immediately.
    #[inline]
    pub fn crosses(self, g0: f64, g1: f64) -> bool {
        let rising = g0 < 0.0 && g1 >= 0.0;
        let falling = g0 > 0.0 && g1 <= 0.0;
        match self {
            Self::Rising => rising,
            Self::Falling => falling,
            Self::Both => rising || falling,
        }
    }
}

/// What the integrator does after [`System::on_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventAction {
    /// Nothing changed; carry on with the current step.
    Continue,
    /// The system modified the state in place; the integrator restarts from
    /// the event time and that state (new first step, FSAL data discarded).
    Reset,
    /// End the integration at the event.
    Stop,
}

/// An ODE `dx/dt = f(t, x)` on a flat state vector, plus optional hooks.
///
/// Only [`dim`](System::dim) and [`rhs`](System::rhs) are required.
///
/// ```
/// use satsim_integrate::{System, SystemError};
///
/// /// Harmonic oscillator x'' = -x.
/// struct Oscillator;
/// impl System for Oscillator {
///     fn dim(&self) -> usize { 2 }
///     fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
///         dx[0] = x[1];
///         dx[1] = -x[0];
///         Ok(())
///     }
/// }
/// let mut dx = [0.0; 2];
/// Oscillator.rhs(0.0, &[1.0, 0.0], &mut dx).unwrap();
/// assert_eq!(dx, [0.0, -1.0]);
/// ```
pub trait System {
    /// Dimension of the state vector.
    fn dim(&self) -> usize;

    /// Evaluates `dx = f(t, x)`.
    ///
    /// Returning `Err` stops the integration with
    /// [`IntegrateError::System`](crate::IntegrateError::System) carrying `t`.
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError>;

    /// Called on the state after each accepted step (e.g. to renormalise a
    /// quaternion). The default does nothing.
    ///
    /// The modification should be of the size of the local error: it is not
    /// seen by the error control. If it changes `x`, FSAL methods re-evaluate
    /// the derivative at the start of the next step (one extra `rhs` call); Radau IIA's
    /// error estimate keeps the collocation polynomial's slope there, which is already an
    /// approximation of that size.
    fn project(&mut self, _x: &mut [f64]) {}

    /// Called after every accepted step (after [`System::project`], before the step's
    /// events and outputs) with the step's end time and state: a place to watch the
    /// solution between output rows. The default does nothing.
    fn step_accepted(&mut self, _t: f64, _x: &[f64]) {}

    /// Per-component weights of the error norm, written into `w`
    /// (`w.len() == dim()`); `0` excludes a component. Default: all 1.
    /// Queried once at the start of an integration.
    fn error_weights(&self, w: &mut [f64]) {
        w.fill(1.0);
    }

    /// Marks the quadrature states in `q` (`q.len() == dim()`, all `false` on entry):
    /// states no right-hand side reads, each an integral of the others (an accumulated
    /// work, a cost). The implicit methods leave them out of the Newton iteration's
    /// convergence test, where their own scale (`atol + rtol |x|`) would hold the iteration
    /// far tighter than the states they integrate need, and cost iterations and Jacobians;
    /// and out of the finite-difference Jacobian, whose columns for them are zero: CVODES's
    /// treatment of quadratures. The other states' steps are then those of the system
    /// without them. Their values come out of the same stage equations, as accurate as the
    /// Newton iteration leaves the states they integrate. The error estimate still counts
    /// them as [`System::error_weights`] says. The first finite-difference Jacobian checks
    /// that their columns are zero ([`IntegrateError::InvalidOptions`] if not). Queried
    /// once at the start of an integration; the default marks none.
    ///
    /// [`IntegrateError::InvalidOptions`]: crate::IntegrateError::InvalidOptions
    fn quadratures(&self, _q: &mut [bool]) {}

    /// Whether [`System::rhs`] at `(t, x)` would return a slope the system holds already,
    /// evaluated for its own ends (its event functions at a step's end, say), at no cost.
    /// Radau IIA's error estimate then takes `f` there, where it otherwise takes its
    /// collocation polynomial's slope. Default: false.
    fn holds_rhs(&self, _t: f64, _x: &[f64]) -> bool {
        false
    }

    /// Analytic Jacobian `jac[i * n + j] = ∂f_i/∂x_j` (row-major), used by
    /// implicit methods. Return `Ok(false)` (the default) to let the
    /// integrator use finite differences.
    fn jacobian(&mut self, _t: f64, _x: &[f64], _jac: &mut [f64]) -> Result<bool, SystemError> {
        Ok(false)
    }

    /// Brings a Jacobian that was evaluated at `(t0, x0)` to `(t, x)` in place, where the
    /// system knows a cheap way to (a multibody system: its mass matrix at both states).
    /// Return `Ok(false)` (the default) to have a new one evaluated. The implicit methods
    /// call it where their Newton iteration asks for a fresher Jacobian, and evaluate a new
    /// one where an updated one failed them.
    fn update_jacobian(
        &mut self,
        _t0: f64,
        _x0: &[f64],
        _t: f64,
        _x: &[f64],
        _jac: &mut [f64],
    ) -> Result<bool, SystemError> {
        Ok(false)
    }

    /// Number of event functions. Default: none.
    fn n_events(&self) -> usize {
        0
    }

    /// Evaluates the event functions `g_k(t, x)` into `g` (`g.len() == n_events()`).
    ///
    /// Returning `Err` (the state could not be evaluated) stops the integration
    /// with [`IntegrateError::System`](crate::IntegrateError::System): an event
    /// is never skipped silently.
    fn events(&mut self, _t: f64, _x: &[f64], _g: &mut [f64]) -> Result<(), SystemError> {
        Ok(())
    }

    /// The event functions at the end of an accepted step, where the method holds `slope`,
    /// its own approximation of `f(t, x)` (Radau IIA's: its collocation polynomial's slope,
    /// `f` at its last stage to within the Newton iteration's convergence), or `None`. Event
    /// functions that read `f` (a stuck wheel's hold torque is `J α` of the carrier's
    /// acceleration) may take it there instead of evaluating `f`; the crossings between step
    /// ends are located on [`System::events`]. Default: [`System::events`], the slope unread.
    fn events_at_step_end(
        &mut self,
        t: f64,
        x: &[f64],
        _slope: Option<&[f64]>,
        g: &mut [f64],
    ) -> Result<(), SystemError> {
        self.events(t, x, g)
    }

    /// Direction of sign change that triggers event `k`. Default: both.
    fn event_direction(&self, _k: usize) -> EventDirection {
        EventDirection::Both
    }

    /// Called at a located event `k` with the time and state at the event.
    /// For [`EventAction::Reset`] the system modifies `x` in place. Default: stop.
    fn on_event(&mut self, _k: usize, _t: f64, _x: &mut [f64]) -> EventAction {
        EventAction::Stop
    }

    /// Called once for every group of events that fall together: `ks` (in
    /// increasing index order, never empty) crossed at the same instant `t`, to
    /// within the event tolerance. All of them are handled, whatever each one
    /// answers: the group's action is [`EventAction::Stop`] if any handler
    /// stops, else [`EventAction::Reset`] if any resets, else
    /// [`EventAction::Continue`].
    ///
    /// The default calls [`System::on_event`] for each `k` in turn (each sees
    /// the state as the previous ones left it). A system whose events interact
    /// (simultaneous impacts) overrides this to resolve them together.
    /// Returning `Err` stops the integration with
    /// [`IntegrateError::System`](crate::IntegrateError::System).
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        let mut action = EventAction::Continue;
        for &k in ks {
            action = action.combine(self.on_event(k, t, x));
        }
        Ok(action)
    }

    /// The next **time stop**: an instant, known in advance, at which the right-hand side
    /// changes (the sample instant of a discrete-time controller). `f64::INFINITY` (the
    /// default) for none.
    ///
    /// Every method lands a step exactly on it (adaptive methods shorten the step; a fixed
    /// step is split there), then, after the outputs up to that instant and the events
    /// within the step, calls [`System::on_stop`] with the state at the stop. A stop at the
    /// start time is handled before the first step. The value must move past `t` once
    /// [`System::on_stop`] has run at `t` (the driver reports a stop that does not as an
    /// error rather than loop). A stop within round-off of the current time
    /// ([`stop_due`](crate::stop_due)) is due there, so that no sliver step is taken to reach it.
    fn next_stop(&self) -> f64 {
        f64::INFINITY
    }

    /// Handles the time stop [`System::next_stop`] at `t` with the state `x` (the state at
    /// the end of the step that landed there, bit for bit). Returns whether the right-hand
    /// side (or `x`, modified in place) changed: the integrator then restarts from `(t, x)`
    /// as after an [`EventAction::Reset`], so that no stage of the old right-hand side is
    /// reused, but an adaptive method with the step its error control proposed rather than
    /// a first step estimated anew. Returning `Err` stops the integration with
    /// [`IntegrateError::System`](crate::IntegrateError::System).
    fn on_stop(&mut self, _t: f64, _x: &mut [f64]) -> Result<bool, SystemError> {
        Ok(false)
    }

    /// Whether the Jacobian taken before the events (or time stop) handled since the last
    /// restart still serves after them: asked once by the implicit methods at each restart
    /// that follows such handling. `false` (the default) has them take a new one there.
    ///
    /// A system answers `true` where the handling changed nothing the stage system must see
    /// exactly: the derivative may have jumped (a friction torque changing sign), the state
    /// may have jumped, but no state became one whose derivative is identically zero (a hinge
    /// newly locked, whose rate the stage system keeps exactly zero only through a zero row).
    /// Newton's convergence check renews a kept Jacobian that no longer serves.
    fn jacobian_survives_restart(&mut self) -> bool {
        false
    }
}

/// Whether a time stop at `stop` is due at time `t`: `t` has reached it, or lies within
/// round-off of it (`1e-12` relative to `max(|stop|, 1)`), so that a stop computed as
/// `k · period` is met by a time reached as a sum of steps.
///
/// ```
/// use satsim_integrate::stop_due;
/// assert!(stop_due(0.3, 0.1 + 0.1 + 0.1)); // 0.30000000000000004
/// assert!(stop_due(0.4, 0.3));
/// assert!(!stop_due(0.3, 0.31));
/// assert!(!stop_due(0.0, f64::INFINITY));
/// ```
pub fn stop_due(t: f64, stop: f64) -> bool {
    t >= stop || (stop.is_finite() && stop - t <= STOP_ROUNDOFF * stop.abs().max(1.0))
}

/// The relative round-off within which a time stop counts as reached ([`stop_due`]).
pub const STOP_ROUNDOFF: f64 = 1e-12;

impl EventAction {
    /// The action of a group of events: `Stop` wins over `Reset`, which wins
    /// over `Continue`.
    pub fn combine(self, other: Self) -> Self {
        use EventAction::*;
        match (self, other) {
            (Stop, _) | (_, Stop) => Stop,
            (Reset, _) | (_, Reset) => Reset,
            _ => Continue,
        }
    }
}

impl<S: System + ?Sized> System for &mut S {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        (**self).rhs(t, x, dx)
    }
    fn project(&mut self, x: &mut [f64]) {
        (**self).project(x)
    }
    fn step_accepted(&mut self, t: f64, x: &[f64]) {
        (**self).step_accepted(t, x)
    }
    fn error_weights(&self, w: &mut [f64]) {
        (**self).error_weights(w)
    }
    fn quadratures(&self, q: &mut [bool]) {
        (**self).quadratures(q)
    }
    fn holds_rhs(&self, t: f64, x: &[f64]) -> bool {
        (**self).holds_rhs(t, x)
    }
    fn jacobian(&mut self, t: f64, x: &[f64], jac: &mut [f64]) -> Result<bool, SystemError> {
        (**self).jacobian(t, x, jac)
    }
    fn update_jacobian(
        &mut self,
        t0: f64,
        x0: &[f64],
        t: f64,
        x: &[f64],
        jac: &mut [f64],
    ) -> Result<bool, SystemError> {
        (**self).update_jacobian(t0, x0, t, x, jac)
    }
    fn n_events(&self) -> usize {
        (**self).n_events()
    }
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        (**self).events(t, x, g)
    }
    fn events_at_step_end(
        &mut self,
        t: f64,
        x: &[f64],
        slope: Option<&[f64]>,
        g: &mut [f64],
    ) -> Result<(), SystemError> {
        (**self).events_at_step_end(t, x, slope, g)
    }
    fn event_direction(&self, k: usize) -> EventDirection {
        (**self).event_direction(k)
    }
    fn on_event(&mut self, k: usize, t: f64, x: &mut [f64]) -> EventAction {
        (**self).on_event(k, t, x)
    }
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        (**self).on_events(ks, t, x)
    }
    fn next_stop(&self) -> f64 {
        (**self).next_stop()
    }
    fn on_stop(&mut self, t: f64, x: &mut [f64]) -> Result<bool, SystemError> {
        (**self).on_stop(t, x)
    }
    fn jacobian_survives_restart(&mut self) -> bool {
        (**self).jacobian_survives_restart()
    }
}
