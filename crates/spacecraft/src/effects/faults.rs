//! Faults injected at a time (a scene's `[[faults]]`, contract section 17): what fails, and
//! the schedule an effect keeps of the faults on its own parts.
//!
//! Each fault belongs to the effect that owns its target: a wheel's to
//! [`ReactionWheels`](super::ReactionWheels), a thruster's to [`Thrusters`](super::Thrusters),
//! a sensor's to [`Sensors`](crate::sensors::Sensors). The owner makes the fault's time `at`
//! one of its time stops ([`Effect::next_sample`](super::Effect::next_sample)), so that every
//! integrator lands a step exactly there, applies the fault there, and logs it in the run's
//! events (`events.csv`) at `at`:
//!
//! - `wheel_stuck`: the bearing seizes. The wheel's hinge is locked, its speed relative to the
//!   bus removed by a momentum-conserving impulse (as a wheel stuck by static friction), and
//!   it never breaks free: its motor, friction and speed limits act no more.
//! - `wheel_off`: the motor gives no torque (its commands are ignored); friction goes on. A
//!   wheel held at its speed limit is released.
//! - `thruster_stuck_on`: the valve stays open: full thrust from `at` on, whatever the
//!   commands. `thruster_off`: it never fires again.
//! - `sensor_stuck`: every reading from `at` on is the last one taken before `at`.
//! - `sensor_bias`: `value` (the sensor's units, one per component of its reading) is added
//!   to every reading taken from `at` on.

/// What fails (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub enum FaultKind {
    /// A wheel's bearing seizes.
    WheelStuck,
    /// A wheel's motor gives no torque.
    WheelOff,
    /// A thruster fires at full thrust from then on.
    ThrusterStuckOn,
    /// A thruster never fires again.
    ThrusterOff,
    /// A sensor's reading freezes.
    SensorStuck,
    /// A bias added to a sensor's readings, one value per component (its units).
    SensorBias(Vec<f64>),
}

impl FaultKind {
    /// The scene's names of the kinds, in the order of [`FaultKind`].
    pub const NAMES: [&'static str; 6] = [
        "wheel_stuck",
        "wheel_off",
        "thruster_stuck_on",
        "thruster_off",
        "sensor_stuck",
        "sensor_bias",
    ];
    /// The scene's name of the kind.
    pub fn name(&self) -> &'static str {
        match self {
            FaultKind::WheelStuck => Self::NAMES[0],
            FaultKind::WheelOff => Self::NAMES[1],
            FaultKind::ThrusterStuckOn => Self::NAMES[2],
            FaultKind::ThrusterOff => Self::NAMES[3],
            FaultKind::SensorStuck => Self::NAMES[4],
            FaultKind::SensorBias(_) => Self::NAMES[5],
        }
    }
}

/// One fault on one of an effect's parts.
#[derive(Clone, Debug, PartialEq)]
pub struct Scheduled {
    /// When it happens (s, finite, >= 0).
    pub at: f64,
    /// Which part (the effect's index of its wheel, thruster or sensor).
    pub target: usize,
    /// What fails.
    pub kind: FaultKind,
    /// Whether it happened.
    pub done: bool,
}

/// The faults on an effect's parts, and which of them happened. An effect's copy made
/// before a run has none happened, so every run applies them afresh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Schedule(Vec<Scheduled>);

impl Schedule {
    /// Adds the fault `kind` on part `target` at `at` (s).
    pub fn push(&mut self, at: f64, target: usize, kind: FaultKind) {
        self.0.push(Scheduled {
            at,
            target,
            kind,
            done: false,
        });
    }
    /// The faults, in the order they were added.
    pub fn list(&self) -> &[Scheduled] {
        &self.0
    }
    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    /// How many it holds.
    pub fn len(&self) -> usize {
        self.0.len()
    }
    /// The earliest time of a fault still to happen (`∞` when none): a time stop.
    pub fn next(&self) -> f64 {
        self.0
            .iter()
            .filter(|f| !f.done)
            .fold(f64::INFINITY, |m, f| m.min(f.at))
    }
    /// A fault due at `t` (per [`satsim_integrate::stop_due`]) that had not happened, now
    /// marked as happened: its index, or `None` when none is left (no allocation).
    pub fn take_due(&mut self, t: f64) -> Option<usize> {
        let k = self
            .0
            .iter()
            .position(|f| !f.done && satsim_integrate::stop_due(t, f.at))?;
        self.0[k].done = true;
        Some(k)
    }
}

/// A reading or bias as the event log shows it: `[1.5, -2, 0.25]`.
pub fn show(values: &[f64]) -> String {
    let parts: Vec<String> = values.iter().map(|v| format!("{v}")).collect();
    format!("[{}]", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_schedule_gives_each_fault_once_at_its_time_and_then_the_next() {
        let mut s = Schedule::default();
        assert_eq!(s.next(), f64::INFINITY);
        s.push(300.0, 1, FaultKind::WheelOff);
        s.push(100.0, 0, FaultKind::WheelStuck);
        s.push(100.0, 2, FaultKind::WheelOff);
        assert_eq!(s.next(), 100.0);
        assert_eq!(s.take_due(99.0), None);
        // Within the stops' round-off of 100 s: due.
        assert_eq!(s.take_due(100.0 - 1e-11), Some(1));
        assert_eq!(s.take_due(100.0), Some(2));
        assert_eq!(s.take_due(100.0), None);
        assert_eq!(s.next(), 300.0);
        assert_eq!(s.take_due(400.0), Some(0));
        assert_eq!(s.next(), f64::INFINITY);
        assert!(s.list().iter().all(|f| f.done));
        assert_eq!(FaultKind::SensorBias(vec![1.0]).name(), "sensor_bias");
        assert_eq!(show(&[1.5, -2.0]), "[1.5, -2]");
    }
}
