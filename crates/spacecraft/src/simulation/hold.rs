//! Hold torques ([`Context::hold_torque`](crate::effects::Context::hold_torque)): the
//! torque a locked hinge must receive to stay locked, and the torque an unlocked one would
//! need to lock (read by an effect deciding whether a stuck wheel breaks free). One hybrid
//! solve with the hinges locked, then RNEA for the torques they receive.

use super::Simulation;
use super::solve::{flexible_dynamics, forward_dynamics};
use satsim_integrate::SystemError;
use satsim_tree::flexible;
use satsim_tree::{Input, rnea};

/// Which hold torques [`Simulation::prepare_with`] computes (only when an effect declares
/// [`Needs::hold_torques`](crate::effects::Needs::hold_torques)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Hold {
    /// None (output rows, energies: nothing there reads them).
    None,
    /// The locked hinges' (one hybrid solve).
    Locked,
    /// Every hinge's (one hybrid solve per unlocked hinge): at events and at the start.
    All,
}

impl Simulation {
    /// Fills the hold torques for the hinges `hold` asks for, after the effects were applied
    /// on this state (`kinematics`: the poses are current).
    pub(super) fn hold_torques_after_effects(
        &mut self,
        kinematics: bool,
        hold: Hold,
    ) -> Result<(), SystemError> {
        self.data.hold.fill(f64::NAN);
        if !self.model.needs_hold || hold == Hold::None {
            return Ok(());
        }
        let nb = self.model.tree.base_nv();
        self.data.tau[nb..].copy_from_slice(&self.data.forces.hinge_torque);
        // The transforms are current after kinematics, and after every solve (RNEA's).
        let mut xup_ready = kinematics || self.data.needs_kinematics;
        if self.data.n_locked > 0 {
            self.data.hold_mask.copy_from_slice(&self.data.locked);
            self.solve_hold(None, xup_ready)?;
            xup_ready = true;
        }
        if hold == Hold::All {
            for k in 0..self.data.locked.len() {
                if !self.data.locked[k] {
                    self.data.hold_mask.copy_from_slice(&self.data.locked);
                    self.data.hold_mask[k] = true;
                    self.solve_hold(Some(k), xup_ready)?;
                    xup_ready = true;
                }
            }
        }
        Ok(())
    }

    /// Hybrid dynamics with `hold_mask` locked, then RNEA for the torques the locked hinges
    /// must receive: all of them (`only` = None) or hinge `only`. `xup_ready`: `data.xup`
    /// holds the transforms of this state (kinematics or an earlier solve ran on it).
    pub(super) fn solve_hold(
        &mut self,
        only: Option<usize>,
        xup_ready: bool,
    ) -> Result<(), SystemError> {
        let nb = self.model.tree.base_nv();
        let err = |e: satsim_tree::DynamicsError| self.model.dynamics_error(e);
        let d = &mut self.data;
        let fext = d
            .forces
            .has_wrench
            .then_some(d.forces.body_wrench.as_slice());
        // The same solve as the right-hand side's, with `hold_mask` locked.
        let need = match (&self.model.flex, &mut d.flex) {
            (Some(f), Some(w)) => {
                // The accelerations go to `a`, which RNEA then reads beside `w`'s buffers.
                let mut a = std::mem::take(&mut w.a);
                let hold = Some(d.hold_mask.as_slice());
                let (elastic, tau) = (&d.forces.elastic, &d.tau);
                let solved = flexible_dynamics(f, w, tau, elastic, fext, hold, xup_ready)
                    .map(|ddq| a.copy_from_slice(ddq));
                // The solve left this state's first pass in `w.data`.
                let need = solved.and_then(|()| {
                    flexible::rnea_with_kinematics(f, &mut w.data, &w.q, &w.v, &a, fext).map(|_| ())
                });
                w.a = a;
                if let Err(e) = need {
                    return Err(self.model.flexible_error(e, &w.q));
                }
                w.data.tau.as_slice()
            }
            _ => {
                let solve = Input::new(&d.q, &d.v, &d.tau)
                    .fext(fext)
                    .locked(Some(&d.hold_mask))
                    .xup_current(xup_ready);
                forward_dynamics(&self.model, &mut d.tree, solve, &mut d.hold_ddq).map_err(err)?;
                rnea(&self.model.tree, &mut d.tree, &d.q, &d.v, &d.hold_ddq, fext)
                    .map_err(err)?
                    .as_slice()
            }
        };
        match only {
            Some(k) => d.hold[k] = need[nb + k],
            None => {
                for (k, h) in d.hold.iter_mut().enumerate() {
                    if d.hold_mask[k] {
                        *h = need[nb + k];
                    }
                }
            }
        }
        // ABA and RNEA leave the poses of the last forward kinematics as they were.
        Ok(())
    }
}
