//! Method selection, tolerances and output requests.

use std::{borrow::Cow, fmt, str::FromStr};

use crate::error::IntegrateError;
use crate::grid::DecimalGrid;

/// An integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Classic fixed-step fourth-order Runge-Kutta; needs `Options::fixed_step`.
    Rk4,
    /// Dormand-Prince 5(4) with FSAL, PI step control and 4th-order dense output.
    Dp54,
    /// Hairer's DOP853: order 8, 5/3 error estimator, 7th-order dense output.
    Dop853,
    /// Implicit Radau IIA of order 5 (3 stages) for stiff problems. As in
    /// Hairer's RADAU5 the tolerances are mapped internally to
    /// `rtol' = 0.1 rtol^(2/3)`, `atol' = rtol' atol / rtol` (its error
    /// estimate is of order 3), so a given `rtol` yields roughly that accuracy.
    Radau5,
}

impl Method {
    /// All methods, in the order of [`Method::NAMES`].
    pub const ALL: [Method; 4] = [Method::Rk4, Method::Dp54, Method::Dop853, Method::Radau5];
    /// The names accepted by [`Method::from_str`].
    pub const NAMES: [&'static str; 4] = ["rk4", "dp54", "dop853", "radau5"];

    /// The method's name, as parsed by [`Method::from_str`].
    pub fn name(self) -> &'static str {
        match self {
            Method::Rk4 => "rk4",
            Method::Dp54 => "dp54",
            Method::Dop853 => "dop853",
            Method::Radau5 => "radau5",
        }
    }

    /// Classical order of the method.
    pub fn order(self) -> usize {
        match self {
            Method::Rk4 => 4,
            Method::Dp54 | Method::Radau5 => 5,
            Method::Dop853 => 8,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A method name that [`Method::from_str`] did not recognise.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown integration method `{0}`; valid names: rk4, dp54, dop853, radau5")]
pub struct UnknownMethod(pub String);

impl FromStr for Method {
    type Err = UnknownMethod;

    /// ```
    /// use satsim_integrate::Method;
    /// assert_eq!("dop853".parse::<Method>().unwrap(), Method::Dop853);
    /// assert!("euler".parse::<Method>().unwrap_err().to_string().contains("radau5"));
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownMethod(s.to_owned()))
    }
}

/// Integrator settings. Build with [`Options::new`] and the `with_*` setters,
/// or with struct update syntax from `Options::default()` (DP54, rtol 1e-6, atol 1e-9).
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// The method.
    pub method: Method,
    /// Relative tolerance (>= 0).
    pub rtol: f64,
    /// Absolute tolerance (> 0). It cannot be 0: a state component that is zero, or passes
    /// through zero, would have no error scale under a relative tolerance alone (its error
    /// norm infinite), and no step would pass the error test. `rtol = 0` (a pure absolute
    /// tolerance) is allowed.
    pub atol: f64,
    /// First step of an adaptive run; chosen automatically (Hairer's
    /// algorithm) when `None`.
    pub h0: Option<f64>,
    /// Largest step an adaptive method may take.
    pub h_max: f64,
    /// Maximum number of step attempts (accepted + rejected). A fixed-step run whose span
    /// takes more than this many steps of [`Options::fixed_step`] is refused before it starts.
    pub max_steps: usize,
    /// Run at this constant step without error control. Required by
    /// [`Method::Rk4`]; optional for the others (used to measure their order).
    /// The steps end on the grid `origin + n · step` ([`Options::grid_origin`]); a step is
    /// split where an output time, a time stop or `t_end` falls inside it, and an event
    /// that restarts the run is followed by the rest of its grid interval. The grid does
    /// not move with outputs or events, so a run cut into pieces of whole steps (each
    /// piece started with the same origin) takes the same steps as one run.
    pub fixed_step: Option<f64>,
    /// The origin of the fixed-step grid; `None` (the default): the run's start `t0`. A
    /// run resumed at a later time passes the first run's `t0` here to keep its steps.
    pub grid_origin: Option<f64>,
    /// Events are located to within this time (s).
    pub event_tol: f64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            method: Method::Dp54,
            rtol: 1e-6,
            atol: 1e-9,
            h0: None,
            h_max: f64::INFINITY,
            max_steps: 1_000_000,
            fixed_step: None,
            grid_origin: None,
            event_tol: 1e-10,
        }
    }
}

impl Options {
    /// Default options for `method`.
    pub fn new(method: Method) -> Self {
        Self {
            method,
            ..Self::default()
        }
    }
    /// Sets both tolerances.
    pub fn with_tolerances(mut self, rtol: f64, atol: f64) -> Self {
        self.rtol = rtol;
        self.atol = atol;
        self
    }
    /// Sets the fixed step (see [`Options::fixed_step`]).
    pub fn with_fixed_step(mut self, h: f64) -> Self {
        self.fixed_step = Some(h);
        self
    }
    /// Sets the origin of the fixed-step grid (see [`Options::grid_origin`]).
    pub fn with_grid_origin(mut self, origin: f64) -> Self {
        self.grid_origin = Some(origin);
        self
    }
    /// Sets the first step.
    pub fn with_h0(mut self, h0: f64) -> Self {
        self.h0 = Some(h0);
        self
    }
    /// Sets the largest step.
    pub fn with_h_max(mut self, h_max: f64) -> Self {
        self.h_max = h_max;
        self
    }
    /// Sets the maximum number of step attempts.
    pub fn with_max_steps(mut self, n: usize) -> Self {
        self.max_steps = n;
        self
    }
    /// Sets the event location tolerance.
    pub fn with_event_tol(mut self, tol: f64) -> Self {
        self.event_tol = tol;
        self
    }

    pub(crate) fn validate(&self) -> Result<(), IntegrateError> {
        let bad = |m: String| Err(IntegrateError::InvalidOptions(m));
        if !(self.rtol >= 0.0 && self.rtol.is_finite()) {
            return bad(format!("rtol must be finite and >= 0, got {}", self.rtol));
        }
        if !(self.atol > 0.0 && self.atol.is_finite()) {
            return bad(format!(
                "atol must be finite and > 0, got {}: under a relative tolerance alone a state \
                 component that is or passes through zero has no error scale; set atol to the \
                 absolute error acceptable in the smallest components",
                self.atol
            ));
        }
        // RADAU5 holds its order-3 error estimate to `0.1 rtol^(2/3)` with `atol` scaled by the
        // same factor over `rtol`: below ten rounding units that factor is out of scale (1e89
        // at rtol 1e-300) and every step passes. Hairer's code refuses such an rtol too.
        if self.method == Method::Radau5 && self.rtol > 0.0 && self.rtol < 10.0 * f64::EPSILON {
            return bad(format!(
                "rtol = {:e} is below ten rounding units ({:e}) for radau5: set it to 0 (atol alone) \
                 or at least that",
                self.rtol,
                10.0 * f64::EPSILON
            ));
        }
        if let Some(h0) = self.h0.filter(|h0| !(*h0 > 0.0 && h0.is_finite())) {
            return bad(format!("h0 must be finite and > 0, got {h0}"));
        }
        if self.h_max.is_nan() || self.h_max <= 0.0 {
            return bad(format!("h_max must be > 0, got {}", self.h_max));
        }
        if self.max_steps == 0 {
            return bad("max_steps must be > 0".into());
        }
        match self.fixed_step {
            Some(h) if !(h > 0.0 && h.is_finite()) => {
                return bad(format!("fixed_step must be finite and > 0, got {h}"));
            }
            None if self.method == Method::Rk4 => {
                return bad("rk4 is a fixed-step method: set fixed_step".into());
            }
            _ => {}
        }
        if let Some(o) = self.grid_origin.filter(|o| !o.is_finite()) {
            return bad(format!("grid_origin must be finite, got {o}"));
        }
        if !(self.event_tol > 0.0 && self.event_tol.is_finite()) {
            return bad(format!(
                "event_tol must be finite and > 0, got {}",
                self.event_tol
            ));
        }
        Ok(())
    }
}

/// When the observer is called.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// At `t0 + i * dt` for `i = 0, 1, ...` up to `t_end`, and at `t_end`; each time the
    /// double nearest to that decimal where `t0` and `dt` are short decimals
    /// ([`DecimalGrid`](crate::DecimalGrid): rows at `0.3`, not `0.30000000000000004`).
    Interval(f64),
    /// At these times (non-decreasing, within `[t0, t_end]`).
    Times(Vec<f64>),
    /// At `t0` and at the end of every accepted step (and at events that
    /// reset or stop the run, with the post-event state).
    Steps,
}

/// Iterates the requested output times without allocating.
#[derive(Debug)]
pub(crate) struct OutputTimes<'a> {
    /// Borrowed by one run, owned by a run of a batch (`lanes.rs`).
    kind: Cow<'a, Output>,
    t0: f64,
    t_end: f64,
    /// `Interval`'s times `t0 + i · dt`, as decimals.
    grid: Option<DecimalGrid>,
    i: usize,
    done: bool,
    /// The time at `i` ([`Self::peek`]).
    next: Option<f64>,
}

impl<'a> OutputTimes<'a> {
    pub(crate) fn new(kind: Cow<'a, Output>, t0: f64, t_end: f64) -> Result<Self, IntegrateError> {
        let bad = |m: String| Err(IntegrateError::InvalidOptions(m));
        match &*kind {
            Output::Interval(dt) if !(*dt > 0.0 && dt.is_finite()) => {
                return bad(format!("output interval must be finite and > 0, got {dt}"));
            }
            Output::Times(ts) => {
                if ts.iter().any(|t| !(*t >= t0 && *t <= t_end)) {
                    return bad(format!("output times must lie within [{t0}, {t_end}]"));
                }
                if ts.windows(2).any(|w| w[1] < w[0]) {
                    return bad("output times must be non-decreasing".into());
                }
            }
            _ => {}
        }
        let grid = match &*kind {
            Output::Interval(dt) => Some(DecimalGrid::new(t0, *dt)),
            _ => None,
        };
        let mut times = Self {
            kind,
            t0,
            t_end,
            grid,
            i: 0,
            done: false,
            next: None,
        };
        times.next = times.time_at(0);
        Ok(times)
    }

    /// The next pending output time, if any (`Steps` has none). Read before every step of a
    /// fixed-step run: kept, and made anew only when the output is taken.
    pub(crate) fn peek(&self) -> Option<f64> {
        self.next
    }

    /// The output time at `i`, unless done.
    fn time_at(&self, i: usize) -> Option<f64> {
        if self.done {
            return None;
        }
        match &*self.kind {
            Output::Steps => None,
            Output::Times(ts) => ts.get(i).copied(),
            Output::Interval(dt) => {
                let t = self.grid.expect("an interval's grid").point(i as f64);
                // Snap to t_end when within rounding of it, so t_end is hit exactly once. The
                // rounding scale is that of the times themselves (and of the interval, capped
                // at the span): an interval longer than the run still writes t0 and t_end.
                let span = self.t_end - self.t0;
                let scale = self.t_end.abs().max(self.t0.abs()).max(dt.min(span));
                if t >= self.t_end - 1e-12 * scale {
                    Some(self.t_end)
                } else {
                    Some(t)
                }
            }
        }
    }

    pub(crate) fn advance(&mut self) {
        if matches!(*self.kind, Output::Interval(_)) && self.next == Some(self.t_end) {
            self.done = true;
        }
        self.i += 1;
        self.next = self.time_at(self.i);
    }

    pub(crate) fn every_step(&self) -> bool {
        matches!(*self.kind, Output::Steps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(dt: f64, t0: f64, t_end: f64) -> Vec<f64> {
        let kind = Output::Interval(dt);
        let mut it = OutputTimes::new(Cow::Borrowed(&kind), t0, t_end).unwrap();
        let mut out = Vec::new();
        while let Some(t) = it.peek() {
            out.push(t);
            it.advance();
        }
        out
    }

    #[test]
    fn atol_must_be_finite_and_positive_while_rtol_may_be_zero() {
        let dp54 = || Options::new(Method::Dp54);
        for (rtol, atol) in [
            (1e-6, 0.0),
            (0.0, 0.0),
            (1e-6, -1e-9),
            (1e-6, f64::INFINITY),
            (1e-6, f64::NAN),
            (f64::INFINITY, 1e-9),
            (f64::NAN, 1e-9),
            (-1e-6, 1e-9),
        ] {
            let e = dp54().with_tolerances(rtol, atol).validate().unwrap_err();
            let IntegrateError::InvalidOptions(m) = e else {
                panic!("{e:?}")
            };
            let key = if rtol >= 0.0 && rtol.is_finite() {
                "atol"
            } else {
                "rtol"
            };
            assert!(m.starts_with(key), "rtol {rtol}, atol {atol}: {m}");
        }
        let m = dp54().with_tolerances(1e-6, 0.0).validate().unwrap_err();
        assert!(m.to_string().contains("passes through zero"), "{m}");
        // A pure absolute tolerance is legitimate.
        assert!(dp54().with_tolerances(0.0, 1e-10).validate().is_ok());
        // RADAU5's tolerance transform needs rtol = 0 or at least ten rounding units.
        let radau5 = |rtol| {
            Options::new(Method::Radau5)
                .with_tolerances(rtol, 1e-10)
                .validate()
        };
        let m = radau5(1e-300).unwrap_err().to_string();
        assert!(
            m.contains("rtol = 1e-300 is below ten rounding units"),
            "{m}"
        );
        assert!(radau5(0.0).is_ok() && radau5(1e-14).is_ok());
        assert!(dp54().with_tolerances(1e-300, 1e-10).validate().is_ok());
    }

    #[test]
    fn an_interval_longer_than_the_run_writes_the_first_and_last_times() {
        assert_eq!(times(1e16, 0.0, 2.0), [0.0, 2.0]);
        assert_eq!(times(3.0, 0.0, 2.0), [0.0, 2.0]);
        assert_eq!(times(1e16, 5.0, 7.0), [5.0, 7.0]);
    }

    #[test]
    fn interval_times_hit_the_end_once() {
        assert_eq!(times(0.5, 0.0, 2.0), [0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(times(0.75, 0.0, 2.0), [0.0, 0.75, 1.5, 2.0]);
        // 0.1 * 30 rounds to 3.0000000000000004: snapped, not a second row.
        let t = times(0.1, 0.0, 3.0);
        assert_eq!(t.len(), 31);
        assert_eq!(*t.last().unwrap(), 3.0);
    }
}
