//! [`SimulationBuilder`] and the one-time set-up of a [`Simulation`]: rotors into the tree,
//! effects in dependency order, the state layout, the initial state.

use super::data::{DeflectionPeak, FlexWork};
use super::hold::Hold;
use super::{RunLog, SimData, SimError, SimModel, Simulation, StateLayout};
use crate::effects::{
    AnyEffect, Effect, EffectSet, Forces, Links, Rotor, Thruster, Torquer, order,
};
use satsim_integrate::SystemError;
use satsim_satellite::kernel::UnrolledAba;
use satsim_tree::flexible::FlexModel;
use satsim_tree::{BaseKind, Body, ForwardDynamics, Hinge, Kernel, Model, State, forward_poses};
use std::ops::Range;

/// Builds a [`Simulation`] from a model, an initial state and effects.
///
/// ```
/// use satsim_spacecraft::effects::HingeSprings;
/// use satsim_spacecraft::simulation::Simulation;
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
/// # Ok::<(), satsim_spacecraft::simulation::SimError>(())
/// ```
pub struct SimulationBuilder {
    model: Model,
    flex: Option<FlexModel>,
    elastic: Option<(Vec<f64>, Vec<f64>)>,
    state: Option<State>,
    effects: Vec<Box<dyn Effect>>,
    /// A copy of each effect as given, where there is one (see [`Simulation::run`]).
    copies: Vec<Option<Box<dyn Fresh>>>,
    t0: f64,
    energy_budget: bool,
    elastic_error: bool,
}

/// An effect as it was given, from which a simulation makes a fresh one each time it starts
/// again ([`Simulation::run`] run twice).
pub(super) trait Fresh: Send {
    fn fresh(&self) -> Box<dyn Effect>;
}

impl<E: Effect + Clone + 'static> Fresh for E {
    fn fresh(&self) -> Box<dyn Effect> {
        Box::new(self.clone())
    }
}

/// A scene's effect (an [`EffectSet`]'s) as a [`Fresh`].
struct FreshAny(Box<dyn AnyEffect>);

impl Fresh for FreshAny {
    fn fresh(&self) -> Box<dyn Effect> {
        self.0.clone_box().into_effect()
    }
}

impl SimulationBuilder {
    /// The initial state (default: at rest, neutral).
    pub fn initial(mut self, state: State) -> Self {
        self.state = Some(state);
        self
    }
    /// Adds an effect (a copy of it is kept, for a simulation that runs more than once).
    pub fn effect(mut self, e: impl Effect + Clone + 'static) -> Self {
        self.copies.push(Some(Box::new(e.clone())));
        self.effects.push(Box::new(e));
        self
    }
    /// Adds a boxed effect. There is no copy of it: a simulation with it runs once
    /// ([`Simulation::run`]).
    pub fn boxed(mut self, e: Box<dyn Effect>) -> Self {
        self.copies.push(None);
        self.effects.push(e);
        self
    }
    /// Adds every effect of `set` (copies of them), in its order.
    pub fn effects(mut self, set: &EffectSet) -> Self {
        for name in set.names() {
            let Some(e) = set.find(name) else { continue };
            self.effects.push(e.clone_box().into_effect());
            self.copies.push(Some(Box::new(FreshAny(e.clone_box()))));
        }
        self
    }
    /// Makes the tree flexible: the simulation's model becomes `model.rigid()` (replacing the
    /// one given to [`Simulation::builder`]) with `model`'s modes attached, and every solve
    /// goes through the flexible algorithms. The state gains `η` and `η̇` (see
    /// [`StateLayout`]); the initial state's `q`, `v` and `tau` are the rigid tree's.
    pub fn flexible(mut self, model: FlexModel) -> Self {
        self.model = model.rigid().clone();
        self.flex = Some(model);
        self
    }
    /// The initial elastic coordinates and rates (default zero), in the flexible model's
    /// order ([`StateLayout::eta`]); lengths other than its number of modes are an error at
    /// [`build`](Self::build).
    pub fn elastic(mut self, eta: Vec<f64>, etadot: Vec<f64>) -> Self {
        self.elastic = Some((eta, etadot));
        self
    }
    /// The initial time (default 0).
    pub fn t0(mut self, t0: f64) -> Self {
        self.t0 = t0;
        self
    }
    /// Whether to integrate the energy budget's work states (default true; see
    /// [the module documentation](crate::simulation#energy-budget)). Without them the output has no
    /// `work_actuators`, `energy_dissipated`, `energy_budget` columns.
    pub fn energy_budget(mut self, on: bool) -> Self {
        self.energy_budget = on;
        self
    }
    /// Whether the flexible bodies' elastic coordinates `η`, `η̇` count in the adaptive
    /// methods' error norm (default true). Without them the steps follow the rigid motion
    /// (attitude, hinges, wheels) alone: an implicit method (Radau IIA) then steps over a
    /// structural mode too fast to matter to that motion and damps it, as the generalised-α
    /// methods of structural dynamics do on purpose, where the default resolves every mode's
    /// ringing to the tolerance. The elastic coordinates are then right only where they vary
    /// slowly against the steps; the rigid motion's accuracy is to be checked against a
    /// reference (`satsim accuracy`). Only for Radau IIA: an explicit method's steps, no
    /// longer held by the modes, go past their stability limit and the modes grow without
    /// bound: a run under `dp54` or `dop853` with `false` is refused
    /// ([`elastic_error_refusal`](super::elastic_error_refusal)), as the scene reader refuses
    /// it at its line.
    pub fn elastic_error(mut self, on: bool) -> Self {
        self.elastic_error = on;
        self
    }
    /// Checks the effects' needs, adds rotor bodies, lays out the state and prepares the
    /// initial state.
    pub fn build(self) -> Result<Simulation, SimError> {
        Simulation::new(self)
    }
}

/// The model plus rotor bodies hinged to their carriers (the root unless a rotor names
/// another body; appended after the model's hinges, in `rotors`' order): the tree a
/// simulation integrates, which a check of its linear motions (the scene reader's RK4 step
/// limit) needs as well.
pub fn with_rotors(model: &Model, rotors: &[Rotor]) -> Result<Model, SimError> {
    let mut b = model.to_builder();
    let root = model.bodies()[0].name().to_owned();
    for r in rotors {
        let carrier = match &r.body {
            None => root.clone(),
            Some(name) if model.body_index(name).is_some() => name.clone(),
            Some(name) => {
                let names: Vec<&str> = model.bodies().iter().map(|b| b.name()).collect();
                return Err(SimError::Needs(format!(
                    "rotor `{}`: unknown body `{name}` (the model's bodies: {})",
                    r.name,
                    names.join(", ")
                )));
            }
        };
        b.push_body(Body::new(r.name.clone(), r.mass, r.inertia()));
        b.push_hinge(Hinge::revolute(r.name.clone(), carrier, r.name.clone(), r.axis).at(r.at));
    }
    Ok(b.build()?)
}

impl Simulation {
    /// Starts building a simulation of `model`.
    pub fn builder(model: Model) -> SimulationBuilder {
        SimulationBuilder {
            model,
            flex: None,
            elastic: None,
            state: None,
            effects: Vec::new(),
            copies: Vec::new(),
            t0: 0.0,
            energy_budget: true,
            elastic_error: true,
        }
    }

    pub(super) fn new(b: SimulationBuilder) -> Result<Self, SimError> {
        let SimulationBuilder {
            model: user,
            flex,
            elastic,
            state,
            effects,
            copies,
            t0,
            energy_budget,
            elastic_error,
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
        let mut copies: Vec<Option<Option<Box<dyn Fresh>>>> =
            copies.into_iter().map(Some).collect();
        let fresh: Vec<Option<Box<dyn Fresh>>> =
            run_order.iter().filter_map(|&i| copies[i].take()).collect();
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
        let torquers: Vec<Torquer> = effects.iter().flat_map(|e| e.torquers()).collect();
        if effects.iter().filter(|e| !e.torquers().is_empty()).count() > 1 {
            return Err(SimError::Needs(
                "more than one effect owns magnetic torquers: give them all to one".into(),
            ));
        }
        let thrust_commander = {
            let commanders: Vec<usize> = (0..effects.len())
                .filter(|&i| effects[i].commands_thrusters())
                .collect();
            if commanders.len() > 1 {
                return Err(SimError::Needs(
                    "more than one effect commands the thrusters".into(),
                ));
            }
            commanders.first().copied()
        };
        let thruster_owners: Vec<(usize, usize)> = effects
            .iter()
            .enumerate()
            .flat_map(|(i, e)| (0..e.thrusters().len()).map(move |j| (i, j)))
            .collect();
        let model = if rotors.is_empty() {
            user.clone()
        } else {
            with_rotors(&user, &rotors)?
        };
        let orbit_effect = effects.iter().position(|e| e.name() == "orbit");
        let flex = match flex {
            Some(f) if rotors.is_empty() => Some(f),
            Some(f) => Some(f.with_rigid(model.clone())?),
            None => None,
        };
        connect(&mut effects, &rotors, &torquers, &model, flex.as_ref());
        let n_elastic = flex.as_ref().map_or(0, |f| f.n_elastic());
        let (eta0, etadot0) =
            elastic.unwrap_or_else(|| (vec![0.0; n_elastic], vec![0.0; n_elastic]));
        if eta0.len() != n_elastic || etadot0.len() != n_elastic {
            return Err(SimError::State(format!(
                "expected eta and etadot of length {n_elastic} (the flexible bodies' modes); got {} and {}",
                eta0.len(),
                etadot0.len()
            )));
        }
        let n_user = user.n_hinges();
        let n_rotors = rotors.len();
        let own_sizes: Vec<(String, usize)> = effects
            .iter()
            .map(|e| (e.name().to_owned(), e.n_states()))
            .collect();
        let mut layout = StateLayout::new(free, n_user, n_elastic, &own_sizes);
        let work = layout.len..layout.len + if energy_budget { 2 } else { 0 };
        layout.len = work.end;
        let own: Vec<Range<usize>> = layout.effects.iter().map(|(_, r)| r.clone()).collect();
        let mut event_start = Vec::with_capacity(effects.len());
        let mut event_owner = Vec::new();
        let mut n_events = 0;
        for (i, e) in effects.iter().enumerate() {
            event_start.push(n_events);
            n_events += e.n_events();
            event_owner.resize(n_events, i);
        }
        let needs_com = effects.iter().any(|e| e.needs().com);
        let net_force_to =
            orbit_effect.filter(|_| free && effects.iter().any(|e| e.needs().net_force));
        let needs_kinematics = needs_com
            || net_force_to.is_some()
            || effects
                .iter()
                .any(|e| e.needs().kinematics || e.needs().poses);
        // The bodies' velocities too, unless every effect that reads the bodies reads only
        // their poses (the energy budget may still ask for them: `rhs_forces`).
        let needs_velocities = effects.iter().any(|e| {
            let n = e.needs();
            n.kinematics || ((n.com || n.net_force) && !n.poses)
        });
        // The rotors' poses too, unless the only effects that read the bodies read their
        // poses but no rotor's (the centre of mass reads every massive body).
        let rotor_poses = needs_com
            || net_force_to.is_some()
            || effects.iter().any(|e| {
                let n = e.needs();
                (n.kinematics || n.poses) && e.reads_rotor_poses()
            });
        let needs_hold = effects.iter().any(|e| e.needs().hold_torques);
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
        x0[layout.eta.clone()].copy_from_slice(&eta0);
        x0[layout.etadot.clone()].copy_from_slice(&etadot0);
        for (e, r) in effects.iter().zip(&own) {
            e.initial_state(&mut x0[r.clone()]);
        }
        // A flexible tree's velocity vector has η̇ after the rotors' rates: in pieces.
        let velocity_at = velocity_in_state(&layout, rotor_effect.map(|i| own[i].clone()))
            .filter(|_| flex.is_none());
        // The preprint layout's unrolled kernel where the tree has that layout (and no
        // flexible body: the flexible algorithms solve those).
        let kernel = UnrolledAba::new(&model)
            .filter(|_| flex.is_none())
            .map(|k| Box::new(k) as Box<dyn Kernel>);
        let fd = ForwardDynamics::new(&model).with_optional_kernel(kernel);
        let mut data = SimData::new(&model, n_rotors, layout.len);
        data.forces = std::mem::replace(&mut data.forces, Forces::new(0, 0, 0))
            .with_torquers(torquers.len())
            .with_elastic(n_elastic);
        data.needs_kinematics = needs_kinematics;
        data.needs_velocities = needs_velocities;
        if !rotor_poses {
            data.pose_bodies = model.n_bodies() - n_rotors;
            // The rotors' transforms, once: their angles stay 0 (`SimData::pose_bodies`).
            forward_poses(&model, &mut data.tree, &data.q)?;
        }
        data.base_tau = base_tau;
        data.flex = flex.as_ref().map(FlexWork::new);
        data.deflection_peaks = flex.as_ref().map_or(Vec::new(), |f| {
            let undeformed = vec![0.0; f.n_elastic()];
            (0..f.rigid().n_bodies())
                .filter_map(|body| {
                    let d = f.deflection_of(body, &undeformed)?;
                    Some(DeflectionPeak {
                        body,
                        tip: 0.0,
                        length: d.length,
                        point: d.point,
                        t: f64::NAN,
                        passed: None,
                    })
                })
                .collect()
        });
        let mut sim = Self {
            model: SimModel {
                tree: model,
                flex,
                layout,
                own,
                event_start,
                event_owner,
                n_events,
                n_user,
                n_rotors,
                rotor_effect,
                velocity_at,
                orbit_effect,
                net_force_to,
                needs_com,
                thrust_commander,
                thruster_owners,
                needs_hold,
                needs_at_start: (needs_kinematics, needs_velocities),
                work,
                elastic_error,
                fd,
                serial: NEXT_SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            },
            log: RunLog {
                calls: vec![0; effects.len()],
                ..RunLog::default()
            },
            effects,
            fresh,
            data,
            x0: Vec::new(),
            x_start: Vec::new(),
            ran: false,
            t0,
        };
        // With an orbit, put the centre of mass at rest in the orbit's frame.
        if free && sim.model.orbit_effect.is_some() && sim.model.tree.total_mass() > 0.0 {
            sim.unpack(&x0);
            sim.kinematics(true).map_err(SimError::Start)?;
            let (p, _) = sim.momentum();
            let du = sim.data.tree.rotation[0].tr_mul(&p) / sim.model.tree.total_mass();
            for k in 0..3 {
                x0[sim.model.layout.velocity.start + k] -= du[k];
            }
        }
        sim.x_start = x0.clone();
        sim.start(x0)?;
        Ok(sim)
    }

    /// Puts a simulation that has run back at its start, as built: fresh copies of the
    /// effects (connected and started again: their modes, held outputs, sensor noise streams
    /// and thruster periods as new), the locks the start sets and no other, the run log
    /// emptied. The constant hinge torques stay as they are. The first call only notes that
    /// the simulation runs. An effect added without a copy
    /// ([`SimulationBuilder::boxed`]) makes a second start an error.
    pub(super) fn restart(&mut self) -> Result<(), SystemError> {
        if !std::mem::replace(&mut self.ran, true) {
            return Ok(());
        }
        let mut effects = Vec::with_capacity(self.effects.len());
        for (e, f) in self.effects.iter().zip(&self.fresh) {
            let Some(f) = f else {
                return Err(SystemError::new(format!(
                    "effect `{}` was added without a copy (`SimulationBuilder::boxed`), so the \
                     simulation runs once: build another to run it again",
                    e.name()
                )));
            };
            effects.push(f.fresh());
        }
        let rotors = self
            .model
            .rotor_effect
            .map(|i| effects[i].rotors())
            .unwrap_or_default();
        let torquers: Vec<Torquer> = effects.iter().flat_map(|e| e.torquers()).collect();
        connect(
            &mut effects,
            &rotors,
            &torquers,
            &self.model.tree,
            self.model.flex.as_ref(),
        );
        self.effects = effects;
        self.log = RunLog {
            calls: vec![0; self.effects.len()],
            ..RunLog::default()
        };
        let d = &mut self.data;
        d.locked.fill(false);
        d.n_locked = 0;
        d.newly_locked = true;
        d.hold.fill(f64::NAN);
        d.requests.clear();
        (d.needs_kinematics, d.needs_velocities) = self.model.needs_at_start;
        self.forget_ahead();
        self.start(self.x_start.clone())
            .map_err(|e| SystemError::new(e.to_string()))
    }

    /// The effects' start hooks (initial locks) at the initial state `x0` (the orbit's
    /// correction made), and the check of its row; sets [`Simulation::x0`].
    fn start(&mut self, mut x0: Vec<f64>) -> Result<(), SimError> {
        let t0 = self.t0;
        let sim = self;
        sim.prepare_with(t0, &x0, true, Hold::All)
            .map_err(SimError::Start)?;
        sim.with_context(t0, &x0, true, |ctx, h| {
            for (e, r) in h.effects.iter_mut().zip(h.own) {
                e.start(ctx, h.forces, &x0[r.clone()], h.requests)
                    .map_err(SimError::Start)?;
            }
            Ok::<(), SimError>(())
        })?;
        let reqs = std::mem::take(&mut sim.data.requests);
        let before = sim.mechanical_energy(t0, &x0).map_err(SimError::Start)?;
        sim.apply_requests(&reqs, &mut x0)?;
        // Its storage back, for the events' requests.
        sim.data.requests = reqs;
        sim.data.requests.clear();
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
        Ok(())
    }
}

/// Tells every effect what the rest of the simulation provides ([`Effect::connect`]).
fn connect(
    effects: &mut [Box<dyn Effect>],
    rotors: &[Rotor],
    torquers: &[Torquer],
    model: &Model,
    flex: Option<&FlexModel>,
) {
    let thrusters: Vec<Thruster> = effects.iter().flat_map(|e| e.thrusters()).collect();
    let links = Links {
        rotors,
        rotors_commanded: effects.iter().any(|e| e.commands_rotors()),
        torquers,
        dipoles_commanded: effects.iter().any(|e| e.commands_dipoles()),
        thrusters: &thrusters,
        model,
        flex,
    };
    for e in effects {
        e.connect(&links);
    }
}

/// Where the tree's velocity vector `[ω; v; hinge rates; rotor rates]` lies in the state as
/// one contiguous run (it does when the rotors' spin rates, if any, follow the hinge rates:
/// the usual order), so that `rhs` moves it, and its derivative, in one copy each.
fn velocity_in_state(layout: &StateLayout, rotors: Option<Range<usize>>) -> Option<usize> {
    let start = if layout.free {
        layout.omega.start
    } else {
        layout.rates.start
    };
    match rotors {
        Some(r) if r.start != layout.rates.end => None,
        _ => Some(start),
    }
}

/// The serial number of the next [`SimModel`] made.
static NEXT_SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

#[cfg(test)]
mod tests {
    use super::velocity_in_state;
    use crate::simulation::StateLayout;

    #[test]
    fn the_velocity_vector_is_one_run_only_when_the_rotor_rates_follow_the_hinge_rates() {
        let wheels_first =
            StateLayout::new(true, 5, 0, &[("wheels".into(), 3), ("orbit".into(), 6)]);
        assert_eq!(
            velocity_in_state(&wheels_first, wheels_first.effect("wheels")),
            Some(9)
        );
        let orbit_first =
            StateLayout::new(true, 5, 0, &[("orbit".into(), 6), ("wheels".into(), 3)]);
        assert_eq!(
            velocity_in_state(&orbit_first, orbit_first.effect("wheels")),
            None
        );
        assert_eq!(velocity_in_state(&orbit_first, None), Some(9));
        let fixed = StateLayout::new(false, 2, 0, &[("wheels".into(), 1)]);
        assert_eq!(velocity_in_state(&fixed, fixed.effect("wheels")), Some(2));
    }
}
