//! [`SimModel`]: what a simulation makes once and never writes during a run.

use super::StateLayout;
use satsim_integrate::SystemError;
use satsim_tree::error::Num;
use satsim_tree::flexible::FlexModel;
use satsim_tree::{DynamicsError, ForwardDynamics, Model};
use std::ops::Range;

/// A dynamics error that names a coordinate by its index (a pivot that failed), with the
/// coordinate in words: ``… at coordinate 15 (pivot -56); coordinate 15 is body `panel1`'s
/// mode 2``.
#[derive(Debug, thiserror::Error)]
#[error("{error}; coordinate {index} is {what}")]
pub struct NamedDynamicsError {
    /// The error.
    pub error: DynamicsError,
    /// The index it names (of the tree's `v`: the scene's model, its rotors, then the modes).
    pub index: usize,
    /// That coordinate in words ([`FlexModel::coordinate`], [`Model::coordinate`]).
    pub what: String,
}

/// The immutable part of a [`Simulation`](super::Simulation): the tree (the scene's model
/// plus the effects' rotor bodies), the state layout, where each effect's states and event
/// functions lie, what the effects need computed, and the dynamics' kernel. Made by
/// [`SimulationBuilder::build`](super::SimulationBuilder::build).
pub struct SimModel {
    /// The tree: the scene's model, then one rotor body per wheel hinged to its root.
    pub(super) tree: Model,
    /// The same tree with its flexible bodies' modes, when it has any: every solve then
    /// goes through the flexible algorithms (`satsim_tree::flexible`), and the effects see
    /// the poses of its kinematics.
    pub(super) flex: Option<FlexModel>,
    pub(super) layout: StateLayout,
    /// Each effect's own states in `x` (the effects' order).
    pub(super) own: Vec<Range<usize>>,
    /// Each effect's first event function; `n_events` in all.
    pub(super) event_start: Vec<usize>,
    pub(super) n_events: usize,
    /// The effect that owns each event function (asked at every step, per function).
    pub(super) event_owner: Vec<usize>,
    /// The scene's hinges (the tree's first hinges) and the rotors after them.
    pub(super) n_user: usize,
    pub(super) n_rotors: usize,
    /// The effect that adds the rotors (its states are their spin rates).
    pub(super) rotor_effect: Option<usize>,
    /// Where the tree's whole velocity vector lies in the state, as one run (see
    /// `velocity_in_state` in build.rs); `None`: in pieces.
    pub(super) velocity_at: Option<usize>,
    pub(super) orbit_effect: Option<usize>,
    /// The orbit effect, when an effect declares [`Needs::net_force`](crate::effects::Needs::net_force):
    /// the effects' net force then moves the orbit (see `carry_net_force` in rhs.rs).
    pub(super) net_force_to: Option<usize>,
    /// Whether an effect reads [`Context::com`](crate::effects::Context::com) (computed
    /// only then), or hold torques.
    pub(super) needs_com: bool,
    /// The effect that commands the thrusters ([`Effect::commands_thrusters`](crate::effects::Effect::commands_thrusters)),
    /// and each thruster's owner and index there ([`Links::thrusters`](crate::effects::Links::thrusters) order).
    pub(super) thrust_commander: Option<usize>,
    pub(super) thruster_owners: Vec<(usize, usize)>,
    pub(super) needs_hold: bool,
    /// [`SimData`](super::SimData)'s `needs_kinematics` and `needs_velocities` as built
    /// (a run may turn them on), for a run that starts again.
    pub(super) needs_at_start: (bool, bool),
    /// The energy budget's states in `x`: `[actuator work, dissipated energy]` (J), or
    /// empty when not tracked.
    pub(super) work: Range<usize>,
    /// Whether `η`, `η̇` count in the error norm
    /// ([`SimulationBuilder::elastic_error`](super::SimulationBuilder::elastic_error)).
    pub(super) elastic_error: bool,
    /// The forward dynamics, chosen once: ABA, with the preprint layout's unrolled kernel
    /// ([`satsim_satellite::kernel::UnrolledAba`]) where the tree has that layout (it takes
    /// every lock mask it accepts).
    pub(super) fd: ForwardDynamics,
    /// This model's serial number in the process: the lanes' cache of gathered kernels
    /// (`lanes.rs`) knows by it that a run is the one it gathered (an address could be
    /// reused by the next run's model).
    pub(super) serial: u64,
}

/// The span of the bodies' masses past which a singular solve is put down to it
/// ([`SimModel::dynamics_error`]): double precision keeps 16 digits, and a light body's
/// inertia added to a heavy one's must keep some. Real spacecraft span far less (a 400 t
/// station and a 10 g sensor: 4e7).
pub const MASS_SPAN: f64 = 1e12;

impl SimModel {
    /// A dynamics error as the right-hand side reports it, the coordinate it names put in
    /// words ([`NamedDynamicsError`]).
    pub(super) fn dynamics_error(&self, e: DynamicsError) -> SystemError {
        match e {
            DynamicsError::NotPositiveDefinite { index, .. } => {
                let what = match &self.flex {
                    Some(f) => f.coordinate(index),
                    None => self.tree.coordinate(index),
                };
                SystemError::from_error(NamedDynamicsError {
                    error: e,
                    index,
                    what,
                })
            }
            // A singular pivot where the masses span more than round-off leaves of the light
            // bodies' inertia: that is why (a slip of units, most likely).
            e @ (DynamicsError::SingularBase | DynamicsError::SingularHinge { .. }) => {
                match self.mass_span() {
                    Some(why) => SystemError::new(format!("{e}; {why}")),
                    None => SystemError::from_error(e),
                }
            }
            e => SystemError::from_error(e),
        }
    }

    /// Where the bodies' masses (a flexible body's with its structure's) span more than
    /// [`MASS_SPAN`], why a solve of the tree can be singular: the light bodies' inertia
    /// added to the heavy one's across a hinge falls below its round-off.
    fn mass_span(&self) -> Option<String> {
        let tree = self.flex.as_ref().map_or(&self.tree, |f| f.rigid());
        let with_mass = || tree.bodies().iter().filter(|b| b.mass() > 0.0);
        let heavy = with_mass().max_by(|a, b| a.mass().total_cmp(&b.mass()))?;
        let light = with_mass().min_by(|a, b| a.mass().total_cmp(&b.mass()))?;
        let span = heavy.mass() / light.mass();
        (span > MASS_SPAN).then(|| {
            format!(
                "the bodies' masses span {span:.1e}: body `{}` has {} kg (with any beam's rho_A x length) and body `{}` {} kg, and beyond {MASS_SPAN:.0e} the light bodies' inertia is lost in the heavy one's round-off; check the units (kg; kg/m for a beam's rho_A)",
                heavy.name(),
                Num(heavy.mass()),
                light.name(),
                Num(light.mass()),
            )
        })
    }

    /// [`Self::dynamics_error`] for a solve of the flexible tree at `q` (its rigid and
    /// elastic coordinates), with why where a flexible body is deflected beyond what its
    /// modal model holds ([`FlexModel::large_deflections`]): a stiff spring deploying a
    /// flexible panel can bend it by its own length, where the second-order terms of its
    /// inertia no longer hold and the solve fails (at the base, on the flexible deployment).
    pub(super) fn flexible_error(&self, e: DynamicsError, q: &[f64]) -> SystemError {
        let error = self.dynamics_error(e);
        let Some(f) = &self.flex else {
            return error;
        };
        let large = f.large_deflections(q);
        let Some(worst) = large.first() else {
            return error;
        };
        let name = |i: usize| f.rigid().bodies()[i].name().to_owned();
        let eta: Vec<String> = worst.eta.iter().map(|e| format!("{e:.4}")).collect();
        let others: Vec<String> = large[1..]
            .iter()
            .map(|d| format!("`{}`", name(d.body)))
            .collect();
        let others = match others.len() {
            0 => String::new(),
            _ => format!(" (also {})", others.join(", ")),
        };
        let size = match worst.point {
            None => format!(
                "body `{}`'s tip is {:.4} m off its axis, {:.0} % of its {} m length (modal coordinates [{}]){others}",
                name(worst.body),
                worst.tip.abs(),
                100.0 * worst.tip.abs() / worst.length,
                satsim_tree::error::Num(worst.length),
                eta.join(", ")
            ),
            Some(k) => format!(
                "body `{}`'s node `{}` has moved {:.4} m, {:.0} % of its {} m from the body's frame (modal coordinates [{}]){others}",
                name(worst.body),
                f.watch_points(worst.body)[k].name,
                worst.tip.abs(),
                100.0 * worst.tip.abs() / worst.length,
                satsim_tree::error::Num(worst.length),
                eta.join(", ")
            ),
        };
        SystemError::new(format!(
            "{error}: the flexible bodies are deflected beyond what their modal model holds: {size}. A modal model is meant for deflections of a few per cent of a body's length: stiffen the body, or soften what drives it (a spring, a controller, a load)"
        ))
    }
}

impl SimModel {
    /// The tree (the scene's model plus rotor bodies).
    pub fn tree(&self) -> &Model {
        &self.tree
    }
    /// The state layout.
    pub fn layout(&self) -> &StateLayout {
        &self.layout
    }
    /// The tree with its flexible bodies' modes, when it has any.
    pub fn flex(&self) -> Option<&FlexModel> {
        self.flex.as_ref()
    }
    /// The number of the scene's hinges (the tree's first hinges; the rotors follow).
    pub fn n_hinges(&self) -> usize {
        self.n_user
    }
    /// The forward dynamics every solve goes through.
    pub fn dynamics(&self) -> &ForwardDynamics {
        &self.fd
    }
    /// The number of event functions of all the effects.
    pub fn n_events(&self) -> usize {
        self.n_events
    }
}
