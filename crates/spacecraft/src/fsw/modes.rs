//! Modes of the flight software (`[[fsw.mode]]`, contract section 16): which blocks run, and
//! the condition that ends each mode.
//!
//! The modes run in order, the first from the start. The blocks a mode runs are at most one
//! estimator, one guidance, one control and one magnetic block (B-dot or momentum dumping).
//! After the blocks ran at a sample instant, the mode's condition is checked; when it has
//! held for the mode's `hold` (s, 0 by default: at once), the next mode begins there. A
//! condition is one of
//!
//! ```text
//! rate < x     |ω| (rad/s): the mode's estimate of the rate when it has one (the gyro's
//!              reading less the estimated bias), else the raw reading of the mode's gyro
//! error < x    the angle (rad) between the mode's estimate and its guidance law's
//!              reference (before any slew shaping: the attitude the slew goes to), both
//!              the flight software's own, never the truth
//! time > x     the time (s) since the mode began
//! ```
//!
//! checked at every sample instant of the scene's sensors. A block that enters a mode it
//! was not running in starts afresh (an estimator without an estimate, a PID with a zero
//! integral, a slew from the current estimate, B-dot without a previous reading), and one
//! that leaves stops commanding (its held commands are zero); a block that runs in both
//! goes on unchanged. Each switch is an event of the run's log.

use std::fmt;

/// What ends a mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Condition {
    /// `|ω| < x` (rad/s).
    RateBelow(f64),
    /// The estimate's angle to the reference `< x` (rad).
    ErrorBelow(f64),
    /// The time in the mode `> x` (s).
    TimeAfter(f64),
}

impl Condition {
    /// Reads `"rate < 0.005"`, `"error < 0.01"` or `"time > 600"` (spaces optional, the
    /// number finite and `>= 0`).
    ///
    /// ```
    /// use satsim_spacecraft::fsw::Condition;
    /// assert_eq!(Condition::parse("rate < 0.005"), Ok(Condition::RateBelow(0.005)));
    /// assert_eq!(Condition::parse("time>600"), Ok(Condition::TimeAfter(600.0)));
    /// assert!(Condition::parse("rate > 0.005").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<Self, String> {
        let expected = "expected \"rate < X\" (rad/s), \"error < X\" (rad) or \"time > X\" (s)";
        let (what, op, x) = ["<", ">"]
            .iter()
            .find_map(|op| s.split_once(op).map(|(a, b)| (a.trim(), *op, b.trim())))
            .ok_or_else(|| format!("unknown condition `{s}`: {expected}"))?;
        let x: f64 = x
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite() && *x >= 0.0)
            .ok_or_else(|| format!("condition `{s}`: `{x}` is not a finite number >= 0"))?;
        match (what, op) {
            ("rate", "<") => Ok(Condition::RateBelow(x)),
            ("error", "<") => Ok(Condition::ErrorBelow(x)),
            ("time", ">") => Ok(Condition::TimeAfter(x)),
            _ => Err(format!("unknown condition `{s}`: {expected}")),
        }
    }

    /// Whether it holds for this rate, error and time in the mode (`None`: not known yet,
    /// so it does not hold).
    pub(crate) fn holds(&self, rate: Option<f64>, error: Option<f64>, time: f64) -> bool {
        match *self {
            Condition::RateBelow(x) => rate.is_some_and(|r| r < x),
            Condition::ErrorBelow(x) => error.is_some_and(|e| e < x),
            Condition::TimeAfter(x) => time > x,
        }
    }
}

impl fmt::Display for Condition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Condition::RateBelow(x) => write!(f, "rate < {x}"),
            Condition::ErrorBelow(x) => write!(f, "error < {x}"),
            Condition::TimeAfter(x) => write!(f, "time > {x}"),
        }
    }
}

/// A mode: its name, the blocks it runs (indices in the [`Onboard`](super::Onboard)'s lists
/// of each kind) and what ends it.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    /// Its name (the events name it).
    pub name: String,
    /// The estimator it runs.
    pub estimator: Option<usize>,
    /// The guidance it runs.
    pub guidance: Option<usize>,
    /// The control it runs.
    pub control: Option<usize>,
    /// The magnetic block it runs.
    pub magnetic: Option<usize>,
    /// What ends it (`None`: it lasts; only the last mode may).
    pub until: Option<Condition>,
    /// How long the condition must hold before the switch (s, >= 0).
    pub hold: f64,
    /// The gyro (index in the sensor set) whose raw reading `rate < x` reads when the mode
    /// has no estimator.
    pub gyro: Option<usize>,
}

impl Mode {
    /// A mode called `name` that runs no block and lasts.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            estimator: None,
            guidance: None,
            control: None,
            magnetic: None,
            until: None,
            hold: 0.0,
            gyro: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conditions_read_and_hold_as_written() {
        assert_eq!(
            Condition::parse(" error<0.01 "),
            Ok(Condition::ErrorBelow(0.01))
        );
        for bad in [
            "rate",
            "rate < -1",
            "rate < nan",
            "time < 5",
            "speed < 1",
            "rate < 1e400",
        ] {
            assert!(Condition::parse(bad).is_err(), "{bad}");
        }
        let c = Condition::RateBelow(0.01);
        assert!(c.holds(Some(0.005), None, 0.0));
        assert!(!c.holds(Some(0.02), None, 0.0) && !c.holds(None, None, 0.0));
        assert!(Condition::TimeAfter(10.0).holds(None, None, 10.5));
        assert!(!Condition::TimeAfter(10.0).holds(None, None, 10.0));
        assert_eq!(
            Condition::parse("time > 600").unwrap().to_string(),
            "time > 600"
        );
    }
}
