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
//!   `q̇ = ½ q ⊗ (0, ω)`; [`System::project`] renormalises it after every step.
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
//! unpack `x` → forward kinematics (only when an effect needs it) → each enabled effect adds
//! hinge torques, body wrenches and its own derivatives → ABA (hybrid ABA when hinges are
//! locked) → pack `dx`.
//!
//! # Energy budget
//!
//! `T + V` (kinetic energy of the tree, wheels included, plus the effects'
//! [`Effect::potential_energy`]) changes by the work of the non-conservative forces. Two more
//! states (after the effects' own, unless [`SimulationBuilder::energy_budget`] turns them
//! off) integrate that work, exactly to the integrator's order: `W`, the work of the
//! actuators (the constant hinge torques, and each effect's [`Power::actuator`]), and `D`, the
//! energy dissipated (each effect's [`Power::dissipated`]). Each effect's forces are measured
//! by the simulation, `Σ Δτ_k q̇_k + Σ Δf_i · v_i` over what its `apply` added, and the effect
//! splits that power in [`Effect::power`] (by default all of it is an actuator's), so a new
//! effect needs no special case. A jump of `T + V` at an event (a latching or rebounding
//! impact's impulse) is booked at the event: a loss into `D`, a gain into `W`. Then
//!
//! `energy_budget = T + V − W + D`
//!
//! is constant up to the integration error. `W` and `D` have zero weight in the error norm
//! ([`System::error_weights`]), so tracking them leaves every other state as it was.

use crate::effects::{Context, Effect, Forces, Links, OrbitState, Power, Request, Rotor, order};
use nalgebra::{DMatrix, DVector, Quaternion, UnitQuaternion};
use satsim_integrate::{
    EventAction, EventDirection, IntegrateError, Options, Output, Stats, System, SystemError,
};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{
    BaseKind, Body, Data, DynamicsError, Hinge, Model, ModelError, State, aba, aba_hybrid,
    center_of_mass, crba, forward_kinematics, kinetic_energy, momentum, rnea,
};
use std::cell::RefCell;
use std::ops::{ControlFlow, Range};
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

/// Where each part of the state lives in `x`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StateLayout {
    /// Free-floating root.
    pub free: bool,
    /// Number of the model's hinges.
    pub n_hinges: usize,
    /// Attitude quaternion (empty for a fixed base).
    pub attitude: Range<usize>,
    /// Hinge angles, file order.
    pub angles: Range<usize>,
    /// Root angular velocity, root axes (empty for a fixed base).
    pub omega: Range<usize>,
    /// Root origin velocity, root axes (empty for a fixed base).
    pub velocity: Range<usize>,
    /// Hinge rates, file order.
    pub rates: Range<usize>,
    /// Each enabled effect's own states, by name, in the effects' order.
    pub effects: Vec<(String, Range<usize>)>,
    /// Total length of the state.
    pub len: usize,
}

impl StateLayout {
    fn new(free: bool, n: usize, own: &[(String, usize)]) -> Self {
        let b = if free { 4 } else { 0 };
        let attitude = 0..b;
        let angles = b..b + n;
        let w = if free { 3 } else { 0 };
        let omega = angles.end..angles.end + w;
        let velocity = omega.end..omega.end + w;
        let rates = velocity.end..velocity.end + n;
        let mut at = rates.end;
        let effects = own
            .iter()
            .map(|(name, k)| {
                let r = at..at + k;
                at += k;
                (name.clone(), r)
            })
            .collect();
        Self {
            free,
            n_hinges: n,
            attitude,
            angles,
            omega,
            velocity,
            rates,
            effects,
            len: at,
        }
    }
    /// The range of effect `name`'s states, if it is enabled and has any.
    pub fn effect(&self, name: &str) -> Option<Range<usize>> {
        self.effects
            .iter()
            .find(|(n, r)| n == name && !r.is_empty())
            .map(|(_, r)| r.clone())
    }
}

/// Builds a [`Simulation`] from a model, an initial state and effects.
///
/// ```
/// use satsim_satellite::effects::HingeSprings;
/// use satsim_satellite::simulation::Simulation;
/// use satsim_tree::{State, samples::chain, BaseKind};
/// let model = chain(3, BaseKind::Free);
/// let mut state = State::rest(&model);
/// state.q[7] = 0.1;
/// let sim = Simulation::builder(model)
///     .initial(state)
///     .effect(HingeSprings::new(vec![5.0, 5.0]))
///     .build()?;
/// // no state for the springs; two for the energy budget
/// assert_eq!(sim.layout().len, 4 + 2 + 6 + 2 + 2);
/// # Ok::<(), satsim_satellite::simulation::SimError>(())
/// ```
pub struct SimulationBuilder {
    model: Model,
    state: Option<State>,
    effects: Vec<Box<dyn Effect>>,
    t0: f64,
    energy_budget: bool,
}

impl SimulationBuilder {
    /// The initial state (default: at rest, neutral).
    pub fn initial(mut self, state: State) -> Self {
        self.state = Some(state);
        self
    }
    /// Adds an effect.
    pub fn effect(mut self, e: impl Effect + 'static) -> Self {
        self.effects.push(Box::new(e));
        self
    }
    /// Adds a boxed effect.
    pub fn boxed(mut self, e: Box<dyn Effect>) -> Self {
        self.effects.push(e);
        self
    }
    /// The initial time (default 0).
    pub fn t0(mut self, t0: f64) -> Self {
        self.t0 = t0;
        self
    }
    /// Whether to integrate the energy budget's work states (default true; see
    /// [the module documentation](self#energy-budget)). Without them the output has no
    /// `work_actuators`, `energy_dissipated`, `energy_budget` columns.
    pub fn energy_budget(mut self, on: bool) -> Self {
        self.energy_budget = on;
        self
    }
    /// Checks the effects' needs, adds rotor bodies, lays out the state and prepares the
    /// initial state.
    pub fn build(self) -> Result<Simulation, SimError> {
        Simulation::new(self)
    }
}

/// A scene ready to integrate: see the module documentation.
pub struct Simulation {
    model: Model,
    data: Data,
    layout: StateLayout,
    effects: Vec<Box<dyn Effect>>,
    own: Vec<Range<usize>>,
    calls: Vec<u64>,
    event_start: Vec<usize>,
    n_events: usize,
    n_user: usize,
    n_rotors: usize,
    rotor_effect: Option<usize>,
    orbit_effect: Option<usize>,
    needs_kinematics: bool,
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

/// The model plus rotor bodies hinged to its root (appended after its hinges).
fn with_rotors(model: &Model, rotors: &[Rotor]) -> Result<Model, ModelError> {
    let mut b = model.to_builder();
    let root = model.bodies()[0].name().to_owned();
    for r in rotors {
        b.push_body(Body::new(r.name.clone(), r.mass, r.inertia()));
        b.push_hinge(
            Hinge::revolute(r.name.clone(), root.clone(), r.name.clone(), r.axis).at(r.at),
        );
    }
    b.build()
}

impl Simulation {
    /// Starts building a simulation of `model`.
    pub fn builder(model: Model) -> SimulationBuilder {
        SimulationBuilder {
            model,
            state: None,
            effects: Vec::new(),
            t0: 0.0,
            energy_budget: true,
        }
    }

    fn new(b: SimulationBuilder) -> Result<Self, SimError> {
        let SimulationBuilder {
            model: user,
            state,
            effects,
            t0,
            energy_budget,
        } = b;
        let state = state.unwrap_or_else(|| State::rest(&user));
        if state.q.len() != user.nq() || state.v.len() != user.nv() || state.tau.len() != user.nv()
        {
            return Err(SimError::State(format!(
                "expected q, v, tau of lengths {}, {}, {}; got {}, {}, {}",
                user.nq(),
                user.nv(),
                user.nv(),
                state.q.len(),
                state.v.len(),
                state.tau.len()
            )));
        }
        for (i, e) in effects.iter().enumerate() {
            if effects[..i].iter().any(|o| o.name() == e.name()) {
                return Err(SimError::Needs(format!(
                    "effect `{}` given twice",
                    e.name()
                )));
            }
        }
        // The order of evaluation: the effects' declared dependencies, else as given.
        let run_order = order::run_order(&effects).map_err(SimError::Needs)?;
        let mut slots: Vec<Option<Box<dyn Effect>>> = effects.into_iter().map(Some).collect();
        let mut effects: Vec<Box<dyn Effect>> = run_order
            .into_iter()
            .filter_map(|i| slots[i].take())
            .collect();
        let free = user.base() == BaseKind::Free;
        let has = |n: &str| effects.iter().any(|e| e.name() == n);
        for e in &effects {
            let needs = e.needs();
            if needs.orbit && !has("orbit") {
                return Err(SimError::Needs(format!(
                    "effects.{} needs an [orbit] table",
                    e.name()
                )));
            }
            if needs.rotors && !effects.iter().any(|o| !o.rotors().is_empty()) {
                return Err(SimError::Needs(format!(
                    "effects.{} needs rotors to command (e.g. [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]])",
                    e.name()
                )));
            }
            if needs.free_base && !free {
                return Err(SimError::Needs(format!(
                    "effects.{} needs a free-floating root (the model has [base] kind = \"fixed\")",
                    e.name()
                )));
            }
        }
        let rotor_effects: Vec<usize> = (0..effects.len())
            .filter(|&i| !effects[i].rotors().is_empty())
            .collect();
        if rotor_effects.len() > 1 {
            return Err(SimError::Needs("only one effect may add rotors".into()));
        }
        let rotor_effect = rotor_effects.first().copied();
        let rotors = rotor_effect
            .map(|i| effects[i].rotors())
            .unwrap_or_default();
        if let Some(i) = rotor_effect
            && effects[i].n_states() != rotors.len()
        {
            return Err(SimError::Needs(format!(
                "effect `{}` must have one state per rotor",
                effects[i].name()
            )));
        }
        let links = Links {
            rotors: &rotors,
            rotors_commanded: effects.iter().any(|e| e.commands_rotors()),
        };
        for e in &mut effects {
            e.connect(&links);
        }
        let orbit_effect = effects.iter().position(|e| e.name() == "orbit");
        let model = if rotors.is_empty() {
            user.clone()
        } else {
            with_rotors(&user, &rotors)?
        };
        let n_user = user.n_hinges();
        let n_rotors = rotors.len();
        let own_sizes: Vec<(String, usize)> = effects
            .iter()
            .map(|e| (e.name().to_owned(), e.n_states()))
            .collect();
        let mut layout = StateLayout::new(free, n_user, &own_sizes);
        let work = layout.len..layout.len + if energy_budget { 2 } else { 0 };
        layout.len = work.end;
        let own: Vec<Range<usize>> = layout.effects.iter().map(|(_, r)| r.clone()).collect();
        let mut event_start = Vec::with_capacity(effects.len());
        let mut n_events = 0;
        for e in &effects {
            event_start.push(n_events);
            n_events += e.n_events();
        }
        let needs_kinematics = effects.iter().any(|e| e.needs().kinematics);
        let needs_hold = effects.iter().any(|e| e.needs().hold_torques);
        let (n_tree_hinges, n_tree_nv) = (model.n_hinges(), model.nv());
        let nh = model.n_hinges();
        let mut base_tau = vec![0.0; nh];
        base_tau[..n_user].copy_from_slice(&state.tau[user.base_nv()..]);
        let mut x0 = vec![0.0; layout.len];
        if free {
            x0[layout.attitude.clone()].copy_from_slice(&state.q[..4]);
            x0[layout.omega.clone()].copy_from_slice(&state.v[..3]);
            x0[layout.velocity.clone()].copy_from_slice(&state.v[3..6]);
        }
        x0[layout.angles.clone()].copy_from_slice(&state.q[user.base_nq()..]);
        x0[layout.rates.clone()].copy_from_slice(&state.v[user.base_nv()..]);
        for (e, r) in effects.iter().zip(&own) {
            e.initial_state(&mut x0[r.clone()]);
        }
        let n_bodies = model.n_bodies();
        let mut sim = Self {
            data: Data::new(&model),
            q: model.neutral(),
            v: vec![0.0; model.nv()],
            tau: vec![0.0; model.nv()],
            forces: Forces::new(nh, n_bodies, n_rotors),
            locked: vec![false; nh],
            model,
            layout,
            calls: vec![0; effects.len()],
            effects,
            own,
            event_start,
            n_events,
            n_user,
            n_rotors,
            rotor_effect,
            orbit_effect,
            needs_kinematics,
            base_tau,
            n_locked: 0,
            scratch: vec![0.0; x0.len()],
            requests: Vec::new(),
            needs_hold,
            hold: vec![f64::NAN; n_tree_hinges],
            hold_mask: vec![false; n_tree_hinges],
            hold_ddq: vec![0.0; n_tree_nv],
            x0: Vec::new(),
            t0,
            rhs_evals: 0,
            log: Vec::new(),
            log_effect: Vec::new(),
            work,
        };
        // With an orbit, put the centre of mass at rest in the orbit's frame.
        if free && sim.orbit_effect.is_some() && sim.model.total_mass() > 0.0 {
            sim.unpack(&x0);
            forward_kinematics(&sim.model, &mut sim.data, &sim.q, &sim.v)?;
            let (p, _) = momentum(&sim.model, &sim.data);
            let du = sim.data.rotation[0].tr_mul(&p) / sim.model.total_mass();
            for k in 0..3 {
                x0[sim.layout.velocity.start + k] -= du[k];
            }
        }
        // Effects' start hooks (initial locks).
        sim.prepare_with(t0, &x0, true, Hold::All)
            .map_err(SimError::Start)?;
        sim.with_context(t0, &x0, true, |ctx, h| {
            for (e, r) in h.effects.iter_mut().zip(h.own) {
                e.start(ctx, h.forces, &x0[r.clone()], h.requests)
                    .map_err(SimError::Start)?;
            }
            Ok::<(), SimError>(())
        })?;
        let reqs = std::mem::take(&mut sim.requests);
        let before = sim.mechanical_energy(t0, &x0).map_err(SimError::Start)?;
        sim.apply_requests(&reqs, &mut x0)?;
        sim.book_jump(t0, &mut x0, before)
            .map_err(SimError::Start)?;
        // Every output quantity of the initial state must be finite (an energy or a momentum
        // can overflow while the state itself is finite).
        let mut row = Vec::new();
        sim.row(t0, &x0, &mut row).map_err(SimError::Start)?;
        if let Some(c) = row.iter().position(|v| !v.is_finite()) {
            return Err(SimError::State(format!(
                "`{}` is not finite at the start: the computation overflows (rates, masses or \
                 inertias too extreme for f64)",
                sim.columns()[c]
            )));
        }
        sim.x0 = x0;
        Ok(sim)
    }

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
    /// How many times each enabled effect was applied by [`System::rhs`], in the order of
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

    /// `x` into the tree's `q` and `v`.
    fn unpack(&mut self, x: &[f64]) {
        let l = &self.layout;
        let n = self.n_user;
        if l.free {
            self.q[..4].copy_from_slice(&x[l.attitude.clone()]);
            self.q[7..7 + n].copy_from_slice(&x[l.angles.clone()]);
            self.v[..3].copy_from_slice(&x[l.omega.clone()]);
            self.v[3..6].copy_from_slice(&x[l.velocity.clone()]);
            self.v[6..6 + n].copy_from_slice(&x[l.rates.clone()]);
        } else {
            self.q[..n].copy_from_slice(&x[l.angles.clone()]);
            self.v[..n].copy_from_slice(&x[l.rates.clone()]);
        }
        if let Some(i) = self.rotor_effect {
            let b = self.model.base_nv() + n;
            self.v[b..b + self.n_rotors].copy_from_slice(&x[self.own[i].clone()]);
        }
    }

    /// Unpacks, runs kinematics and every effect's `apply` (own derivatives into `scratch`).
    fn prepare(&mut self, t: f64, x: &[f64], kinematics: bool) -> Result<(), SystemError> {
        self.prepare_with(t, x, kinematics, Hold::None)
    }

    /// As [`Self::prepare`], then fills the hold torques for the hinges `hold` asks for.
    fn prepare_with(
        &mut self,
        t: f64,
        x: &[f64],
        kinematics: bool,
        hold: Hold,
    ) -> Result<(), SystemError> {
        self.apply_effects(t, x, kinematics)?;
        self.hold.fill(f64::NAN);
        if !self.needs_hold {
            return Ok(());
        }
        let nb = self.model.base_nv();
        self.tau[nb..].copy_from_slice(&self.forces.hinge_torque);
        if self.n_locked > 0 {
            self.hold_mask.copy_from_slice(&self.locked);
            self.solve_hold(None)?;
        }
        if hold == Hold::All {
            for k in 0..self.locked.len() {
                if !self.locked[k] {
                    self.hold_mask.copy_from_slice(&self.locked);
                    self.hold_mask[k] = true;
                    self.solve_hold(Some(k))?;
                }
            }
        }
        Ok(())
    }

    /// Hybrid dynamics with `hold_mask` locked, then RNEA for the torques the locked hinges
    /// must receive: all of them (`only` = None) or hinge `only`.
    fn solve_hold(&mut self, only: Option<usize>) -> Result<(), SystemError> {
        let nb = self.model.base_nv();
        let fext = if self.forces.has_wrench {
            Some(self.forces.body_wrench.as_slice())
        } else {
            None
        };
        let err = |e: satsim_tree::DynamicsError| SystemError::new(e.to_string());
        let ddq = aba_hybrid(
            &self.model,
            &mut self.data,
            &self.q,
            &self.v,
            &self.tau,
            fext,
            &self.hold_mask,
        )
        .map_err(err)?;
        self.hold_ddq.copy_from_slice(ddq.as_slice());
        let need = rnea(
            &self.model,
            &mut self.data,
            &self.q,
            &self.v,
            &self.hold_ddq,
            fext,
        )
        .map_err(err)?;
        match only {
            Some(k) => self.hold[k] = need[nb + k],
            None => {
                for (k, h) in self.hold.iter_mut().enumerate() {
                    if self.hold_mask[k] {
                        *h = need[nb + k];
                    }
                }
            }
        }
        // ABA and RNEA leave the poses of the last forward kinematics as they were.
        Ok(())
    }

    /// Unpacks, runs kinematics and every effect's `apply` (own derivatives into `scratch`).
    fn apply_effects(&mut self, t: f64, x: &[f64], kinematics: bool) -> Result<(), SystemError> {
        self.unpack(x);
        let kin = kinematics || self.needs_kinematics;
        if kin {
            forward_kinematics(&self.model, &mut self.data, &self.q, &self.v)
                .map_err(|e| SystemError::new(e.to_string()))?;
        }
        self.with_context(t, x, kin, |ctx, h| {
            h.forces.clear();
            h.forces.hinge_torque.copy_from_slice(h.base_tau);
            for (e, r) in h.effects.iter_mut().zip(h.own) {
                e.apply(ctx, h.forces, &x[r.clone()], &mut h.scratch[r.clone()])?;
            }
            Ok(())
        })
    }

    /// Carries out requests made together (at one event instant, or at the start) on the
    /// state `x`: unlocks first, then one momentum-conserving impulse solve for every hinge
    /// whose rate must change (a `Lock` wants rate 0, a `SetRate` its rate; a `Lock` wins
    /// when one hinge gets both), then the locks.
    pub(crate) fn apply_requests(
        &mut self,
        reqs: &[Request],
        x: &mut [f64],
    ) -> Result<(), SimError> {
        let mut targets: Vec<(usize, f64)> = Vec::new();
        let mut locks: Vec<usize> = Vec::new();
        for r in reqs {
            match *r {
                Request::Unlock(h) => {
                    if self.locked[h] {
                        self.locked[h] = false;
                        self.n_locked -= 1;
                    }
                }
                Request::Lock(h) => {
                    locks.push(h);
                    targets.retain(|&(g, _)| g != h);
                    targets.push((h, 0.0));
                }
                Request::SetRate { hinge, rate } => {
                    if !locks.contains(&hinge) {
                        targets.retain(|&(g, _)| g != hinge);
                        targets.push((hinge, rate));
                    }
                }
            }
        }
        if !targets.is_empty() {
            self.impulses(&targets, x)?;
        }
        for h in locks {
            if !self.locked[h] {
                self.locked[h] = true;
                self.n_locked += 1;
            }
        }
        Ok(())
    }

    /// Index in `x` of tree hinge `h`'s rate.
    fn rate_index(&self, h: usize) -> usize {
        match self.rotor_effect {
            Some(i) if h >= self.n_user => self.own[i].start + (h - self.n_user),
            _ => self.layout.rates.start + h,
        }
    }

    /// One momentum-conserving impulse solve that sets each hinge `h` of `targets` to its
    /// rate: impulses `λ_j` between each target hinge's two bodies, over the free degrees of
    /// freedom (base, unlocked hinges and the targets; other locked hinges stay rigid):
    /// `Δv = M_ff⁻¹ E λ` with `(Eᵀ M_ff⁻¹ E) λ = target − v_E`. Simultaneous impacts are
    /// thus resolved together, symmetric ones symmetrically.
    fn impulses(&mut self, targets: &[(usize, f64)], x: &mut [f64]) -> Result<(), SimError> {
        self.unpack(x);
        crba(&self.model, &mut self.data, &self.q)?;
        let nb = self.model.base_nv();
        let nv = self.model.nv();
        let is_target = |d: usize| d >= nb && targets.iter().any(|&(h, _)| h == d - nb);
        let free: Vec<usize> = (0..nv)
            .filter(|&d| d < nb || is_target(d) || !self.locked[d - nb])
            .collect();
        let m = DMatrix::from_fn(free.len(), free.len(), |r, c| {
            self.data.mass_matrix[(free[r], free[c])]
        });
        let singular = || SimError::State("singular mass matrix at an impact".into());
        let chol = m.cholesky().ok_or_else(singular)?;
        // Positions of the targets among the free dofs.
        let pos: Vec<usize> = targets
            .iter()
            .map(|&(h, _)| free.iter().position(|&d| d == nb + h).unwrap_or(0))
            .collect();
        let mut e = DMatrix::zeros(free.len(), targets.len());
        for (j, &p) in pos.iter().enumerate() {
            e[(p, j)] = 1.0;
        }
        let col = chol.solve(&e);
        let a = DMatrix::from_fn(targets.len(), targets.len(), |r, c| col[(pos[r], c)]);
        let b = DVector::from_fn(targets.len(), |r, _| {
            targets[r].1 - x[self.rate_index(targets[r].0)]
        });
        let lambda = a.cholesky().ok_or_else(singular)?.solve(&b);
        let dv = &col * &lambda;
        if !dv.iter().all(|v| v.is_finite()) {
            return Err(SimError::State(
                "an impact produced non-finite velocities".into(),
            ));
        }
        for (c, &d) in free.iter().enumerate() {
            let idx = if d < nb {
                if d < 3 {
                    self.layout.omega.start + d
                } else {
                    self.layout.velocity.start + d - 3
                }
            } else {
                self.rate_index(d - nb)
            };
            x[idx] += dv[c];
        }
        for &(h, target) in targets {
            x[self.rate_index(h)] = target;
        }
        Ok(())
    }

    /// Output column names: `t`, attitude, rates, hinge angles and rates, the effects'
    /// columns, energies and angular momentum.
    pub fn columns(&self) -> Vec<String> {
        let mut c: Vec<String> = [
            "t", "q_w", "q_x", "q_y", "q_z", "omega_x", "omega_y", "omega_z",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        for name in &self.model.hinge_names()[..self.n_user] {
            c.push(format!("angle_{name}"));
        }
        for name in &self.model.hinge_names()[..self.n_user] {
            c.push(format!("rate_{name}"));
        }
        for e in &self.effects {
            if !e.rotors().is_empty() {
                c.extend(e.state_names());
            }
            c.extend(e.output_columns());
        }
        c.extend(
            [
                "kinetic_energy",
                "potential_energy",
                "total_energy",
                "h_x",
                "h_y",
                "h_z",
                "h_norm",
            ]
            .iter()
            .map(|s| s.to_string()),
        );
        if !self.work.is_empty() {
            c.extend(
                ["work_actuators", "energy_dissipated", "energy_budget"]
                    .iter()
                    .map(|s| s.to_string()),
            );
        }
        c
    }

    /// One output row at `(t, x)` (see [`Simulation::columns`]).
    /// A state of the wrong length is an error.
    pub fn row(&mut self, t: f64, x: &[f64], row: &mut Vec<f64>) -> Result<(), SystemError> {
        self.check_len(x.len(), "row")?;
        row.clear();
        self.prepare(t, x, true)?;
        row.push(t);
        let l = &self.layout;
        if l.free {
            row.extend_from_slice(&x[l.attitude.clone()]);
            row.extend_from_slice(&x[l.omega.clone()]);
        } else {
            row.extend_from_slice(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        }
        row.extend_from_slice(&x[l.angles.clone()]);
        row.extend_from_slice(&x[l.rates.clone()]);
        let d = self.diagnostics_prepared(t, x, Some(row));
        row.push(d.kinetic);
        row.push(d.potential);
        row.push(d.kinetic + d.potential);
        row.extend_from_slice(d.h.as_slice());
        row.push(d.h.norm());
        if !self.work.is_empty() {
            let (work, lost) = (x[self.work.start], x[self.work.start + 1]);
            row.push(work);
            row.push(lost);
            row.push(d.kinetic + d.potential - work + lost);
        }
        Ok(())
    }

    /// Energies and momenta at `(t, x)`.
    pub fn diagnostics(&mut self, t: f64, x: &[f64]) -> Result<Diagnostics, SystemError> {
        self.check_len(x.len(), "diagnostics")?;
        self.prepare(t, x, true)?;
        Ok(self.diagnostics_prepared(t, x, None))
    }

    fn diagnostics_prepared(
        &mut self,
        t: f64,
        x: &[f64],
        row: Option<&mut Vec<f64>>,
    ) -> Diagnostics {
        let kinetic =
            kinetic_energy(&self.model, &mut self.data, &self.q, &self.v).unwrap_or(f64::NAN);
        let (p, h) = momentum(&self.model, &self.data);
        let rotor_effect = self.rotor_effect;
        let potential = self.with_context(t, x, true, |ctx, hooks| {
            let mut potential = 0.0;
            for (e, r) in hooks.effects.iter().zip(hooks.own) {
                potential += e.potential_energy(ctx, &x[r.clone()]);
            }
            if let Some(row) = row {
                for (i, (e, r)) in hooks.effects.iter().zip(hooks.own).enumerate() {
                    // The wheel speeds (no call to `rotors()`, which allocates).
                    if rotor_effect == Some(i) {
                        row.extend_from_slice(&x[r.clone()]);
                    }
                    e.output(ctx, &x[r.clone()], row);
                }
            }
            potential
        });
        Diagnostics {
            kinetic,
            potential,
            h,
            p,
        }
    }

    /// Integrates from the initial state to `t_end`, calling `sink(t, row)` with an output
    /// row (see [`Simulation::columns`]) at each output time. A sink error stops the run.
    /// Every row passed to `sink` is finite: a row with a non-finite entry stops the run with
    /// an error naming the column.
    pub fn run<E>(
        &mut self,
        options: &Options,
        t_end: f64,
        output: &Output,
        mut sink: impl FnMut(f64, &[f64]) -> Result<(), E>,
    ) -> Result<Stats, RunError<E>> {
        let x0 = self.x0.clone();
        let t0 = self.t0;
        let columns = self.columns();
        let cell = RefCell::new(self);
        let mut shared = Shared(&cell);
        let mut row = Vec::new();
        let mut failure: Option<RunError<E>> = None;
        let result =
            satsim_integrate::integrate(&mut shared, options, t0, &x0, t_end, output, |t, x| {
                let mut sim = cell.borrow_mut();
                if let Err(e) = sim.row(t, x, &mut row) {
                    failure = Some(RunError::Integrate(IntegrateError::System { t, source: e }));
                    return ControlFlow::Break(());
                }
                // A non-finite quantity is never presented as a result.
                if let Some(c) = row.iter().position(|v| !v.is_finite()) {
                    let why = format!("`{}` is not finite: the computation overflowed", columns[c]);
                    failure = Some(RunError::Integrate(IntegrateError::System {
                        t,
                        source: SystemError::new(why),
                    }));
                    return ControlFlow::Break(());
                }
                if let Err(e) = sink(t, &row) {
                    failure = Some(RunError::Sink { t, error: e });
                    return ControlFlow::Break(());
                }
                ControlFlow::Continue(())
            });
        match (result, failure) {
            (_, Some(f)) => Err(f),
            (Ok(stats), None) => Ok(stats),
            (Err(e), None) => Err(RunError::Integrate(e)),
        }
    }
}

/// Why [`Simulation::run`] stopped early.
#[derive(Debug, Error)]
pub enum RunError<E> {
    /// The integrator (or the dynamics) failed.
    #[error("{0}")]
    Integrate(IntegrateError),
    /// The output sink failed at time `t`.
    #[error("output failed at t = {t}: {error}")]
    Sink {
        /// Time of the row.
        t: f64,
        /// The sink's error.
        error: E,
    },
}

/// Energies (J) and momenta (inertial axes) of the tree, wheels included.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diagnostics {
    /// Kinetic energy (relative to the centre-of-mass frame when there is an orbit).
    pub kinetic: f64,
    /// Potential energy of the effects (springs, gravity gradient).
    pub potential: f64,
    /// Angular momentum about the centre of mass (N m s).
    pub h: Vec3,
    /// Linear momentum (N s).
    pub p: Vec3,
}

struct Shared<'a, 'b>(&'a RefCell<&'b mut Simulation>);

impl System for Shared<'_, '_> {
    fn dim(&self) -> usize {
        self.0.borrow().layout.len
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.0.borrow_mut().rhs(t, x, dx)
    }
    fn project(&mut self, x: &mut [f64]) {
        self.0.borrow_mut().project(x)
    }
    fn error_weights(&self, w: &mut [f64]) {
        self.0.borrow().error_weights(w)
    }
    fn n_events(&self) -> usize {
        self.0.borrow().n_events
    }
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        self.0.borrow_mut().events(t, x, g)
    }
    fn event_direction(&self, k: usize) -> EventDirection {
        self.0.borrow().event_direction(k)
    }
    fn on_event(&mut self, k: usize, t: f64, x: &mut [f64]) -> EventAction {
        self.0.borrow_mut().on_event(k, t, x)
    }
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        self.0.borrow_mut().on_events(ks, t, x)
    }
}

fn orbit_of(effects: &[Box<dyn Effect>], own: &[Range<usize>], x: &[f64]) -> Option<OrbitState> {
    effects
        .iter()
        .zip(own)
        .find_map(|(e, r)| e.orbit_state(&x[r.clone()]))
}

#[allow(clippy::too_many_arguments)]
/// The parts of a simulation that the effects' hooks write, beside the read-only
/// [`Context`] (see [`Simulation::with_context`]).
struct Hooks<'a> {
    effects: &'a mut [Box<dyn Effect>],
    own: &'a [Range<usize>],
    forces: &'a mut Forces,
    requests: &'a mut Vec<Request>,
    calls: &'a mut [u64],
    scratch: &'a mut [f64],
    base_tau: &'a [f64],
    event_start: &'a [usize],
}

impl Simulation {
    /// Splits the simulation, once for every hook, into the [`Context`] of time `t` and state
    /// `x` (`kin`: whether the poses are current) and the mutable [`Hooks`], and runs `f`.
    fn with_context<R>(
        &mut self,
        t: f64,
        x: &[f64],
        kin: bool,
        f: impl FnOnce(&Context, Hooks) -> R,
    ) -> R {
        let Self {
            model,
            data,
            effects,
            own,
            forces,
            requests,
            calls,
            scratch,
            base_tau,
            event_start,
            q,
            v,
            locked,
            layout,
            n_user,
            hold,
            ..
        } = self;
        let (attitude, omega) = if layout.free {
            (
                UnitQuaternion::new_unchecked(Quaternion::new(q[0], q[1], q[2], q[3])),
                Vec3::new(v[0], v[1], v[2]),
            )
        } else {
            (UnitQuaternion::identity(), Vec3::zeros())
        };
        let nb = model.base_nv();
        let ctx = Context {
            t,
            model,
            data,
            q,
            v,
            n_hinges: *n_user,
            angles: &x[layout.angles.clone()],
            rates: &x[layout.rates.clone()],
            locked,
            com: if kin {
                center_of_mass(model, data)
            } else {
                Vec3::zeros()
            },
            orbit: orbit_of(effects, own, x),
            attitude,
            omega,
            rotor_rates: &v[nb + *n_user..],
            hold_torque: hold,
        };
        f(
            &ctx,
            Hooks {
                effects,
                own,
                forces,
                requests,
                calls,
                scratch,
                base_tau,
                event_start,
            },
        )
    }
}

/// Which hold torques [`Simulation::prepare_with`] computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Hold {
    /// None.
    None,
    /// The locked hinges' (one hybrid solve).
    Locked,
    /// Every hinge's (one hybrid solve per unlocked hinge): at events and at the start.
    All,
}

impl System for Simulation {
    fn dim(&self) -> usize {
        self.layout.len
    }

    /// `dx = f(t, x)`; slices of the wrong length are an error, not a panic.
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        self.check_len(x.len(), "rhs")?;
        self.check_len(dx.len(), "rhs (derivative)")?;
        self.rhs_evals += 1;
        self.unpack(x);
        if self.needs_kinematics {
            forward_kinematics(&self.model, &mut self.data, &self.q, &self.v)
                .map_err(|e| SystemError::new(e.to_string()))?;
        }
        let kin = self.needs_kinematics;
        let track = !self.work.is_empty();
        let nb = self.model.base_nv();
        let power = self.with_context(t, x, kin, |ctx, h| {
            h.forces.clear();
            h.forces.hinge_torque.copy_from_slice(h.base_tau);
            // Energy budget: the constant torques are an actuator's; each effect's forces
            // are measured by the change of the total power it makes.
            let mut hinges = if track {
                h.forces.hinge_power(ctx.v, nb)
            } else {
                0.0
            };
            let (mut wrenches, mut added) = (0.0, 0);
            let mut power = Power::actuator(hinges);
            for ((e, r), c) in h.effects.iter_mut().zip(h.own).zip(h.calls.iter_mut()) {
                *c += 1;
                e.apply(ctx, h.forces, &x[r.clone()], &mut dx[r.clone()])?;
                if track {
                    let now = h.forces.hinge_power(ctx.v, nb);
                    let mut applied = now - hinges;
                    hinges = now;
                    if h.forces.wrenches_added() != added {
                        added = h.forces.wrenches_added();
                        let now = h.forces.wrench_power(&ctx.data.v);
                        applied += now - wrenches;
                        wrenches = now;
                    }
                    let p = e.power(ctx, &x[r.clone()], applied);
                    power.actuator += p.actuator;
                    power.dissipated += p.dissipated;
                }
            }
            Ok::<Power, SystemError>(power)
        })?;
        if track && !kin && self.forces.has_wrench {
            // A wrench's power needs the bodies' velocities: an effect wrote one without
            // asking for kinematics, so they are computed from now on (this evaluation again).
            self.needs_kinematics = true;
            self.rhs_evals -= 1;
            return self.rhs(t, x, dx);
        }
        if track {
            dx[self.work.start] = power.actuator;
            dx[self.work.start + 1] = power.dissipated;
        }
        self.tau[nb..].copy_from_slice(&self.forces.hinge_torque);
        let fext = if self.forces.has_wrench {
            Some(self.forces.body_wrench.as_slice())
        } else {
            None
        };
        let ddq = if self.n_locked > 0 {
            aba_hybrid(
                &self.model,
                &mut self.data,
                &self.q,
                &self.v,
                &self.tau,
                fext,
                &self.locked,
            )
        } else {
            aba(
                &self.model,
                &mut self.data,
                &self.q,
                &self.v,
                &self.tau,
                fext,
            )
        }
        .map_err(|e| SystemError::new(e.to_string()))?;
        let l = &self.layout;
        let n = self.n_user;
        if l.free {
            let (w, a) = (&x[l.omega.clone()], &x[l.attitude.clone()]);
            // q̇ = ½ q ⊗ (0, ω)
            let qd = crate::effects::quat_mul(&[a[0], a[1], a[2], a[3]], &[0.0, w[0], w[1], w[2]]);
            for k in 0..4 {
                dx[l.attitude.start + k] = 0.5 * qd[k];
            }
            for k in 0..3 {
                dx[l.omega.start + k] = ddq[k];
                dx[l.velocity.start + k] = ddq[3 + k];
            }
        }
        dx[l.angles.clone()].copy_from_slice(&x[l.rates.clone()]);
        dx[l.rates.clone()].copy_from_slice(&ddq.as_slice()[nb..nb + n]);
        if let Some(i) = self.rotor_effect {
            let r = self.own[i].clone();
            dx[r].copy_from_slice(&ddq.as_slice()[nb + n..nb + n + self.n_rotors]);
        }
        Ok(())
    }

    /// The energy budget's work states are bookkeeping: they stay out of the error control,
    /// so that tracking them leaves the steps (and every other state) as they were.
    fn error_weights(&self, w: &mut [f64]) {
        w.fill(1.0);
        w[self.work.clone()].fill(0.0);
    }

    fn project(&mut self, x: &mut [f64]) {
        if self.layout.free {
            let a = self.layout.attitude.clone();
            let norm = x[a.clone()].iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > 0.0 {
                for v in &mut x[a] {
                    *v /= norm;
                }
            }
        }
    }

    fn n_events(&self) -> usize {
        self.n_events
    }

    /// The effects' event functions. A state on which the effects or the hold torques
    /// cannot be evaluated is an error (an event is never skipped silently).
    fn events(&mut self, t: f64, x: &[f64], g: &mut [f64]) -> Result<(), SystemError> {
        if self.n_events == 0 {
            return Ok(());
        }
        self.check_len(x.len(), "events")?;
        if g.len() != self.n_events {
            return Err(SystemError::new(format!(
                "events: g has length {} but the simulation has {} event functions",
                g.len(),
                self.n_events
            )));
        }
        self.prepare_with(t, x, false, Hold::Locked)
            .map_err(|e| SystemError::new(format!("event functions: {e}")))?;
        let kin = self.needs_kinematics;
        self.with_context(t, x, kin, |ctx, h| {
            for (i, (e, r)) in h.effects.iter().zip(h.own).enumerate() {
                let s = h.event_start[i];
                e.events(ctx, h.forces, &x[r.clone()], &mut g[s..s + e.n_events()]);
            }
        });
        Ok(())
    }

    fn event_direction(&self, k: usize) -> EventDirection {
        let i = self.event_owner(k);
        self.effects[i].event_direction(k - self.event_start[i])
    }

    fn on_event(&mut self, k: usize, t: f64, x: &mut [f64]) -> EventAction {
        match self.on_events(&[k], t, x) {
            Ok(a) => a,
            Err(_) => EventAction::Stop,
        }
    }

    /// Handles simultaneous events together: every owning effect's `on_event` sees the same
    /// state (the one at the event), then all their requests are carried out at once, with
    /// one impulse solve for all the impacts (see `Simulation::apply_requests`), so that a
    /// symmetric pair of impacts stays symmetric to round-off.
    fn on_events(
        &mut self,
        ks: &[usize],
        t: f64,
        x: &mut [f64],
    ) -> Result<EventAction, SystemError> {
        self.check_len(x.len(), "on_events")?;
        let before = self.mechanical_energy(t, x)?;
        if let Err(e) = self.prepare_with(t, x, false, Hold::All) {
            let why = format!("event handling failed: {e}");
            self.log.push((t, why.clone()));
            self.log_effect
                .push(ks.first().map_or(0, |&k| self.event_owner(k)));
            return Err(SystemError::new(why));
        }
        let kin = self.needs_kinematics;
        let mut action = EventAction::Continue;
        let mut own_state = Vec::new();
        for &k in ks {
            let i = self.event_owner(k);
            let local = k - self.event_start[i];
            let r = self.own[i].clone();
            own_state.clear();
            own_state.extend_from_slice(&x[r.clone()]);
            let a = self.with_context(t, x, kin, |ctx, h| {
                h.effects[i].on_event(local, ctx, h.forces, &mut own_state, h.requests)
            });
            x[r].copy_from_slice(&own_state);
            action = action.combine(a);
            let what = self.effects[i].describe_event(local);
            if !what.is_empty() {
                self.log.push((t, what));
                self.log_effect.push(i);
            }
        }
        let reqs = std::mem::take(&mut self.requests);
        let changed = !reqs.is_empty();
        let result = self.apply_requests(&reqs, x);
        self.requests = reqs;
        self.requests.clear();
        if let Err(e) = result {
            let why = format!("impact failed: {e}");
            self.log.push((t, why.clone()));
            self.log_effect
                .push(ks.first().map_or(0, |&k| self.event_owner(k)));
            return Err(SystemError::new(why));
        }
        self.book_jump(t, x, before)?;
        Ok(if changed {
            action.combine(EventAction::Reset)
        } else {
            action
        })
    }
}

impl Simulation {
    /// An error unless a state slice has the layout's length (`what` names the caller).
    fn check_len(&self, got: usize, what: &str) -> Result<(), SystemError> {
        if got == self.layout.len {
            Ok(())
        } else {
            Err(SystemError::new(format!(
                "{what}: state has length {got}, expected {}",
                self.layout.len
            )))
        }
    }

    /// `T + V` at `(t, x)` (0 when the energy budget is not tracked).
    fn mechanical_energy(&mut self, t: f64, x: &[f64]) -> Result<f64, SystemError> {
        if self.work.is_empty() {
            return Ok(0.0);
        }
        let d = self.diagnostics(t, x)?;
        Ok(d.kinetic + d.potential)
    }

    /// Books the jump of `T + V` from `before` to its value at `(t, x)` (an impact's
    /// impulse, an effect's own reset) into the energy budget's states: a loss as
    /// dissipated, a gain as actuator work.
    fn book_jump(&mut self, t: f64, x: &mut [f64], before: f64) -> Result<(), SystemError> {
        if self.work.is_empty() {
            return Ok(());
        }
        let jump = self.mechanical_energy(t, x)? - before;
        if jump < 0.0 {
            x[self.work.start + 1] -= jump;
        } else {
            x[self.work.start] += jump;
        }
        Ok(())
    }

    fn event_owner(&self, k: usize) -> usize {
        (0..self.effects.len())
            .rev()
            .find(|&i| self.event_start[i] <= k && self.effects[i].n_events() > 0)
            .unwrap_or(0)
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
