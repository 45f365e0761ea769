//! [`SimData`]: the scratch of every evaluation, and the discrete state.

use super::ahead::Ahead;
use crate::effects::{Forces, Request};
use satsim_tree::flexible::{FlexData, FlexModel};
use satsim_tree::{Data, Model};

/// The flexible algorithms' workspace and their full coordinates: `q = [the rigid tree's q,
/// η]`, `v = [its v, η̇]`, `tau` likewise (no generalised force on the modes from the
/// effects: their wrenches act on the bodies' frames).
pub(super) struct FlexWork {
    pub(super) data: FlexData,
    pub(super) q: Vec<f64>,
    pub(super) v: Vec<f64>,
    pub(super) tau: Vec<f64>,
    /// Accelerations by RNEA's caller (the locked hinges' power, hold torques).
    pub(super) a: Vec<f64>,
}

impl FlexWork {
    pub(super) fn new(model: &FlexModel) -> Self {
        let nv = model.nv();
        Self {
            data: FlexData::new(model),
            q: model.neutral(),
            v: vec![0.0; nv],
            tau: vec![0.0; nv],
            a: vec![0.0; nv],
        }
    }
}

/// The written part of a [`Simulation`](super::Simulation), allocated once by the builder:
/// the buffers every pass of the right-hand-side pipeline writes, and the discrete state that
/// the continuous state `x` does not hold (which hinges are locked, the constant torques).
/// A buffer's contents mean something only right after the pass that wrote it.
pub struct SimData {
    /// The tree's workspace (poses after kinematics, ABA's and RNEA's buffers).
    pub(super) tree: Data,
    /// With flexible bodies, their workspace and coordinates.
    pub(super) flex: Option<FlexWork>,
    /// `x` unpacked into the tree's coordinates and velocities, and its generalized forces.
    pub(super) q: Vec<f64>,
    pub(super) v: Vec<f64>,
    pub(super) tau: Vec<f64>,
    /// What the effects applied in the last pass.
    pub(super) forces: Forces,
    /// The effects' own derivatives where a pass does not write `dx` (rows, events).
    pub(super) scratch: Vec<f64>,
    /// The effects' requests at an event.
    pub(super) requests: Vec<Request>,
    /// Buffers of an event's impulse solve (`events.rs`), reserved here so that handling an
    /// event allocates nothing.
    pub(super) impulse: ImpulseWork,
    /// Hold torques (see [`Context::hold_torque`](crate::effects::Context::hold_torque))
    /// and their work buffers.
    pub(super) hold: Vec<f64>,
    pub(super) hold_mask: Vec<bool>,
    pub(super) hold_ddq: Vec<f64>,
    /// `q̈` where the dynamics cannot write it straight into the derivative.
    pub(super) ddq: Vec<f64>,
    /// Whether every pass runs kinematics: an effect asked for it, or wrote a wrench whose
    /// power the energy budget needs (found at the first such pass).
    pub(super) needs_kinematics: bool,
    /// Whether that kinematics computes the bodies' velocities in the right-hand side (every
    /// other pass that asks for kinematics gets them): an effect reads them, or the energy
    /// budget measures the power of a wrench (found at the first such pass); otherwise only
    /// the poses ([`Needs::poses`](crate::effects::Needs::poses)).
    pub(super) needs_velocities: bool,
    /// How many of the tree's first bodies that poses-only kinematics places: all of them, or
    /// all but the rotors the effects add (the tree's last bodies) where no effect reads a
    /// rotor's pose there ([`Effect::reads_rotor_poses`](crate::effects::Effect::reads_rotor_poses)).
    /// A rotor's hinge angle is no state and stays 0, so its transform in `tree.xup`, set
    /// when the simulation is built, stays current (every solve that recomputes it gets the
    /// same).
    pub(super) pose_bodies: usize,
    /// Which hinges (the scene's, then the rotors) are locked now, and how many.
    pub(super) locked: Vec<bool>,
    pub(super) n_locked: usize,
    /// A hinge was locked since the integrator last asked
    /// ([`satsim_integrate::System::jacobian_survives_restart`]).
    pub(super) newly_locked: bool,
    /// The constant hinge torques every pass starts from (N m, tree hinge order: the
    /// initial state's `torque`, zero on the rotors).
    pub(super) base_tau: Vec<f64>,
    /// The right-hand side the event functions evaluated at the end of a step, for the next
    /// step's first stage (`ahead.rs`).
    pub(super) ahead: Ahead,
    /// Each watched flexible body's largest deflection over the accepted steps so far.
    pub(super) deflection_peaks: Vec<DeflectionPeak>,
    /// The energy budget over the output rows so far.
    pub(super) budget: BudgetWatch,
    /// The mass matrices' workspace of the Jacobian's updates (`jacobian.rs`), made at the
    /// first.
    pub(super) jac_update: Option<Box<super::jacobian::JacobianUpdate>>,
}

/// The smallest and largest energy budget `T + V − W + D` of the output rows so far, and
/// the largest of its four terms any row showed (J): what
/// [`Simulation::budget_warning`](super::Simulation::budget_warning) weighs.
#[derive(Clone, Copy, Debug)]
pub(super) struct BudgetWatch {
    pub(super) min: f64,
    pub(super) max: f64,
    pub(super) scale: f64,
}

impl Default for BudgetWatch {
    fn default() -> Self {
        Self {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            scale: 0.0,
        }
    }
}

impl BudgetWatch {
    /// A row's budget and its terms.
    pub(super) fn see(&mut self, budget: f64, terms: [f64; 4]) {
        self.min = self.min.min(budget);
        self.max = self.max.max(budget);
        for x in terms {
            self.scale = self.scale.max(x.abs());
        }
    }
}

/// A flexible body's largest deflection over a run's accepted steps
/// ([`Simulation::deflection_peaks`](super::Simulation::deflection_peaks)): a beam's tip,
/// or for given modes the watched point bent most for its distance from the body's frame
/// ([`FlexModel::deflection_of`](satsim_tree::flexible::FlexModel::deflection_of)).
#[derive(Clone, Debug, PartialEq)]
pub struct DeflectionPeak {
    /// The body (of the scene's model).
    pub body: usize,
    /// The tip's deflection along the beam's `bend`, or the size of the watched point's
    /// displacement, there (m).
    pub tip: f64,
    /// The beam's length, or the watched point's distance from the body's frame (m).
    pub length: f64,
    /// The watched point ([`FlexModel::watch_points`](satsim_tree::flexible::FlexModel::watch_points));
    /// `None` for a beam's tip.
    pub point: Option<usize>,
    /// When (s).
    pub t: f64,
    /// The first accepted step's end at which the deflection passed
    /// [`SMALL_DEFLECTION`](satsim_tree::flexible::SMALL_DEFLECTION) of the length (s);
    /// `None` while it has not.
    pub passed: Option<f64>,
}

impl DeflectionPeak {
    /// The largest deflection as a fraction of the length (dimensionless): past
    /// [`SMALL_DEFLECTION`](satsim_tree::flexible::SMALL_DEFLECTION), beyond the modal model.
    pub fn fraction(&self) -> f64 {
        self.tip.abs() / self.length
    }
}

/// The buffers of [`Simulation::apply_requests`](super::Simulation) and its impulse solve:
/// the matrices are lent to nalgebra as `DMatrix`es of the size at hand and taken back,
/// their storage kept.
#[derive(Clone, Debug, Default)]
pub(super) struct ImpulseWork {
    /// `(hinge, rate)` to set, and the hinges to lock.
    pub(super) targets: Vec<(usize, f64)>,
    pub(super) locks: Vec<usize>,
    /// The free degrees of freedom, and the targets' positions among them.
    pub(super) free: Vec<usize>,
    pub(super) pos: Vec<usize>,
    /// Storage of `M_ff`, `M_ff⁻¹ E`, `Eᵀ M_ff⁻¹ E`, the rate jumps wanted, `Δv`.
    pub(super) m: Vec<f64>,
    pub(super) col: Vec<f64>,
    pub(super) a: Vec<f64>,
    pub(super) b: Vec<f64>,
    pub(super) dv: Vec<f64>,
    /// The states of the effect whose event is handled.
    pub(super) own: Vec<f64>,
}

impl ImpulseWork {
    /// For at most `dofs` degrees of freedom, `hinges` hinges (each a target at most) and
    /// `n_states` states.
    fn new(dofs: usize, hinges: usize, n_states: usize) -> Self {
        Self {
            targets: Vec::with_capacity(hinges),
            locks: Vec::with_capacity(hinges),
            free: Vec::with_capacity(dofs),
            pos: Vec::with_capacity(hinges),
            m: Vec::with_capacity(dofs * dofs),
            col: Vec::with_capacity(dofs * hinges),
            a: Vec::with_capacity(hinges * hinges),
            b: Vec::with_capacity(hinges),
            dv: Vec::with_capacity(dofs),
            own: Vec::with_capacity(n_states),
        }
    }
}

impl SimData {
    /// Buffers for `tree` with `n_states` states and `n_rotors` rotors.
    pub(super) fn new(tree: &Model, n_rotors: usize, n_states: usize) -> Self {
        let (nh, nv) = (tree.n_hinges(), tree.nv());
        Self {
            tree: Data::new(tree),
            flex: None,
            q: tree.neutral(),
            v: vec![0.0; nv],
            tau: vec![0.0; nv],
            forces: Forces::new(nh, tree.n_bodies(), n_rotors),
            scratch: vec![0.0; n_states],
            requests: Vec::with_capacity(4 * nh + 4),
            // A flexible tree's elastic coordinates take two states each: at most half.
            impulse: ImpulseWork::new(nv + n_states / 2, nh, n_states),
            hold: vec![f64::NAN; nh],
            hold_mask: vec![false; nh],
            hold_ddq: vec![0.0; nv],
            ddq: vec![0.0; nv],
            needs_kinematics: false,
            needs_velocities: true,
            pose_bodies: tree.n_bodies(),
            locked: vec![false; nh],
            n_locked: 0,
            newly_locked: true,
            base_tau: vec![0.0; nh],
            ahead: Ahead::new(n_states),
            deflection_peaks: Vec::new(),
            budget: BudgetWatch::default(),
            jac_update: None,
        }
    }
    /// The loads the effects applied in the last pass.
    pub fn forces(&self) -> &Forces {
        &self.forces
    }
    /// The tree's workspace after the last pass (the poses of its kinematics, when it ran).
    pub fn tree(&self) -> &Data {
        &self.tree
    }
    /// Which hinges (the scene's, then the rotors) are locked now.
    pub fn locked(&self) -> &[bool] {
        &self.locked
    }
}
