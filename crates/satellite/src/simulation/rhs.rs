//! The right-hand side's parts: unpacking the state, kinematics, the effects' hooks (with
//! the [`Context`] they read) and the hold torques.

use super::{SimError, Simulation};
use crate::effects::{Context, Effect, EventReads, Forces, OrbitState, Request};
use nalgebra::{Quaternion, UnitQuaternion};
use satsim_integrate::SystemError;
use satsim_tree::spatial::Vec3;
use satsim_tree::{
    Locks, UnrolledAba, aba_hybrid, aba_hybrid_with_kinematics, center_of_mass, forward_kinematics,
    rnea,
};
use std::ops::Range;

impl Simulation {
    /// `x` into the tree's `q` and `v`.
    pub(super) fn unpack(&mut self, x: &[f64]) {
        let l = &self.layout;
        let n = self.n_user;
        if l.free {
            // x = [attitude, angles, ω, v, rates, ...] (`StateLayout`); a fixed-size copy
            // where the length is known (no `memcpy` call).
            self.q[..4].copy_from_slice(&x[..4]);
            self.q[7..7 + n].copy_from_slice(&x[4..4 + n]);
        } else {
            self.q[..n].copy_from_slice(&x[l.angles.clone()]);
        }
        if let Some(s) = self.velocity_at {
            // The whole velocity vector is one run of the state: one copy.
            let nv = self.v.len();
            self.v.copy_from_slice(&x[s..s + nv]);
            return;
        }
        let nb = self.model.base_nv();
        if l.free {
            self.v[..6 + n].copy_from_slice(&x[l.omega.start..l.omega.start + 6 + n]);
        } else {
            self.v[..n].copy_from_slice(&x[l.rates.clone()]);
        }
        if let Some(i) = self.rotor_effect {
            self.v[nb + n..nb + n + self.n_rotors].copy_from_slice(&x[self.own[i].clone()]);
        }
    }

    /// Unpacks, runs kinematics and every effect's `apply` (own derivatives into `scratch`).
    pub(super) fn prepare(
        &mut self,
        t: f64,
        x: &[f64],
        kinematics: bool,
    ) -> Result<(), SystemError> {
        self.prepare_with(t, x, kinematics, Hold::None)
    }

    /// As [`Self::prepare`], then fills the hold torques for the hinges `hold` asks for.
    pub(super) fn prepare_with(
        &mut self,
        t: f64,
        x: &[f64],
        kinematics: bool,
        hold: Hold,
    ) -> Result<(), SystemError> {
        self.apply_effects(t, x, kinematics)?;
        self.hold.fill(f64::NAN);
        if !self.needs_hold || hold == Hold::None {
            return Ok(());
        }
        let nb = self.model.base_nv();
        self.tau[nb..].copy_from_slice(&self.forces.hinge_torque);
        // The transforms are current after kinematics, and after every solve (RNEA's).
        let mut xup_ready = kinematics || self.needs_kinematics;
        if self.n_locked > 0 {
            self.hold_mask.copy_from_slice(&self.locked);
            self.solve_hold(None, xup_ready)?;
            xup_ready = true;
        }
        if hold == Hold::All {
            for k in 0..self.locked.len() {
                if !self.locked[k] {
                    self.hold_mask.copy_from_slice(&self.locked);
                    self.hold_mask[k] = true;
                    self.solve_hold(Some(k), xup_ready)?;
                    xup_ready = true;
                }
            }
        }
        Ok(())
    }

    /// Before the event functions: what they read, and no more (the union of the
    /// effects' [`Effect::event_reads`]). Returns whether they read the poses (which are
    /// then current).
    pub(super) fn prepare_events(&mut self, t: f64, x: &[f64]) -> Result<bool, SystemError> {
        let reads = self
            .effects
            .iter()
            .filter(|e| e.n_events() > 0)
            .fold(EventReads::STATE, |r, e| r.union(e.event_reads()));
        let hold = reads.hold_torques && self.needs_hold && self.n_locked > 0;
        let wrap = |e: SystemError| SystemError::new(format!("event functions: {e}"));
        if reads.forces || hold {
            let h = if hold { Hold::Locked } else { Hold::None };
            self.prepare_with(t, x, reads.kinematics, h).map_err(wrap)?;
            return Ok(reads.kinematics);
        }
        self.unpack(x);
        self.hold.fill(f64::NAN);
        if reads.kinematics {
            forward_kinematics(&self.model, &mut self.data, &self.q, &self.v)
                .map_err(|e| wrap(SystemError::new(e.to_string())))?;
        }
        Ok(reads.kinematics)
    }

    /// Hybrid dynamics with `hold_mask` locked, then RNEA for the torques the locked hinges
    /// must receive: all of them (`only` = None) or hinge `only`. `xup_ready`: `data.xup`
    /// holds the transforms of this state (kinematics or an earlier solve ran on it).
    pub(super) fn solve_hold(
        &mut self,
        only: Option<usize>,
        xup_ready: bool,
    ) -> Result<(), SystemError> {
        let nb = self.model.base_nv();
        let fext = if self.forces.has_wrench {
            Some(self.forces.body_wrench.as_slice())
        } else {
            None
        };
        let err = |e: satsim_tree::DynamicsError| SystemError::new(e.to_string());
        // The unrolled kernel where it takes this lock mask (as in `rhs`), else the generic
        // hybrid ABA.
        match kernel_for(&self.unrolled, Some(&self.hold_mask)) {
            Some((k, locks)) => {
                let (q, v, tau) = (&self.q, &self.v, &self.tau);
                k.aba_hybrid_with_forces_into(q, v, tau, fext, locks, &mut self.hold_ddq)
                    .map_err(err)?;
            }
            None => {
                let hybrid = if xup_ready {
                    aba_hybrid_with_kinematics
                } else {
                    aba_hybrid
                };
                let ddq = hybrid(
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
            }
        }
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
    pub(super) fn apply_effects(
        &mut self,
        t: f64,
        x: &[f64],
        kinematics: bool,
    ) -> Result<(), SystemError> {
        self.unpack(x);
        let kin = kinematics || self.needs_kinematics;
        if kin {
            forward_kinematics(&self.model, &mut self.data, &self.q, &self.v)
                .map_err(|e| SystemError::new(e.to_string()))?;
        }
        self.with_context(t, x, kin, |ctx, h| {
            h.forces.reset_to(h.base_tau);
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
}

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

#[allow(clippy::too_many_arguments)]
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
            needs_com,
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
            com: (kin && *needs_com).then(|| center_of_mass(model, data)),
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

/// The unrolled kernel and its form of the lock mask `locked` (`None`: nothing locked, no
/// mask to read), where the model has the kernel's layout and the kernel takes the mask
/// (not with a gimbal hinge locked); `None` sends the caller to the generic ABA.
pub(super) fn kernel_for<'a>(
    unrolled: &'a Option<UnrolledAba>,
    locked: Option<&[bool]>,
) -> Option<(&'a UnrolledAba, Locks)> {
    let kernel = unrolled.as_ref()?;
    match locked {
        None => Some((kernel, Locks::NONE)),
        Some(mask) => Some((kernel, kernel.locks(mask)?)),
    }
}
