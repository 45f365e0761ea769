//! [`Simulation`]: a tree, the enabled effects and the state layout derived from them,
//! implementing [`satsim_integrate::System`].
//!
//! # State layout
//!
//! `x = [attitude q (4), hinge angles (n), ω (3), root-origin velocity (3), hinge rates (n)]`
//! followed by each enabled effect's own states, in the effects' order (orbit: `r, v`;
//! reaction wheels: one speed per wheel). A fixed-base model has no attitude, `ω` or
//! velocity. Nothing else: a disabled effect is never constructed, adds no state and is never
//! visited. See [`StateLayout`].
//!
//! - `q` is the root (bus) attitude, root to inertial, Hamilton `[w, x, y, z]`;
//!   `q̇ = ½ q ⊗ (0, ω)`; [`System::project`](satsim_integrate::System::project) renormalises it after every step.
//! - `ω` and the velocity of the root frame's origin are in root axes. The root's position is
//!   not a state: no effect depends on it (the dynamics are invariant under translation and
//!   the gravity-gradient models use positions relative to the centre of mass). With an
//!   orbit, velocities are relative to the frame that falls with the centre of mass, and the
//!   initial root velocity is corrected so that the centre of mass is at rest in it (the
//!   orbit carries the centre of mass' motion).
//! - Reaction-wheel rotors are extra bodies of the tree, hinged to the root; their spin rates
//!   are the wheel effect's states and their (irrelevant) angles are not states.
//!
//! # Right-hand side
//!
//! unpack `x` → forward kinematics (only when an effect needs it; the centre of mass only
//! when an effect reads it) → each enabled effect adds hinge torques, body wrenches and its
//! own derivatives → ABA (hybrid ABA when hinges are locked; reusing the kinematics' hinge
//! transforms when they ran; the unrolled kernel, hybrid too, where the model has the
//! preprint's layout and no gimbal hinge is locked) → pack `dx`.
//!
//! # Event and output passes
//!
//! The event functions are evaluated at the end of every step. That pass computes only what
//! they read ([`Effect::event_reads`]): hinge stops and
//! slipping wheels read the state alone, so no effect is applied; a stuck wheel reads its
//! hold torque, and only then are the effects applied and the hybrid-dynamics solve run.
//! An output row applies the effects (their output columns may read what `apply` set) and
//! runs kinematics once, but no hold-torque solve (nothing in a row reads it).
//!
//! # Energy budget
//!
//! `T + V` (kinetic energy of the tree, wheels included, plus the effects'
//! [`Effect::potential_energy`]) changes by the work of the non-conservative forces. Two more
//! states (after the effects' own, unless [`SimulationBuilder::energy_budget`] turns them
//! off) integrate that work, exactly to the integrator's order: `W`, the work of the
//! actuators (the constant hinge torques, and each effect's [`Power::actuator`](crate::effects::Power::actuator)), and `D`, the
//! energy dissipated (each effect's [`Power::dissipated`](crate::effects::Power::dissipated)). Each effect's forces are measured
//! by the simulation, `Σ Δτ_k q̇_k + Σ Δf_i · v_i` over what its `apply` added, and the effect
//! splits that power in [`Effect::power`] (by default all of it is an actuator's), so a new
//! effect needs no special case. A jump of `T + V` at an event (a latching or rebounding
//! impact's impulse) is booked at the event: a loss into `D`, a gain into `W`. Then
//!
//! `energy_budget = T + V − W + D`
//!
//! is constant up to the integration error. `W` and `D` have zero weight in the error norm
//! ([`System::error_weights`](satsim_integrate::System::error_weights)), so tracking them leaves every other state as it was.
//!
//! # Files
//!
//! `build.rs` ([`SimulationBuilder`], set-up), `layout.rs` ([`StateLayout`]), `rhs.rs` (the
//! right-hand side's parts), `system.rs` (the [`System`](satsim_integrate::System) the integrators see), `events.rs`
//! (impulses, energy jumps at events), `rows.rs` (output rows, [`Diagnostics`]), `run.rs`
//! ([`Simulation::run`]).

mod build;
mod events;
mod layout;
mod rhs;
mod rows;
mod run;
mod system;
#[cfg(test)]
mod tests;

pub use build::SimulationBuilder;
pub use layout::StateLayout;
pub use rows::Diagnostics;
pub use run::RunError;

use crate::effects::{Effect, Forces, Request, Rotor};
use satsim_integrate::SystemError;
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{Data, DynamicsError, Model, ModelError, UnrolledAba};
use std::ops::Range;
use thiserror::Error;

/// Why a simulation could not be set up.
#[derive(Debug, Error)]
pub enum SimError {
    /// An effect's needs are not met, or effects conflict.
    #[error("{0}")]
    Needs(String),
    /// The initial state does not fit the model.
    #[error("initial state: {0}")]
    State(String),
    /// The model with the effects' rotors added is invalid.
    #[error("model with reaction-wheel rotors: {0}")]
    Model(#[from] ModelError),
    /// An effect rejected the initial state.
    #[error("{0}")]
    Start(SystemError),
    /// The dynamics failed on the initial state.
    #[error("initial state: {0}")]
    Dynamics(#[from] DynamicsError),
}

/// A scene ready to integrate: see the module documentation.
pub struct Simulation {
    model: Model,
    data: Data,
    /// ABA unrolled for the model's layout, where it has the preprint's (`rhs` uses it,
    /// with the effects' wrenches, unless a gimbal hinge is locked).
    unrolled: Option<UnrolledAba>,
    layout: StateLayout,
    effects: Vec<Box<dyn Effect>>,
    own: Vec<Range<usize>>,
    calls: Vec<u64>,
    event_start: Vec<usize>,
    n_events: usize,
    n_user: usize,
    n_rotors: usize,
    rotor_effect: Option<usize>,
    /// Where the tree's whole velocity vector lies in the state, as one run (see
    /// `velocity_in_state` in build.rs); `None`: in pieces.
    velocity_at: Option<usize>,
    orbit_effect: Option<usize>,
    needs_kinematics: bool,
    /// Whether an effect reads [`Context::com`](crate::effects::Context::com) (computed
    /// only then).
    needs_com: bool,
    base_tau: Vec<f64>,
    locked: Vec<bool>,
    n_locked: usize,
    q: Vec<f64>,
    v: Vec<f64>,
    tau: Vec<f64>,
    forces: Forces,
    scratch: Vec<f64>,
    requests: Vec<Request>,
    /// Hold torques (see [`Context::hold_torque`]) and their work buffers.
    needs_hold: bool,
    hold: Vec<f64>,
    hold_mask: Vec<bool>,
    hold_ddq: Vec<f64>,
    x0: Vec<f64>,
    t0: f64,
    rhs_evals: u64,
    log: Vec<(f64, String)>,
    /// The effect (index into `effects`) of each `log` entry.
    log_effect: Vec<usize>,
    /// The energy budget's states in `x`: `[actuator work, dissipated energy]` (J), or
    /// empty when not tracked.
    work: Range<usize>,
}

impl Simulation {
    /// The state layout.
    pub fn layout(&self) -> &StateLayout {
        &self.layout
    }
    /// The tree (the scene's model plus rotor bodies).
    pub fn model(&self) -> &Model {
        &self.model
    }
    /// The initial state `x0`.
    pub fn x0(&self) -> &[f64] {
        &self.x0
    }
    /// The initial time.
    pub fn t0(&self) -> f64 {
        self.t0
    }
    /// Names of the enabled effects, in the order they are visited.
    pub fn effect_names(&self) -> Vec<&str> {
        self.effects.iter().map(|e| e.name()).collect()
    }
    /// How many times each enabled effect was applied by [`System::rhs`](satsim_integrate::System::rhs), in the order of
    /// [`Simulation::effect_names`].
    pub fn effect_calls(&self) -> &[u64] {
        &self.calls
    }
    /// Right-hand-side evaluations so far.
    pub fn rhs_evals(&self) -> u64 {
        self.rhs_evals
    }
    /// Which hinges (model hinges, then rotors) are locked now.
    pub fn locked(&self) -> &[bool] {
        &self.locked
    }
    /// The constant hinge torques every evaluation starts from before the effects add
    /// theirs (N m, tree hinge order: the model's hinges, then the rotors): the initial
    /// state's `torque`, zero on the rotors. [`crate::linearize`] perturbs them to form `B`.
    pub fn constant_torques_mut(&mut self) -> &mut [f64] {
        &mut self.base_tau
    }
    /// Unlocks hinge `h` (tree order) as if its effect had released it (a no-op when it is
    /// not locked). [`crate::linearize`] frees wheels held by static friction this way.
    pub fn release(&mut self, h: usize) {
        if self.locked.get(h).copied().unwrap_or(false) {
            self.locked[h] = false;
            self.n_locked -= 1;
        }
    }
    /// What happened at each handled event: `(t, description)`.
    pub fn event_log(&self) -> &[(f64, String)] {
        &self.log
    }
    /// Every handled event as `(t, effect name, description)`, in order (the
    /// [`event_log`](Self::event_log) with the effect whose event it was).
    pub fn event_records(&self) -> impl Iterator<Item = (f64, &str, &str)> {
        self.log
            .iter()
            .zip(&self.log_effect)
            .map(|((t, what), &i)| (*t, self.effects[i].name(), what.as_str()))
    }
    /// The effect called `name`, if enabled.
    pub fn effect(&self, name: &str) -> Option<&dyn Effect> {
        self.effects
            .iter()
            .find(|e| e.name() == name)
            .map(|e| e.as_ref())
    }
}

/// The unit quaternion norm check used by tests: `|‖q‖ − 1|` of the attitude in `x`.
pub fn attitude_norm_error(layout: &StateLayout, x: &[f64]) -> f64 {
    let n = x[layout.attitude.clone()]
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt();
    (n - 1.0).abs()
}

/// Rotor inertia helper re-exported for examples.
pub fn rotor_inertia(axis: Vec3, axial: f64, transverse: f64) -> Mat3 {
    Rotor {
        name: String::new(),
        axis,
        at: Vec3::zeros(),
        mass: 0.0,
        axial,
        transverse,
    }
    .inertia()
}
