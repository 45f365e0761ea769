//! Integration errors.

use std::fmt;

use crate::system::SystemError;

/// A number as a message shows it: `{}` for zero and magnitudes in `[1e-9, 1e9)` (the times
/// of ordinary runs, to the last digit), `{:e}` beyond, so that a time of `1e-293` is not
/// written out as hundreds of digits. The same rule as `satsim_tree::error::Num`: the
/// integrator depends on no other crate of the workspace, so it keeps its own copy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a.is_finite() && a != 0.0 && !(1e-9..1e9).contains(&a) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// Why an integration failed. Every output before the failure has already
/// been passed to the observer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrateError {
    /// The options (or the time span / output request) are inconsistent.
    #[error("invalid options: {0}")]
    InvalidOptions(String),
    /// The step size became negligible relative to `t` (e.g. a finite-time
    /// blow-up, a discontinuity the error control cannot pass, or a stiff motion under an
    /// explicit method).
    #[error("step size underflow at t = {} (h = {h:e}){what}", Num(*.t))]
    StepSizeUnderflow {
        /// Time reached.
        t: f64,
        /// Step size that was too small.
        h: f64,
        /// The state entry the steps were last cut for: the one whose error estimate was the
        /// largest against its tolerance at the last step the error control rejected (for
        /// radau5 also its Newton increment, where the iteration did not contract), or the
        /// first that was not finite in a trial stage. `None` where the last cut was for a
        /// stage the system refused with its own error or a singular iteration matrix.
        entry: Option<usize>,
        /// What limited the step (`": …"`, appended to the message): the integrator names
        /// the entry by its index; a caller that knows the system may name it, and say what
        /// to try, instead.
        what: String,
    },
    /// More step attempts than `Options::max_steps` (typically: a stiff
    /// problem given to an explicit method).
    #[error("maximum number of steps exceeded at t = {}{stepping}", Num(*.t))]
    MaxSteps {
        /// Time reached.
        t: f64,
        /// What the steps were spent on, as the caller that knows the system tells it
        /// (`"; …"`, appended to the message), or empty: the integrator leaves it empty.
        stepping: String,
    },
    /// The system returned a non-finite derivative for a finite state, or a
    /// fixed-step run produced a non-finite state.
    #[error("non-finite value at t = {}{what}", Num(*.t))]
    NonFinite {
        /// Time of the offending evaluation.
        t: f64,
        /// The first entry that is not finite, when one is known.
        entry: Option<NonFiniteEntry>,
        /// What is not finite (`": …"`, appended to the message): the integrator names the
        /// entry by its index; a caller that knows the system may name it instead.
        what: String,
    },
    /// The Newton iteration of an implicit method did not converge in
    /// fixed-step mode, or its iteration matrix stayed singular.
    #[error("implicit solver failed to converge at t = {} (h = {h:e})", Num(*.t))]
    ConvergenceFailure {
        /// Time reached.
        t: f64,
        /// Step size attempted.
        h: f64,
    },
    /// The system reported a failure.
    #[error("system error at t = {}: {source}", Num(*.t))]
    System {
        /// Time of the failing evaluation.
        t: f64,
        /// The system's error.
        source: SystemError,
    },
}

/// The entry of a vector that an [`IntegrateError::NonFinite`] found not finite first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NonFiniteEntry {
    /// Entry `i` of the state.
    State(usize),
    /// Entry `i` of the derivative, the state being finite.
    Derivative(usize),
}

impl IntegrateError {
    /// A step size underflow at `t` (step `h`), the steps shortened last for the error of
    /// state entry `entry` where it is known.
    pub(crate) fn step_size_underflow(t: f64, h: f64, entry: Option<usize>) -> Self {
        let what = entry
            .map(|i| format!(": the steps were last cut for state entry {i}"))
            .unwrap_or_default();
        IntegrateError::StepSizeUnderflow { t, h, entry, what }
    }
    /// The first non-finite entry of the state `x` at `t` (none found: no entry named).
    pub(crate) fn non_finite_state(t: f64, x: &[f64]) -> Self {
        Self::non_finite(
            t,
            x.iter()
                .position(|v| !v.is_finite())
                .map(NonFiniteEntry::State),
        )
    }
    /// The first non-finite entry of the derivative `dx` of a finite state at `t`.
    pub(crate) fn non_finite_derivative(t: f64, dx: &[f64]) -> Self {
        Self::non_finite(
            t,
            dx.iter()
                .position(|v| !v.is_finite())
                .map(NonFiniteEntry::Derivative),
        )
    }
    fn non_finite(t: f64, entry: Option<NonFiniteEntry>) -> Self {
        let what = match entry {
            Some(NonFiniteEntry::State(i)) => format!(": state entry {i}"),
            Some(NonFiniteEntry::Derivative(i)) => format!(": the derivative of state entry {i}"),
            None => String::new(),
        };
        IntegrateError::NonFinite { t, entry, what }
    }
}
