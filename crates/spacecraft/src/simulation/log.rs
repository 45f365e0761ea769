//! [`RunLog`]: what a run has done so far.

/// Events the log has room for when the simulation is built: handling the first this many
/// allocates nothing; more grow it (amortised).
const RESERVED_EVENTS: usize = 64;

/// Counters and the record of handled events; the only part of a
/// [`Simulation`](super::Simulation) that outlives a pass as history.
#[derive(Clone, Debug)]
pub struct RunLog {
    /// Right-hand-side evaluations.
    pub(super) rhs_evals: u64,
    /// Of those, the ones whose dynamics were solved in the lanes of a batch of runs
    /// (`lanes.rs`).
    pub(super) lane_rhs: u64,
    /// Right-hand sides answered by the slope the event functions had just evaluated at the
    /// same state (`ahead.rs`): not evaluated again, so not in `rhs_evals`.
    pub(super) reused_rhs: u64,
    /// Of `rhs_evals`, the right-hand sides that the event functions took from the lanes of
    /// a batch, which had evaluated them at the step's end (`ahead.rs`).
    pub(super) lane_ahead: u64,
    /// How many times each effect was applied by the right-hand side (the effects' order).
    pub(super) calls: Vec<u64>,
    /// Each handled event: `(t, description)`, and the effect whose event it was.
    pub(super) events: Vec<(f64, String)>,
    pub(super) event_effects: Vec<usize>,
    /// Strings reserved for the events' descriptions, taken as events come.
    pub(super) spare: Vec<String>,
}

impl Default for RunLog {
    fn default() -> Self {
        Self {
            rhs_evals: 0,
            lane_rhs: 0,
            reused_rhs: 0,
            lane_ahead: 0,
            calls: Vec::new(),
            events: Vec::with_capacity(RESERVED_EVENTS),
            event_effects: Vec::with_capacity(RESERVED_EVENTS),
            spare: (0..RESERVED_EVENTS)
                .map(|_| String::with_capacity(crate::effects::EVENT_TEXT))
                .collect(),
        }
    }
}

impl RunLog {
    /// Right-hand-side evaluations so far.
    pub fn rhs_evals(&self) -> u64 {
        self.rhs_evals
    }
    /// Of [`RunLog::rhs_evals`], the right-hand sides whose dynamics were solved together
    /// with other runs' in SIMD lanes ([`Simulation::run_lanes`](super::Simulation::run_lanes)).
    pub fn lane_rhs(&self) -> u64 {
        self.lane_rhs
    }
    /// Right-hand sides answered by the slope the event functions had just evaluated at the
    /// same state, instead of being evaluated again (not counted in
    /// [`RunLog::rhs_evals`]; see [`Simulation::reuse_event_slopes`](super::Simulation::reuse_event_slopes)).
    pub fn reused_rhs(&self) -> u64 {
        self.reused_rhs
    }
    /// Of [`RunLog::rhs_evals`], the right-hand sides that the event functions took from
    /// the lanes of a batch of runs, which had evaluated them together at the steps' ends.
    pub fn lane_ahead(&self) -> u64 {
        self.lane_ahead
    }
    /// What happened at each handled event: `(t, description)`.
    pub fn events(&self) -> &[(f64, String)] {
        &self.events
    }
}
