//! [`Sampling`]: the clock of a discrete-time law (a controller with a `period`).
//!
//! The law is evaluated at the start of the run and at every multiple of the period after it
//! (`t = 0, period, 2 period, …` for a run from 0), and its output held in between (a
//! zero-order hold). The simulation lands a step exactly on each sample instant (a time stop
//! of the integrator, [`satsim_integrate::System::next_stop`]) and calls the effect's
//! [`Effect::sample`](super::Effect::sample) there, so the held output is exactly constant
//! over each sample interval, whatever the integrator.

use satsim_integrate::DecimalGrid;

/// The sample instants of a discrete-time law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// The instants `k · period`, as decimals: the same doubles as a fixed step's grid and
    /// an output interval's rows where the decimals meet, so no sliver step between them.
    grid: DecimalGrid,
    next: f64,
}

impl Sampling {
    /// A clock of this period (s); `None` unless it is finite and > 0. The first sample is
    /// due at once (the start of the run).
    ///
    /// ```
    /// use satsim_spacecraft::effects::Sampling;
    /// let mut s = Sampling::new(0.1).unwrap();
    /// assert_eq!(s.next(), f64::NEG_INFINITY);
    /// s.taken(0.0);
    /// assert_eq!(s.next(), 0.1);
    /// s.taken(0.2);
    /// assert_eq!(s.next(), 0.3); // the decimal, where 3.0 * 0.1 is 0.30000000000000004
    /// s.taken(0.1 + 0.1 + 0.1); // 0.30000000000000004, reached as a sum of steps
    /// assert_eq!(s.next(), 4.0 * 0.1);
    /// assert!(Sampling::new(0.0).is_none() && Sampling::new(f64::NAN).is_none());
    /// ```
    pub fn new(period: f64) -> Option<Self> {
        (period > 0.0 && period.is_finite()).then_some(Self {
            grid: DecimalGrid::new(0.0, period),
            next: f64::NEG_INFINITY,
        })
    }
    /// The period (s).
    pub fn period(&self) -> f64 {
        self.grid.step()
    }
    /// The next sample instant: `k · period` (the double nearest to that decimal where the
    /// period is a short one: [`DecimalGrid`]), the first after the last sample taken (`-∞`
    /// before the first).
    pub fn next(&self) -> f64 {
        self.next
    }
    /// A sample was taken at `t`: the next instant is the first multiple of the period after
    /// it (a `t` within a millionth of a period below a multiple counts as that multiple,
    /// so that a stop met within round-off moves on).
    pub fn taken(&mut self, t: f64) {
        self.next = self.grid.next_after(t, 1e-6);
    }
}
