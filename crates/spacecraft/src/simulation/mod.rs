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
//! unpack `x` → forward kinematics (only when an effect needs it, the poses alone where no
//! effect reads the bodies' velocities, and then not the rotors' where no effect reads a
//! rotor's pose; the centre of mass only when an effect reads it) → each enabled effect adds hinge torques, body wrenches and its
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
//! - `rhs.rs`: **the right-hand side**, one pipeline read top to bottom (unpack → kinematics →
//!   effects → dynamics → pack), and the stages every other pass runs;
//! - `model.rs` ([`SimModel`], made once), `data.rs` ([`SimData`], written by every pass),
//!   `log.rs` ([`RunLog`]), `layout.rs` ([`StateLayout`]), `build.rs` ([`SimulationBuilder`]);
//! - `solve.rs` (the dynamics stage's solves, which the right-hand side and the hold
//!   torques share);
//! - `context.rs` (what the effects' hooks see and write), `hold.rs` (hold torques),
//!   `events.rs` (the event functions' pass, requests, impulses, energy jumps), `system.rs`
//!   (the [`System`](satsim_integrate::System) the integrators see), `rows.rs` (output rows,
//!   [`Diagnostics`]), `run.rs` ([`Simulation::run`]), `lanes.rs` ([`Simulation::run_lanes`]:
//!   runs of a batch with their dynamics solved together in SIMD lanes), `stepping.rs` ([`Stepping`]: the
//!   simulation advanced a piece at a time from outside, with inputs held between pieces;
//!   and the time stops of the effects' discrete-time laws).

mod ahead;
mod build;
mod context;
mod data;
mod events;
mod hold;
mod jacobian;
mod lanes;
mod layout;
mod loads;
mod log;
mod model;
mod rhs;
mod rows;
mod run;
mod solve;
mod stepping;
mod system;

pub use build::{SimulationBuilder, with_rotors};
pub use data::{DeflectionPeak, SimData};
pub use lanes::{LaneJob, LaneJobs, RowSink};
pub use layout::StateLayout;
pub use loads::{EffectLoads, moment_about};
pub use log::RunLog;
pub use model::{NamedDynamicsError, SimModel};
pub use rows::Diagnostics;
pub use run::{RunError, elastic_error_refusal};
pub use stepping::{EventRecord, OutputGrid, StepError, StepWork, Stepping};

use crate::effects::{Effect, Rotor};
use satsim_integrate::SystemError;
use satsim_tree::flexible::{FlexError, FlexModel};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{DynamicsError, ForwardDynamics, Model, ModelError};
use thiserror::Error;

/// The spread of the energy budget over a run's rows, as a share of the largest of its
/// terms, beyond which [`Simulation::budget_warning`] speaks. Every shipped scene's budget
/// stays within 3e-7 of it except the flexible deployment's (1.8e-3: the ringing Radau IIA
/// damps where `elastic_error = false` leaves it unresolved).
pub const BUDGET_DRIFT: f64 = 0.01;

/// Whether an energy budget whose output rows spread over `spread` J (largest less
/// smallest), its terms reaching `scale` J, moved by more than [`BUDGET_DRIFT`] of it:
/// [`Simulation::budget_warning`]'s test, and a campaign's for each run from its
/// `min_`/`max_` columns.
pub fn budget_drifted(spread: f64, scale: f64) -> bool {
    spread > BUDGET_DRIFT * scale
}

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
    /// The flexible bodies do not fit the tree with the effects' rotors.
    #[error("flexible bodies: {0}")]
    Flexible(#[from] FlexError),
    /// The dynamics failed on the initial state.
    #[error("initial state: {0}")]
    Dynamics(#[from] DynamicsError),
}

/// A scene ready to integrate: see the module documentation.
///
/// As in `satsim-tree`, what is made once is apart from what a run writes: the
/// [`SimModel`] (the tree with the effects' rotors, the state layout, the effects'
/// places in it, the dynamics' kernel) is never written during a run; the [`SimData`] holds
/// the scratch of every evaluation and the discrete state that `x` does not hold (locks,
/// held torques); the [`RunLog`] counts evaluations and records the events. The effects
/// change their modes at events and their held outputs at their samples; every run starts
/// from fresh copies of them, so that a second run gives the first's bits (see
/// [`Simulation::run`]).
pub struct Simulation {
    model: SimModel,
    effects: Vec<Box<dyn Effect>>,
    /// The effects as given (in `effects`' order), to start from again; `None` for one
    /// given without a copy.
    fresh: Vec<Option<Box<dyn build::Fresh>>>,
    data: SimData,
    log: RunLog,
    x0: Vec<f64>,
    /// The initial state before the effects' start hooks.
    x_start: Vec<f64>,
    /// Whether a run (or a [`Stepping`]) has started.
    ran: bool,
    t0: f64,
}

impl Simulation {
    /// What was made once: the tree with the rotors, the layout, the effects' places, the
    /// kernel.
    pub fn sim_model(&self) -> &SimModel {
        &self.model
    }
    /// The buffers of the last pass and the discrete state (locks, constant torques).
    pub fn data(&self) -> &SimData {
        &self.data
    }
    /// Evaluations counted and events handled so far.
    pub fn run_log(&self) -> &RunLog {
        &self.log
    }
    /// The state layout.
    pub fn layout(&self) -> &StateLayout {
        &self.model.layout
    }
    /// The tree (the scene's model plus rotor bodies).
    pub fn model(&self) -> &Model {
        &self.model.tree
    }
    /// The tree with its flexible bodies' modes, when it has any.
    pub fn flex_model(&self) -> Option<&FlexModel> {
        self.model.flex.as_ref()
    }
    /// `<body>_<k>` for every elastic coordinate, in the state's order (`eta_` and `etadot_`
    /// prefix them in the columns; `k` from 1).
    pub fn elastic_names(&self) -> Vec<String> {
        let Some(f) = &self.model.flex else {
            return Vec::new();
        };
        let tree = f.rigid();
        (0..tree.n_bodies())
            .flat_map(|i| (1..=f.modes(i)).map(move |k| format!("{}_{k}", tree.bodies()[i].name())))
            .collect()
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
        &self.log.calls
    }
    /// Right-hand-side evaluations so far.
    pub fn rhs_evals(&self) -> u64 {
        self.log.rhs_evals
    }
    /// Which hinges (model hinges, then rotors) are locked now.
    pub fn locked(&self) -> &[bool] {
        &self.data.locked
    }
    /// The constant hinge torques every evaluation starts from before the effects add
    /// theirs (N m, tree hinge order: the model's hinges, then the rotors): the initial
    /// state's `torque`, zero on the rotors. The linearisation (`satsim_tools::linearize`) perturbs them to form `B`.
    pub fn constant_torques_mut(&mut self) -> &mut [f64] {
        self.forget_ahead();
        &mut self.data.base_tau
    }
    /// Unlocks hinge `h` (tree order) as if its effect had released it (a no-op when it is
    /// not locked). The linearisation frees wheels held by static friction this way.
    pub fn release(&mut self, h: usize) {
        self.forget_ahead();
        if self.data.locked.get(h).copied().unwrap_or(false) {
            self.data.locked[h] = false;
            self.data.n_locked -= 1;
        }
    }
    /// Each watched flexible body's largest deflection over the accepted steps of the runs
    /// so far (the initial state not among them), in the model's body order: a beam's tip,
    /// or for given modes the watched point bent most for its distance from the body's
    /// frame. Where one passed [`SMALL_DEFLECTION`](satsim_tree::flexible::SMALL_DEFLECTION)
    /// of its length, the run went beyond what its modal model holds. Empty without
    /// watched bodies.
    pub fn deflection_peaks(&self) -> &[DeflectionPeak] {
        &self.data.deflection_peaks
    }
    /// A warning for each watched body whose deflection went past
    /// [`SMALL_DEFLECTION`](satsim_tree::flexible::SMALL_DEFLECTION) of its length in the
    /// runs so far ([`Self::deflection_peaks`]): the results from then on are not the
    /// structure's, though the model may go on without a sign (the linear model, without
    /// `stiffening`, has no term that fails with the deflection).
    pub fn deflection_warnings(&self) -> Vec<String> {
        self.deflection_peaks()
            .iter()
            .filter_map(|p| self.deflection_warning(p))
            .collect()
    }

    /// The [`Self::deflection_warnings`] of the body bent most for its size, where one went
    /// past a tenth of it: why a run that failed there failed.
    pub fn deflection_failure(&self) -> Option<String> {
        self.deflection_peaks()
            .iter()
            .filter(|p| p.passed.is_some())
            .max_by(|a, b| a.fraction().total_cmp(&b.fraction()))
            .and_then(|p| self.deflection_warning(p))
    }

    /// The warning of peak `p`, where its body went past a tenth of its size.
    fn deflection_warning(&self, p: &DeflectionPeak) -> Option<String> {
        let f = self.model.flex.as_ref()?;
        let passed = p.passed?;
        let body = f.rigid().bodies()[p.body].name();
        let consequence = format!(
            "beyond what its modal model holds (a few per cent of the length), so the run's results from t = {passed:.4} s on are not the structure's: stiffen the body, or soften what drives it (a spring, a controller, a load)"
        );
        let length = satsim_tree::error::Num(p.length);
        Some(match p.point {
            None => format!(
                "body `{body}`'s tip passed a tenth of its {length} m length at t = {passed:.4} s and went {:.4} m off its axis ({:.0} % of the length) at t = {:.4} s: {consequence}",
                p.tip.abs(),
                100.0 * p.fraction(),
                p.t,
            ),
            Some(k) => format!(
                "body `{body}` passed a tenth of its size at t = {passed:.4} s: its node `{}` moved {:.4} m at t = {:.4} s, {:.0} % of its {length} m from the body's frame, {consequence}",
                f.watch_points(p.body)[k].name,
                p.tip.abs(),
                p.t,
                100.0 * p.fraction(),
            ),
        })
    }

    /// A warning where the energy budget (`T + V − W + D`, constant along the exact motion)
    /// moved over the output rows (its largest less its smallest) by more than
    /// [`BUDGET_DRIFT`] of the largest of its terms any row showed ([`budget_drifted`]):
    /// the integration's error, not the structure's behaviour. RK4 at a step inside a fast
    /// mode's stability limit but near it damps that mode (a third of a panel's energy in a
    /// second, where the stability check passes), and a loose tolerance lets the energy
    /// wander; with `elastic_error = false`, Radau IIA damps the ringing it steps over, which
    /// the warning then names first. `None` without an energy budget
    /// (`SimulationBuilder::energy_budget(false)`) or rows.
    pub fn budget_warning(&self) -> Option<String> {
        let b = self.data.budget;
        let spread = b.max - b.min;
        // With the elastic coordinates out of the error, the likeliest cause is the implicit
        // method damping the ringing it steps over, which no step or tolerance setting names.
        let left_out = if self.model.elastic_error || self.model.flex.is_none() {
            ""
        } else {
            "with `integrator.elastic_error = false` the implicit method damps the ringing of the modes it steps over (`true` resolves them), "
        };
        budget_drifted(spread, b.scale).then(|| {
            format!(
                "the energy budget moved by {spread:.3e} J over the run (between {:.6e} J and {:.6e} J, {:.1} % of the {:.3e} J its largest energy term reached): along the exact motion it is constant, so this is the integration's error, not the structure's behaviour: {left_out}a fixed step near a fast mode's stability limit damps that mode (shorten `integrator.step`: `satsim modes` lists the modes; or use an adaptive method), or the tolerance is too loose (tighten `rtol` and `atol`)",
                b.min,
                b.max,
                100.0 * spread / b.scale,
                b.scale,
            )
        })
    }
    /// What `satsim run` warns of after a run (the runs so far): the flexible bodies bent
    /// beyond their modal model ([`Self::deflection_warnings`]), then an energy budget that
    /// did not close ([`Self::budget_warning`]).
    pub fn run_warnings(&self) -> Vec<String> {
        let mut w = self.deflection_warnings();
        w.extend(self.budget_warning());
        w
    }
    /// What happened at each handled event: `(t, description)`.
    pub fn event_log(&self) -> &[(f64, String)] {
        &self.log.events
    }
    /// Every handled event as `(t, effect name, description)`, in order (the
    /// [`event_log`](Self::event_log) with the effect whose event it was).
    pub fn event_records(&self) -> impl Iterator<Item = (f64, &str, &str)> {
        self.log
            .events
            .iter()
            .zip(&self.log.event_effects)
            .map(|((t, what), &i)| (*t, self.effects[i].name(), what.as_str()))
    }
    /// The effect called `name`, if enabled.
    pub fn effect(&self, name: &str) -> Option<&dyn Effect> {
        self.effects
            .iter()
            .find(|e| e.name() == name)
            .map(|e| e.as_ref())
    }
    /// The enabled effects, in the order they are visited.
    pub fn effects(&self) -> impl Iterator<Item = &dyn Effect> {
        self.effects.iter().map(|e| e.as_ref())
    }
    /// Drops the layout's kernel: every solve from now on takes the generic ABA (to compare
    /// the two, or to time the kernel's gain).
    pub fn use_generic_dynamics(&mut self) {
        self.forget_ahead();
        self.model.fd = ForwardDynamics::new(&self.model.tree);
    }
    /// Whether every evaluation runs the forward kinematics (an effect needs the poses).
    pub fn runs_kinematics(&self) -> bool {
        self.data.needs_kinematics
    }
    /// Whether an effect reads hold torques ([`Context::hold_torque`](crate::effects::Context::hold_torque)).
    pub fn needs_hold_torques(&self) -> bool {
        self.model.needs_hold
    }
    /// Whether the tree's velocity vector is one run of the state (the dynamics then write
    /// `q̈` straight into the derivative).
    pub fn velocity_is_one_run(&self) -> bool {
        self.model.velocity_at.is_some()
    }
    /// The hold torques at `(t, x)` (N m, tree hinge order; NaN where not computed): those of
    /// the locked hinges, and with `all` every hinge's (as at an event).
    pub fn hold_torques(&mut self, t: f64, x: &[f64], all: bool) -> Result<&[f64], SystemError> {
        self.check_len(x.len(), "hold_torques")?;
        let hold = if all {
            hold::Hold::All
        } else {
            hold::Hold::Locked
        };
        self.prepare_with(t, x, false, hold)?;
        Ok(&self.data.hold)
    }
    /// The event functions with everything computed first (every effect applied, kinematics,
    /// the locked hinges' hold torques): slower than [`System::events`](satsim_integrate::System::events), which computes only
    /// what the effects' [`Effect::event_reads`] declare, and the reference it is tested
    /// against.
    pub fn reference_events(
        &mut self,
        t: f64,
        x: &[f64],
        g: &mut [f64],
    ) -> Result<(), SystemError> {
        self.check_len(x.len(), "reference_events")?;
        if g.len() != self.model.n_events {
            return Err(SystemError::new(format!(
                "reference_events: g has length {} but the simulation has {} event functions",
                g.len(),
                self.model.n_events
            )));
        }
        self.prepare_with(t, x, true, hold::Hold::Locked)?;
        self.with_context(t, x, true, |ctx, h| {
            for (i, (e, r)) in h.effects.iter().zip(h.own).enumerate() {
                let s = h.event_start[i];
                e.events(ctx, h.forces, &x[r.clone()], &mut g[s..s + e.n_events()]);
            }
        });
        Ok(())
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
        body: None,
        axis,
        nominal: axis,
        at: Vec3::zeros(),
        mass: 0.0,
        axial,
        transverse,
    }
    .inertia()
}
