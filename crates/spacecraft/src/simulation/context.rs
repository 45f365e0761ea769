//! The effects' view of a pass: the read-only [`Context`] of a time and state, and the
//! mutable [`Hooks`] their `apply`, `events`, `on_event` and `start` write.

use super::{SimData, SimModel, Simulation};
use crate::effects::{Context, Effect, Forces, OrbitState, Request};
use nalgebra::{Quaternion, UnitQuaternion};
use satsim_tree::center_of_mass;
use satsim_tree::spatial::Vec3;
use std::ops::Range;

pub(super) fn orbit_of(
    effects: &[Box<dyn Effect>],
    own: &[Range<usize>],
    x: &[f64],
) -> Option<OrbitState> {
    effects
        .iter()
        .zip(own)
        .find_map(|(e, r)| e.orbit_state(&x[r.clone()]))
}

/// The parts of a simulation that the effects' hooks write, beside the read-only
/// [`Context`] (see [`Simulation::with_context`]).
pub(super) struct Hooks<'a> {
    pub(super) effects: &'a mut [Box<dyn Effect>],
    pub(super) own: &'a [Range<usize>],
    pub(super) forces: &'a mut Forces,
    pub(super) requests: &'a mut Vec<Request>,
    pub(super) calls: &'a mut [u64],
    pub(super) scratch: &'a mut [f64],
    pub(super) base_tau: &'a [f64],
    pub(super) event_start: &'a [usize],
    pub(super) net_force_to: Option<usize>,
}

impl Simulation {
    /// Splits the simulation, once for every hook, into the [`Context`] of time `t` and state
    /// `x` (`kin`: whether the poses are current; the centre of mass is computed from them
    /// when an effect reads it) and the mutable [`Hooks`], and runs `f`.
    pub(super) fn with_context<R>(
        &mut self,
        t: f64,
        x: &[f64],
        kin: bool,
        f: impl FnOnce(&Context, Hooks) -> R,
    ) -> R {
        self.with_context_power(t, x, kin, false, f)
    }

    /// [`Self::with_context`], with [`Context::power`] set to `power` (the right-hand side's
    /// effects pass with the energy budget on).
    pub(super) fn with_context_power<R>(
        &mut self,
        t: f64,
        x: &[f64],
        kin: bool,
        power: bool,
        f: impl FnOnce(&Context, Hooks) -> R,
    ) -> R {
        let Self {
            model,
            effects,
            data,
            log,
            ..
        } = self;
        let SimModel {
            tree: model,
            own,
            event_start,
            layout,
            n_user,
            needs_com,
            net_force_to,
            ..
        } = &*model;
        let SimData {
            tree: data,
            forces,
            requests,
            scratch,
            base_tau,
            q,
            v,
            locked,
            hold,
            flex,
            ..
        } = data;
        let calls = &mut log.calls;
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
            com: (kin && *needs_com).then(|| center_of_mass(model, data)),
            orbit: orbit_of(effects, own, x),
            attitude,
            omega,
            rotor_rates: &v[nb + *n_user..],
            eta: &x[layout.eta.clone()],
            etadot: &x[layout.etadot.clone()],
            deformed: flex.as_ref().filter(|_| kin).map(|w| w.data.inertias()),
            hold_torque: hold,
            power,
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
                net_force_to: *net_force_to,
            },
        )
    }
}
