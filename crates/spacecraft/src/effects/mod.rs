//! Effects: the physics a scene may switch on, each a small module behind one trait,
//! [`Effect`].
//!
//! A [`crate::simulation::Simulation`] holds only the effects a scene enables, in the order
//! their declared dependencies give ([`Effect::after`], [`Effect::before`], resolved by a
//! stable topological sort, [`order`]); an effect that is off is never constructed, so it
//! costs nothing and adds no state. At every right-hand-side evaluation the simulation
//!
//! 1. unpacks the state and runs the tree's forward kinematics,
//! 2. builds a [`Context`] (time, kinematics, hinge angles and rates, orbit, bus attitude),
//! 3. calls [`Effect::apply`] on each enabled effect, which adds hinge torques and body
//!    wrenches to [`Forces`] and writes the derivatives of its own states,
//! 4. runs the articulated-body algorithm (hybrid, when hinges are locked) and packs the
//!    derivative.
//!
//! Effects with discontinuities (hinge stops, stiction) declare event functions; the
//! integrator locates their zero crossings and the effect answers with [`Request`]s (lock a
//! hinge, unlock it, set its rate by a momentum-conserving impulse) that the simulation
//! carries out.
//!
//! Adding an effect touches one new file: a type implementing [`Effect`] (only `name` and
//! `apply` are required) and, to be read from a scene's `[effects.<name>]` section,
//! [`SceneEffect`] (its serde section and its construction), registered in a [`Registry`]
//! exactly as the built-in effects are ([`Registry::with_builtins`]). Without a scene, push
//! it with [`crate::simulation::SimulationBuilder::effect`].

pub mod attitude_control;
pub mod bdot;
pub mod drag;
pub mod facets;
pub mod faults;
pub mod gravity_gradient;
pub mod hinge_control;
pub mod hinge_springs;
pub mod hinge_stops;
pub mod magnetic;
pub mod modal_loads;
pub mod orbit;
pub mod order;
pub mod reaction_wheels;
pub mod registry;
pub mod sampling;
pub mod section;
pub mod solar_radiation;
pub mod thrusters;

pub use attitude_control::{AttitudeControl, Target};
pub use bdot::Bdot;
pub use drag::Drag;
pub use facets::Facets;
pub use faults::{FaultKind, Schedule};
pub use gravity_gradient::{GravityGradient, GravityModel};
pub use hinge_control::{HingeControl, HingeProfile};
pub use hinge_springs::HingeSprings;
pub use hinge_stops::{HingeStop, HingeStops, StopAction};
pub use magnetic::Magnetic;
pub use orbit::{Elements, Orbit, OrbitModel, ThirdBodies};
pub use reaction_wheels::{ReactionWheels, Wheel};
pub use registry::{AnyEffect, EffectSet, Registry, SceneEffect, needs_met};
pub use sampling::Sampling;
pub use section::{Bound, SceneText, Section};
pub use solar_radiation::SolarRadiation;
pub use thrusters::{ThrustMode, Thruster, Thrusters};

use nalgebra::UnitQuaternion;
use satsim_integrate::{EventAction, EventDirection, SystemError};
use satsim_tree::flexible::FlexModel;
use satsim_tree::spatial::{Force, Mat3, Motion, RigidInertia, Vec3};
use satsim_tree::{Data, Model};

/// What an effect requires of the rest of the scene. Unmet needs are scene errors that say
/// what to add.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// An `[orbit]` (the effect reads the centre of mass' position).
    pub orbit: bool,
    /// Rotors to command (an effect that adds rotors, e.g. `[effects.reaction_wheels]`): the
    /// effect writes [`Forces::rotor_command`].
    pub rotors: bool,
    /// A free-floating root (`[base] kind = "free"`).
    pub free_base: bool,
    /// Body poses and velocities in [`Context::data`] (forward kinematics is skipped when no
    /// enabled effect needs it; without it `data.rotation`, `data.position` and `data.v` are
    /// stale).
    pub kinematics: bool,
    /// Body poses only, `data.rotation` and `data.position` (and `com` without velocities):
    /// where every effect that reads the bodies says this, the right-hand side leaves
    /// `data.v` stale, a third of the kinematics' work. An effect that says it reads no
    /// `data.v` in any of its functions.
    pub poses: bool,
    /// The system's centre of mass, [`Context::com`] (implies `kinematics`, or only the
    /// poses with `poses`). It is computed only when an enabled effect declares it;
    /// otherwise `Context::com` is `None`.
    pub com: bool,
    /// [`Context::hold_torque`] in `events`, `on_event` and `start` (stick/slip decisions).
    /// It costs a hybrid-dynamics solve and an RNEA per evaluation, never in the rhs.
    pub hold_torques: bool,
    /// Its wrenches have a net force that moves the centre of mass (solar pressure, drag).
    /// The attitude and hinges are integrated in the frame that falls with the centre of
    /// mass; when an enabled effect declares this (and the scene has an orbit), the
    /// simulation moves the net external force `F` to the orbit after every effect has
    /// applied its loads: the orbit's acceleration gains `F / M`, and each body `i` receives
    /// the frame's inertial force `−m_i F / M` at its centre of mass, so the centre of mass
    /// stays at rest in that frame while the torques about it are unchanged. Implies
    /// `kinematics`.
    pub net_force: bool,
}

/// An axisymmetric rotor body that an effect adds to the tree (a reaction wheel, a momentum
/// wheel, a control-moment gyro's rotor), hinged to its carrier (the root unless `body` names
/// another body) about `axis`. Its dynamics do not depend on its angle, which is therefore not
/// a state: its spin rate relative to the carrier is.
#[derive(Clone, Debug, PartialEq)]
pub struct Rotor {
    /// Body and hinge name (the reaction wheels use `wheel_<name>`).
    pub name: String,
    /// The carrier body's name; `None`: the root.
    pub body: Option<String>,
    /// Unit spin axis, the carrier's axes: the true axis, misalignment included.
    pub axis: Vec3,
    /// The unit spin axis the flight software assumes (the carrier's axes): `axis` without
    /// its misalignment. Controllers allocate torques with this one.
    pub nominal: Vec3,
    /// Centre of the rotor in the carrier's frame (m).
    pub at: Vec3,
    /// Mass (kg, default 0: the wheel's mass is usually part of the bus).
    pub mass: f64,
    /// Moment of inertia about the spin axis (kg m²).
    pub axial: f64,
    /// Moment of inertia about any transverse axis through the centre (kg m²).
    pub transverse: f64,
}

impl Rotor {
    /// The rotor's inertia tensor about its centre, the carrier's axes (the rotor frame is
    /// parallel to the carrier's at zero angle, and the tensor is invariant under spin).
    pub fn inertia(&self) -> Mat3 {
        let a = self.axis;
        let aat = a * a.transpose();
        aat * self.axial + (Mat3::identity() - aat) * self.transverse
    }
    /// Whether the root carries it (the controllers' allocations use only those: they work
    /// in the bus's axes, which a rotor on a moving body leaves).
    pub fn on_root(&self) -> bool {
        self.body.is_none()
    }
}

/// A magnetic torquer that an effect owns (`[[effects.magnetic.torquer]]`): a coil of
/// dipole along `axis` of `body`, commanded through [`Forces::dipole_command`].
#[derive(Clone, Debug, PartialEq)]
pub struct Torquer {
    /// Its name (columns `dipole_<name>`).
    pub name: String,
    /// The body that carries it (index in the model's bodies).
    pub body: usize,
    /// Unit axis, that body's axes.
    pub axis: Vec3,
    /// The largest dipole it makes (A m²).
    pub max_dipole: f64,
}

/// The orbit of the system's centre of mass at the time of evaluation (inertial frame, SI).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitState {
    /// Position of the centre of mass from the Earth's centre (m).
    pub r: Vec3,
    /// Its velocity (m/s).
    pub v: Vec3,
    /// Gravitational parameter μ (m³/s²).
    pub mu: f64,
}

impl OrbitState {
    /// The unit local vertical (from the Earth's centre to the satellite), inertial axes.
    pub fn vertical(&self) -> Vec3 {
        self.r.normalize()
    }
    /// The local orbital frame (LVLH), orbital to inertial: z towards the Earth's centre
    /// (nadir), y along the negative orbit normal `−r × v`, x = y × z completing the triad
    /// (along the velocity on a circular orbit). The frame turns at `r × v / r²`.
    pub fn orbital_frame(&self) -> UnitQuaternion<f64> {
        let z = -self.r.normalize();
        let y = -self.r.cross(&self.v).normalize();
        let x = y.cross(&z);
        UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(
            Mat3::from_columns(&[x, y, z]),
        ))
    }
    /// The orbital frame's angular velocity, inertial axes (rad/s): `r × v / r²`, the rate
    /// [`crate::effects::AttitudeControl`]'s orbital target turns at. Exact on a Keplerian
    /// orbit; a perturbation's acceleration along the orbit normal (J2) also turns the frame
    /// about the vertical, at `r (a·ĥ)/h`, which this leaves out (for J2 in a low orbit, of
    /// order 1e-3 of the orbital rate).
    pub fn orbital_rate(&self) -> Vec3 {
        self.r.cross(&self.v) / self.r.norm_squared()
    }
}

/// Everything an effect may read during an evaluation.
pub struct Context<'a> {
    /// Time (s).
    pub t: f64,
    /// The tree (the scene's model plus any rotor bodies).
    pub model: &'a Model,
    /// Kinematics after `forward_kinematics`: `rotation[i]` (body to inertial),
    /// `position[i]` (body origin, relative to the tree's reference point), `v[i]`.
    pub data: &'a Data,
    /// The tree's full position vector (attitude, position (zero), all hinge angles).
    pub q: &'a [f64],
    /// The tree's full velocity vector.
    pub v: &'a [f64],
    /// Number of the scene model's hinges (the rotors' hinges follow).
    pub n_hinges: usize,
    /// The model's hinge angles, file order (rad).
    pub angles: &'a [f64],
    /// The model's hinge rates, file order (rad/s).
    pub rates: &'a [f64],
    /// Which hinges (model hinges then rotors) are locked.
    pub locked: &'a [bool],
    /// The system's centre of mass, inertial axes, relative to the tree's reference point:
    /// `Some` when an enabled effect declares [`Needs::com`] and the poses are current
    /// (see [`Context::com_or_err`]), `None` otherwise, never a stale or zero value.
    pub com: Option<Vec3>,
    /// The orbit of the centre of mass, when the scene has one.
    pub orbit: Option<OrbitState>,
    /// Root (bus) attitude, bus to inertial.
    pub attitude: UnitQuaternion<f64>,
    /// Root angular velocity, bus axes (rad/s).
    pub omega: Vec3,
    /// Rotor spin rates relative to the bus (rad/s), one per rotor.
    pub rotor_rates: &'a [f64],
    /// The flexible bodies' elastic coordinates `η` (the layout's order; empty without).
    pub eta: &'a [f64],
    /// Their rates `η̇`.
    pub etadot: &'a [f64],
    /// Each body's inertia at its deformation (body axes, about its origin: a stiffened
    /// beam's [`FlexModel::deformed_inertia`] of `eta`, the rigid model's otherwise), as the
    /// flexible kinematics made it for the dynamics: `Some` when the poses are current in a
    /// tree with flexible bodies, `None` otherwise.
    pub deformed: Option<&'a [RigidInertia]>,
    /// Per hinge (model hinges then rotors): the total torque the hinge must receive to have
    /// zero acceleration, everything else as now (the locked hinges locked): `(M q̈ + C −
    /// Jᵀfext)_k` with `q̈` from hybrid dynamics. A hinge held by friction sticks while the
    /// friction it needs, `hold − motor`, is within its static friction. Filled for locked
    /// hinges in `events` (when an effect's [`Effect::event_reads`] asks for them), for
    /// every hinge in `on_event` and `start`, and only when an effect sets
    /// [`Needs::hold_torques`]; NaN where not computed.
    pub hold_torque: &'a [f64],
    /// Whether the simulation asks the effects for [`Effect::power`] after this
    /// evaluation's `apply` (the right-hand side, with the energy budget on). An effect that
    /// works out its power in `apply` may skip that work when it is false: the other passes
    /// (event functions, output rows) and a run without the budget never read it.
    pub power: bool,
}

impl Needs {
    /// What an effect that loads the bodies' facets from the environment needs (solar
    /// pressure, drag): an orbit, a free base, the poses and the centre of mass, and its net
    /// force carried to the orbit.
    pub const SURFACE_LOADS: Needs = Needs {
        orbit: true,
        free_base: true,
        kinematics: true,
        poses: false,
        com: true,
        hold_torques: false,
        rotors: false,
        net_force: true,
    };
}

impl Context<'_> {
    /// Index (in the tree's hinge order) of rotor `j`'s hinge.
    pub fn rotor_hinge(&self, j: usize) -> usize {
        self.n_hinges + j
    }
    /// The centre of mass, or an error naming the effect that read it without declaring
    /// [`Needs::com`].
    pub fn com_or_err(&self, effect: &str) -> Result<Vec3, SystemError> {
        self.com.ok_or_else(|| {
            SystemError::new(format!(
                "{effect} reads the centre of mass but does not declare `Needs::com`"
            ))
        })
    }
    /// The orbit, or an error naming the effect that needed it.
    pub fn orbit_or_err(&self, effect: &str) -> Result<OrbitState, SystemError> {
        self.orbit
            .ok_or_else(|| SystemError::new(format!("{effect} needs an orbit")))
    }
}

/// What effects produce: generalised forces and commands.
#[derive(Clone, Debug)]
pub struct Forces {
    /// Torque on each hinge (model hinges in file order, then rotors), N m, acting on the
    /// child, reacting on the parent.
    pub hinge_torque: Vec<f64>,
    /// External wrench on each body (in `model.bodies` order), body coordinates, about the
    /// body frame's origin.
    pub body_wrench: Vec<Force>,
    /// Whether any effect wrote a body wrench in this evaluation.
    pub has_wrench: bool,
    /// How many wrenches were added in this evaluation (the energy budget measures the
    /// wrenches' power only after an effect that added one).
    wrenches_added: u32,
    /// Motor torque commanded to each rotor (N m, on the rotor about its axis, tree order):
    /// the channel from a controller ([`Effect::commands_rotors`]) to the effect that owns
    /// the rotors, which runs after it ([`Effect::before`]) and decides what to do with it
    /// (limits, friction). Zeroed before every evaluation.
    pub rotor_command: Vec<f64>,
    /// Dipole (A m²) commanded to each magnetic torquer (in [`Links::torquers`] order): the
    /// same channel for torquers, from a controller ([`Effect::commands_dipoles`]) to the
    /// effect that owns them ([`Effect::torquers`]), which clamps it. Zeroed before every
    /// evaluation; empty without torquers.
    pub dipole_command: Vec<f64>,
    /// Motor commands held from outside the effects (N m, one per rotor, tree order: the
    /// stepping API's `wheel_<name>` inputs), added by the effect that owns the rotors to
    /// its command (the controller's, or its constant `torque`) before its limits. Kept
    /// between evaluations (zero unless set).
    pub rotor_input: Vec<f64>,
    /// Dipoles held from outside the effects (A m², one per torquer, [`Links::torquers`]
    /// order: the stepping API's `dipole_<name>` inputs), added by the effect that owns the
    /// torquers to its command before it clamps it. Kept between evaluations.
    pub dipole_input: Vec<f64>,
    /// Generalised force on each elastic coordinate `ηₖ` of the flexible bodies (the
    /// layout's `eta` order; N √kg⁻¹·m… the work per unit `ηₖ`): where a load on a flexible
    /// body reaches its modes, `Σ φₖ(p)·f + ψₖ(p)·n` for a force `f` and couple `n` at the
    /// point `p` of the body (its mode shapes there, [`Links::flex`]). Zeroed before every
    /// evaluation; empty without flexible bodies.
    pub elastic: Vec<f64>,
}

impl Forces {
    /// Zeroed forces for `n_hinges` hinges, `n_bodies` bodies and `n_rotors` rotors.
    pub fn new(n_hinges: usize, n_bodies: usize, n_rotors: usize) -> Self {
        Self {
            hinge_torque: vec![0.0; n_hinges],
            body_wrench: vec![Force::zero(); n_bodies],
            has_wrench: false,
            wrenches_added: 0,
            rotor_command: vec![0.0; n_rotors],
            dipole_command: Vec::new(),
            rotor_input: vec![0.0; n_rotors],
            dipole_input: Vec::new(),
            elastic: Vec::new(),
        }
    }
    /// Room for `n` elastic coordinates' generalised forces.
    pub fn with_elastic(mut self, n: usize) -> Self {
        self.elastic = vec![0.0; n];
        self
    }
    /// The power (W) of the elastic forces, `Σ_k Q_k η̇_k`.
    pub fn elastic_power(&self, etadot: &[f64]) -> f64 {
        self.elastic.iter().zip(etadot).map(|(q, e)| q * e).sum()
    }
    /// Room for `n` torquers' commands.
    pub fn with_torquers(mut self, n: usize) -> Self {
        self.dipole_command = vec![0.0; n];
        self.dipole_input = vec![0.0; n];
        self
    }
    /// Clears everything to zero.
    pub fn clear(&mut self) {
        self.hinge_torque.fill(0.0);
        if self.has_wrench {
            self.body_wrench.fill(Force::zero());
            self.has_wrench = false;
        }
        self.wrenches_added = 0;
        self.rotor_command.fill(0.0);
        self.dipole_command.fill(0.0);
        self.elastic.fill(0.0);
    }
    /// As [`Forces::clear`], with the hinge torques set to `hinge_torque` (one copy rather
    /// than zeroing first: this runs at every right-hand side).
    pub fn reset_to(&mut self, hinge_torque: &[f64]) {
        self.hinge_torque.copy_from_slice(hinge_torque);
        if self.has_wrench {
            self.body_wrench.fill(Force::zero());
            self.has_wrench = false;
        }
        self.wrenches_added = 0;
        self.rotor_command.fill(0.0);
        self.dipole_command.fill(0.0);
        self.elastic.fill(0.0);
    }
    /// The power (W) of the hinge torques, `Σ_k τ_k q̇_k`, with `v` the tree's velocity
    /// vector (its first `n_base` entries the root's). The wheel commands are not forces
    /// and do not count.
    pub fn hinge_power(&self, v: &[f64], n_base: usize) -> f64 {
        self.hinge_torque
            .iter()
            .zip(&v[n_base..])
            .map(|(t, r)| t * r)
            .sum()
    }
    /// The power (W) of the body wrenches, `Σ_i f_i · v_i`, with `body_v` the bodies'
    /// spatial velocities in body coordinates (not read when no wrench was added).
    pub fn wrench_power(&self, body_v: &[Motion]) -> f64 {
        if !self.has_wrench {
            return 0.0;
        }
        self.body_wrench
            .iter()
            .zip(body_v)
            .map(|(f, m)| m.dot(f))
            .sum()
    }
    /// How many wrenches [`Forces::add_wrench`] added since the last [`Forces::clear`].
    pub fn wrenches_added(&self) -> u32 {
        self.wrenches_added
    }
    /// Adds a wrench (body coordinates, about the body origin) on body `i`.
    pub fn add_wrench(&mut self, i: usize, f: Force) {
        self.body_wrench[i] += f;
        self.has_wrench = true;
        self.wrenches_added = self.wrenches_added.wrapping_add(1);
    }
}

/// The non-conservative power of an effect's forces at one evaluation (W), split by where
/// the energy goes: see [`Effect::power`] and the energy budget in
/// [`crate::simulation`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Power {
    /// Power that actuators (motors, controllers) and other non-conservative driving forces
    /// (a field that moves with the orbit) feed into the system; negative when they brake it.
    pub actuator: f64,
    /// Power lost to dissipation (dampers, friction); `>= 0` for a passive element.
    pub dissipated: f64,
}

impl Power {
    /// All of `p` is an actuator's.
    pub fn actuator(p: f64) -> Self {
        Self {
            actuator: p,
            dissipated: 0.0,
        }
    }
    /// All of `p` is dissipated.
    pub fn dissipated(p: f64) -> Self {
        Self {
            actuator: 0.0,
            dissipated: p,
        }
    }
}

/// What the simulation tells every effect once it is built ([`Effect::connect`]).
#[derive(Clone, Copy, Debug)]
pub struct Links<'a> {
    /// The tree's rotors, in hinge order after the model's hinges (one entry of
    /// [`Forces::rotor_command`] each).
    pub rotors: &'a [Rotor],
    /// Whether an enabled effect writes [`Forces::rotor_command`] ([`Effect::commands_rotors`]).
    pub rotors_commanded: bool,
    /// The magnetic torquers, one entry of [`Forces::dipole_command`] each.
    pub torquers: &'a [Torquer],
    /// Whether an enabled effect writes [`Forces::dipole_command`] ([`Effect::commands_dipoles`]).
    pub dipoles_commanded: bool,
    /// The thrusters of every effect ([`Effect::thrusters`]), in the effects' order: the
    /// order of [`Effect::thrust_commands`].
    pub thrusters: &'a [Thruster],
    /// The tree every [`Context::model`] will be (the scene's model plus the rotors), for
    /// per-body constants an effect works out once rather than at every evaluation.
    pub model: &'a Model,
    /// The flexible bodies, when the tree has any: their mode shapes at a point
    /// ([`FlexModel::point_shape`]) turn a load there into [`Forces::elastic`].
    pub flex: Option<&'a FlexModel>,
}

/// What an effect's event functions ([`Effect::events`]) read beyond the state, so that the
/// event pass (run at the end of every step) computes only that. Always available to them:
/// the time, the hinge angles and rates, the locked flags, the attitude and rates, the orbit,
/// the effect's own states and its own fields (its mode). See [`Effect::event_reads`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EventReads {
    /// `forces`: what every effect's [`Effect::apply`] writes at this state (then every
    /// effect is applied). Otherwise `forces` holds an earlier evaluation's values.
    pub forces: bool,
    /// [`Context::hold_torque`] of the locked hinges (a hybrid-dynamics solve and an RNEA,
    /// after every `apply`; only with [`Needs::hold_torques`]). Otherwise NaN.
    pub hold_torques: bool,
    /// Body poses and velocities in [`Context::data`], and [`Context::com`] (forward
    /// kinematics). Otherwise stale (and `com` is `None`).
    pub kinematics: bool,
}

impl EventReads {
    /// Nothing beyond the state: no effect is applied, no kinematics, no hold torques.
    pub const STATE: Self = Self {
        forces: false,
        hold_torques: false,
        kinematics: false,
    };
    /// Everything (the default: always right, the most work).
    pub const ALL: Self = Self {
        forces: true,
        hold_torques: true,
        kinematics: true,
    };
    /// What either reads.
    pub fn union(self, o: Self) -> Self {
        Self {
            forces: self.forces || o.forces,
            hold_torques: self.hold_torques || o.hold_torques,
            kinematics: self.kinematics || o.kinematics,
        }
    }
}

/// Whose hold torques an effect's event functions read ([`Effect::hold_reads`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HoldReads {
    /// Every locked hinge's.
    Locked,
    /// The locked rotors' only.
    Rotors,
}

/// What an effect asks the simulation to do at one of its events.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Request {
    /// Bring hinge `h` (tree order) to rest by a plastic, momentum-conserving impulse, then
    /// lock it (it transmits rigidly until unlocked).
    Lock(usize),
    /// Bring hinge `hinge` (tree order) to `rate` by a momentum-conserving impulse, then lock
    /// it there: it turns at that rate, transmitting rigidly, until unlocked (a wheel held
    /// at its speed limit).
    Hold {
        /// The hinge, tree order.
        hinge: usize,
        /// Its rate while locked (rad/s).
        rate: f64,
    },
    /// Release a locked hinge.
    Unlock(usize),
    /// Change hinge `h`'s rate to `rate` by a momentum-conserving impulse between its two
    /// bodies (a rebound).
    SetRate {
        /// The hinge, tree order.
        hinge: usize,
        /// The rate after the impulse (rad/s).
        rate: f64,
    },
}

/// One piece of physics. Only [`Effect::name`] and [`Effect::apply`] are required.
pub trait Effect: Send {
    /// The scene's name for it (`hinge_springs`, ...).
    fn name(&self) -> &str;
    /// What it needs from the scene.
    fn needs(&self) -> Needs {
        Needs::default()
    }
    /// Number of its own states (orbit: 6, wheels: one per wheel).
    fn n_states(&self) -> usize {
        0
    }
    /// Names of its own states (for the state layout and output).
    fn state_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Its initial own states.
    fn initial_state(&self, _own: &mut [f64]) {}
    /// The centre of mass' orbit held in its own states, for an orbit effect.
    fn orbit_state(&self, _own: &[f64]) -> Option<OrbitState> {
        None
    }
    /// Rotor bodies it adds to the tree. An effect with rotors has exactly one own state per
    /// rotor, its spin rate, whose derivative the dynamics provide (`apply` leaves it alone).
    fn rotors(&self) -> Vec<Rotor> {
        Vec::new()
    }
    /// Whether it writes motor commands into [`Forces::rotor_command`] (one per rotor of the
    /// tree, see [`Effect::connect`]).
    fn commands_rotors(&self) -> bool {
        false
    }
    /// Magnetic torquers it owns (at most one enabled effect owns torquers).
    fn torquers(&self) -> Vec<Torquer> {
        Vec::new()
    }
    /// Whether it writes dipole commands into [`Forces::dipole_command`] (one per torquer,
    /// see [`Effect::connect`]); it must run before the effect that owns the torquers.
    fn commands_dipoles(&self) -> bool {
        false
    }
    /// Thrusters it owns (the stepping API's `thrust_<name>` inputs, in this order).
    fn thrusters(&self) -> Vec<Thruster> {
        Vec::new()
    }
    /// Holds the stepping API's duty `duty` (in [0, 1]) for its thruster `j` (in
    /// [`Effect::thrusters`] order), set at time `t`: added to the thruster's constant duty
    /// from the first period start at or after `t` (a period start at `t` already latched
    /// is latched again).
    fn hold_thrust_input(&mut self, _j: usize, _duty: f64, _t: f64) {}
    /// Whether it commands the thrusters ([`Effect::thrust_commands`]; at most one enabled
    /// effect does).
    fn commands_thrusters(&self) -> bool {
        false
    }
    /// The duties (each in [0, 1]) it commands now, one per thruster of [`Links::thrusters`]
    /// (empty when it commands none). The simulation reads them after every time stop's
    /// samples and holds each on the effect that owns the thruster
    /// ([`Effect::hold_thrust_command`]), so that a command sampled at a period start is
    /// latched at that start, and one sampled between period starts at the next.
    fn thrust_commands(&self) -> &[f64] {
        &[]
    }
    /// Holds a controller's duty `duty` (in [0, 1]) for its thruster `j` (in
    /// [`Effect::thrusters`] order), set at time `t`: added to the thruster's constant duty
    /// and the stepping API's input, latched as [`Effect::hold_thrust_input`] is.
    fn hold_thrust_command(&mut self, _j: usize, _duty: f64, _t: f64) {}
    /// Effects (by [`Effect::name`]) that must run before this one in every evaluation, e.g.
    /// because it reads what they write into [`Forces`]. Each must be enabled: a missing one
    /// or a cycle is a setup error.
    fn after(&self) -> &[&str] {
        &[]
    }
    /// Effects that must run after this one (attitude control before the wheels it
    /// commands). Each must be enabled, as for [`Effect::after`].
    fn before(&self) -> &[&str] {
        &[]
    }
    /// Called once when the simulation is built, before [`Effect::start`]: what the rest of
    /// the simulation provides (the tree's rotors, whether a controller commands them).
    fn connect(&mut self, _links: &Links) {}
    /// The next sample instant of a discrete-time law (a controller with a `period`):
    /// the simulation lands a step exactly there and calls [`Effect::sample`].
    /// `f64::INFINITY` (the default) for an effect that samples nothing.
    fn next_sample(&self) -> f64 {
        f64::INFINITY
    }
    /// Evaluates the law at its sample instant `ctx.t` (due per
    /// [`satsim_integrate::stop_due`]) and holds its output until the next: `apply` then
    /// applies the held output, exactly constant over the sample interval. Must move
    /// [`Effect::next_sample`] past `ctx.t`.
    fn sample(&mut self, _ctx: &Context) -> Result<(), SystemError> {
        Ok(())
    }
    /// Whether it only observes (a sensor): `apply` adds nothing and `sample` changes nothing
    /// the dynamics read, so that a sample of it alone does not restart the integrator (the
    /// steps stay those of a run without it).
    fn observes_only(&self) -> bool {
        false
    }
    /// Whether [`Effect::sample`] reads the body poses and velocities in [`Context::data`]:
    /// the simulation then runs forward kinematics at its sample instants (not in every
    /// right-hand side). The default: [`Needs::kinematics`] or [`Needs::poses`].
    fn sample_reads_kinematics(&self) -> bool {
        let n = self.needs();
        n.kinematics || n.poses
    }
    /// The readings of the sensors it models, appended to `out` as `(name, values)`: each
    /// the reading last taken or, where a sample is due at `ctx.t`, the one taken there
    /// (see [`crate::sensors`]). An effect that measures nothing appends nothing.
    fn measure(&self, _ctx: &Context, _out: &mut Vec<(String, Vec<f64>)>) {}
    /// Adds its hinge torques and body wrenches to `forces` and writes the derivatives of its
    /// own states (`own`) into `own_dot`.
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        own: &[f64],
        own_dot: &mut [f64],
    ) -> Result<(), SystemError>;
    /// Its potential energy (J), counted in the total energy.
    fn potential_energy(&self, _ctx: &Context, _own: &[f64]) -> f64 {
        0.0
    }
    /// The non-conservative power of the forces it added in its last [`Effect::apply`] (on
    /// the same state), for the energy budget. `applied` is the power of those forces, which
    /// the simulation measures: `Σ_k Δτ_k q̇_k + Σ_i Δf_i · v_i` over the hinge torques and
    /// body wrenches it added. An effect with a [`Effect::potential_energy`] must leave out
    /// the conservative part, `−dV/dt` at fixed time (it is counted in the potential); what
    /// remains it splits into actuator work and dissipation. The default counts all of
    /// `applied` as an actuator's: right for an effect that has neither a potential nor
    /// losses (a motor, a controller).
    fn power(&self, _ctx: &Context, _own: &[f64], applied: f64) -> Power {
        Power::actuator(applied)
    }
    /// Whether [`Effect::power`] reads `applied` (the default). An effect that works out its
    /// power itself says `false`: the simulation then need not measure the power of its
    /// wrenches, which takes the bodies' velocities (see [`Needs::poses`]).
    fn power_reads_applied(&self) -> bool {
        true
    }
    /// Whether, declaring [`Needs::poses`], it reads the poses of the rotor bodies the
    /// effects add (the reaction wheels': [`Rotor`]) in [`Effect::apply`] (the default, always
    /// right). A rotor's angle is no state: its pose is its carrier's, turned about its axis
    /// by a fixed angle, and an effect that loads a balanced rotor through its carrier (the
    /// gravity gradient) reads none. Where no effect reads them (and none needs the
    /// velocities or the centre of mass), the right-hand side's poses pass leaves the rotors'
    /// stale; every other pass computes them.
    fn reads_rotor_poses(&self) -> bool {
        true
    }
    /// Whether its [`Effect::output`] or [`Effect::potential_energy`] reads what its last
    /// `apply` kept (a command, a mode), so that an output row runs `apply` first: the
    /// default. `false` lets a row whose effects all say so skip the effects' pass; right
    /// for an effect whose `apply` only adds forces, which rows do not read.
    fn row_reads_apply(&self) -> bool {
        true
    }
    /// Extra output columns.
    fn output_columns(&self) -> Vec<String> {
        Vec::new()
    }
    /// Values of [`Effect::output_columns`], appended to `row`.
    fn output(&self, _ctx: &Context, _own: &[f64], _row: &mut Vec<f64>) {}
    /// Called once before the run with the initial state: may lock hinges (a wheel at rest
    /// under static friction, a hinge that starts on a latching stop).
    fn start(
        &mut self,
        _ctx: &Context,
        _forces: &Forces,
        _own: &[f64],
        _requests: &mut Vec<Request>,
    ) -> Result<(), SystemError> {
        Ok(())
    }
    /// Number of event functions (fixed for the run).
    fn n_events(&self) -> usize {
        0
    }
    /// Evaluates the event functions into `g`. What is current in `ctx` and `forces` beyond
    /// the state is what some effect's [`Effect::event_reads`] asks for.
    fn events(&self, _ctx: &Context, _forces: &Forces, _own: &[f64], _g: &mut [f64]) {}
    /// What [`Effect::events`] reads beyond the state, asked before every evaluation of the
    /// event functions (so it may depend on the effect's mode: a wheel reads hold torques only
    /// while it is stuck). The default, everything ([`EventReads::ALL`], the poses only when
    /// the effect declares [`Needs::kinematics`] or [`Needs::poses`]), is always right; a
    /// narrower answer spares
    /// the event pass, at every step, the effects' `apply`, kinematics or a hybrid-dynamics
    /// solve. It must be exact: what is not declared is stale in `events`.
    fn event_reads(&self) -> EventReads {
        EventReads {
            kinematics: self.needs().kinematics || self.needs().poses,
            ..EventReads::ALL
        }
    }
    /// Whose [`Context::hold_torque`] [`Effect::events`] reads when [`Effect::event_reads`]
    /// asks for hold torques: every locked hinge's (the default, always right), or only the
    /// locked rotors' ([`HoldReads::Rotors`]: the others are then NaN in `events`), which
    /// spares the event pass the inverse dynamics of the rest of the tree.
    fn hold_reads(&self) -> HoldReads {
        HoldReads::Locked
    }
    /// Which sign changes of event `k` count.
    fn event_direction(&self, _k: usize) -> EventDirection {
        EventDirection::Both
    }
    /// Handles its event `k`: may change its own states and mode, and push requests.
    /// Return [`EventAction::Reset`] when anything changed (the integrator restarts).
    fn on_event(
        &mut self,
        _k: usize,
        _ctx: &Context,
        _forces: &Forces,
        _own: &mut [f64],
        _requests: &mut Vec<Request>,
    ) -> EventAction {
        EventAction::Continue
    }
    /// A short description of what happened at the last event (for the run summary).
    fn describe_event(&self, _k: usize) -> String {
        String::new()
    }
    /// [`Effect::describe_event`] appended to `out`, which the simulation's event log
    /// reserved: an effect that keeps its description in a buffer of its own appends it here
    /// without allocating (the default appends `describe_event`'s string).
    fn describe_event_into(&self, k: usize, out: &mut String) {
        out.push_str(&self.describe_event(k));
    }
    /// What happened at its last [`Effect::sample`] that the run's event log should show (a
    /// flight software's mode switch), moved into `out`: the simulation logs each at the
    /// sample's time. The default logs nothing.
    fn drain_sample_log(&mut self, _out: &mut Vec<String>) {}
}

/// The room an effect reserves for its event descriptions (bytes): one written into it with
/// [`set_text`] allocates nothing unless longer.
pub(crate) const EVENT_TEXT: usize = 192;

/// Replaces `out` with the formatted `args`, in its own storage (an event's description).
pub(crate) fn set_text(out: &mut String, args: std::fmt::Arguments) {
    use std::fmt::Write as _;
    out.clear();
    let _ = out.write_fmt(args);
}

/// Hamilton product of quaternions stored `[w, x, y, z]`.
#[inline]
pub fn quat_mul(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::Forces;
    use satsim_tree::spatial::{Force, Vec3};

    #[test]
    fn reset_to_sets_the_hinge_torques_and_clears_the_rest() {
        let mut f = Forces::new(3, 2, 1);
        f.hinge_torque.copy_from_slice(&[1.0, 2.0, 3.0]);
        f.add_wrench(1, Force::new(Vec3::x(), Vec3::y()));
        f.rotor_command[0] = 4.0;
        f.reset_to(&[0.5, 0.0, -0.5]);
        assert_eq!(f.hinge_torque, [0.5, 0.0, -0.5]);
        assert!(!f.has_wrench && f.wrenches_added() == 0);
        assert!(f.body_wrench.iter().all(|w| *w == Force::zero()));
        assert_eq!(f.rotor_command, [0.0]);
    }
}
