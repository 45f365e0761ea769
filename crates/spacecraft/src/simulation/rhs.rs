//! The right-hand side, `dx = f(t, x)`, as one pipeline read top to bottom:
//!
//! 1. **unpack** `x` into the tree's `q` and `v`;
//! 2. **kinematics**: the poses and velocities of every body, when an effect reads them (the
//!    poses alone where no effect reads the velocities, `Needs::poses`);
//! 3. **effects**: each enabled effect adds hinge torques and body wrenches and writes its
//!    own states' derivatives (and, for the energy budget, the power of what it added);
//! 4. **dynamics**: forward dynamics (ABA, hybrid when hinges are locked; the layout's
//!    unrolled kernel where it takes the lock mask; the flexible ABA with elastic
//!    coordinates) for `q̈` (and `η̈`);
//! 5. **pack** `q̇ = ½ q ⊗ (0, ω)`, the hinge rates, `η̇` and the accelerations into `dx`.
//!
//! Every other pass runs the first three stages through [`Simulation::prepare_with`]: an
//! output row, the event functions (only what they read, `events.rs`), the hold torques
//! (`hold.rs`, which take the dynamics stage's solves, `solve.rs`, with other locks) and the linearisation (which
//! calls the right-hand side itself).

use super::Simulation;
use super::hold::Hold;
use super::model::SimModel;
use super::solve::{flexible_dynamics, flexible_forces, forward_dynamics};
use crate::effects::{Context, Forces, Power};
use satsim_integrate::SystemError;
use satsim_tree::flexible;
use satsim_tree::spatial::{Force, Vec3};
use satsim_tree::{DynamicsError, Input, forward_kinematics, forward_poses_of, momentum, rnea};

impl Simulation {
    /// `dx = f(t, x)`; slices of the wrong length are an error, not a panic. The three
    /// pieces are also called apart, by the lanes of a batch of runs (`lanes.rs`), which
    /// solve the dynamics of several runs at once between [`Self::rhs_forces`] and
    /// [`Self::rhs_power`].
    pub(super) fn right_hand_side(
        &mut self,
        t: f64,
        x: &[f64],
        dx: &mut [f64],
    ) -> Result<(), SystemError> {
        if self.reuse_ahead(t, x, dx) {
            return Ok(());
        }
        let kin = self.rhs_forces(t, x, dx)?;
        self.dynamics(kin, dx)?;
        self.rhs_power(x, dx)
    }

    /// Stages 1-3 and the positions' part of stage 5: unpack, kinematics, the effects (their
    /// own derivatives straight into `dx`, and the power they add), `q̇`, and the generalised
    /// forces of the dynamics into `data.tau`. Returns whether the poses are current.
    pub(super) fn rhs_forces(
        &mut self,
        t: f64,
        x: &[f64],
        dx: &mut [f64],
    ) -> Result<bool, SystemError> {
        self.check_len(x.len(), "rhs")?;
        self.check_len(dx.len(), "rhs (derivative)")?;
        self.log.rhs_evals += 1;
        let track = !self.model.work.is_empty();
        let (kin, power) = loop {
            // 1-2.
            self.unpack(x);
            let kin = self.kinematics(false)?;
            // 3. The effects write their own derivatives straight into `dx`.
            let velocities = kin && self.data.needs_velocities;
            let (power, unmeasured) =
                self.apply_effects(t, x, kin, velocities, Some(&mut *dx), true)?;
            if track && (unmeasured || (!kin && self.data.forces.has_wrench)) {
                // A wrench's power needs the bodies' velocities: an effect wrote one without
                // asking for kinematics (or for the poses only) and reads its power, so they
                // are computed from now on (this evaluation again).
                self.data.needs_kinematics = true;
                self.data.needs_velocities = true;
                continue;
            }
            break (kin, power);
        };
        if track {
            dx[self.model.work.start] = power.actuator;
            dx[self.model.work.start + 1] = power.dissipated;
        }
        self.pack_positions(x, dx);
        let (nb, d) = (self.model.tree.base_nv(), &mut self.data);
        d.tau[nb..].copy_from_slice(&d.forces.hinge_torque);
        Ok(kin)
    }

    /// After the dynamics: the energy budget's power of the locked hinges and of the modal
    /// damping.
    pub(super) fn rhs_power(&mut self, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
        if self.model.work.is_empty() {
            return Ok(());
        }
        dx[self.model.work.start] += self.locked_hinges_power(dx)?;
        if let Some(f) = &self.model.flex {
            // Modal damping dissipates `Σ 2 ζ ωₖ η̇ₖ²`.
            let etadot = &x[self.model.layout.etadot.clone()];
            dx[self.model.work.start + 1] += f
                .damping()
                .iter()
                .zip(etadot)
                .map(|(c, e)| c * e * e)
                .sum::<f64>();
        }
        Ok(())
    }

    /// The power of the torques that keep the locked hinges locked, `Σ (H_k − τ_k) q̇_k`:
    /// zero unless a hinge is locked while it turns (a wheel held at its speed limit), whose
    /// constraint does work on the tree that no effect applied. An actuator's for the
    /// energy budget (the effect holding it books its friction's share). One RNEA with the
    /// accelerations just solved, only then.
    fn locked_hinges_power(&mut self, dx: &[f64]) -> Result<f64, SystemError> {
        let (m, d) = (&self.model, &mut self.data);
        let nb = m.tree.base_nv();
        if d.n_locked == 0
            || !d
                .locked
                .iter()
                .enumerate()
                .any(|(k, &l)| l && d.v[nb + k] != 0.0)
        {
            return Ok(0.0);
        }
        match m.velocity_at {
            Some(s) => {
                let nv = d.v.len();
                d.hold_ddq.copy_from_slice(&dx[s..s + nv]);
            }
            None => d.hold_ddq.copy_from_slice(&d.ddq),
        }
        let fext = d
            .forces
            .has_wrench
            .then_some(d.forces.body_wrench.as_slice());
        let need = match (&m.flex, &mut d.flex) {
            // After the dynamics on this state: its first pass is current.
            (Some(f), Some(w)) => {
                flexible_forces(f, w, &d.hold_ddq, &dx[m.layout.etadot.clone()], fext)
                    .map_err(SystemError::from_error)?
            }
            _ => rnea(&m.tree, &mut d.tree, &d.q, &d.v, &d.hold_ddq, fext)
                .map_err(SystemError::from_error)?
                .as_slice(),
        };
        let mut power = 0.0;
        for (k, &locked) in d.locked.iter().enumerate() {
            if locked {
                power += (need[nb + k] - d.tau[nb + k]) * d.v[nb + k];
            }
        }
        Ok(power)
    }

    /// Stages 1-3 for every pass but the right-hand side (rows, events, hold torques, the
    /// start): unpack, kinematics (`kinematics`: whether this pass needs the poses, beside the
    /// effects' own needs), every effect's `apply` (own derivatives into a scratch buffer),
    /// then the hold torques `hold` asks for.
    pub(super) fn prepare_with(
        &mut self,
        t: f64,
        x: &[f64],
        kinematics: bool,
        hold: Hold,
    ) -> Result<(), SystemError> {
        self.unpack(x);
        let kin = self.kinematics(kinematics)?;
        self.apply_effects(t, x, kin, kin, None, false)?;
        self.hold_torques_after_effects(kinematics, hold)
    }

    /// [`Self::prepare_with`] without hold torques.
    pub(super) fn prepare(
        &mut self,
        t: f64,
        x: &[f64],
        kinematics: bool,
    ) -> Result<(), SystemError> {
        self.prepare_with(t, x, kinematics, Hold::None)
    }

    /// Stage 1: `x` into the tree's `q` and `v`.
    pub(super) fn unpack(&mut self, x: &[f64]) {
        let (m, d) = (&self.model, &mut self.data);
        let l = &m.layout;
        let n = m.n_user;
        unpack_positions(m, x, &mut d.q);
        if let Some(s) = m.velocity_at {
            // The whole velocity vector is one run of the state: one copy.
            let nv = d.v.len();
            d.v.copy_from_slice(&x[s..s + nv]);
            return;
        }
        let nb = m.tree.base_nv();
        if l.free {
            d.v[..6 + n].copy_from_slice(&x[l.omega.start..l.omega.start + 6 + n]);
        } else {
            d.v[..n].copy_from_slice(&x[l.rates.clone()]);
        }
        if let Some(i) = m.rotor_effect {
            d.v[nb + n..nb + n + m.n_rotors].copy_from_slice(&x[m.own[i].clone()]);
        }
        // A flexible tree's velocity vector is never one run of the state, so the early
        // return above is not taken.
        if d.flex.is_some() {
            self.unpack_elastic(x);
        }
    }

    /// A flexible tree's coordinates: the rigid ones, then `η` and `η̇`. Apart, so that the
    /// rigid path's `unpack` stays as small as it was (inlined, instruction for instruction).
    #[inline(never)]
    fn unpack_elastic(&mut self, x: &[f64]) {
        let (l, d) = (&self.model.layout, &mut self.data);
        if let Some(w) = &mut d.flex {
            let (nq, nv) = (d.q.len(), d.v.len());
            w.q[..nq].copy_from_slice(&d.q);
            w.q[nq..].copy_from_slice(&x[l.eta.clone()]);
            w.v[..nv].copy_from_slice(&d.v);
            w.v[nv..].copy_from_slice(&x[l.etadot.clone()]);
        }
    }

    /// Stage 2: forward kinematics when this pass asks for it or an effect needs it; returns
    /// whether the poses are now current. The velocities too, unless the right-hand side's
    /// effects read only the poses (`data.needs_velocities`; a pass that asks gets them).
    #[inline]
    pub(super) fn kinematics(&mut self, asked: bool) -> Result<bool, SystemError> {
        let kin = asked || self.data.needs_kinematics;
        if kin {
            if self.model.flex.is_some() {
                self.flexible_kinematics()?;
            } else {
                let d = &mut self.data;
                if asked || d.needs_velocities {
                    forward_kinematics(&self.model.tree, &mut d.tree, &d.q, &d.v)
                } else {
                    forward_poses_of(&self.model.tree, &mut d.tree, &d.q, d.pose_bodies)
                }
                .map_err(SystemError::from_error)?;
            }
        }
        Ok(kin)
    }

    /// The poses of a flexible tree (its hinges carried by the deformation). Apart, so that
    /// the rigid path's `kinematics` stays inlined.
    #[inline(never)]
    fn flexible_kinematics(&mut self) -> Result<(), SystemError> {
        let d = &mut self.data;
        if let (Some(f), Some(w)) = (&self.model.flex, &mut d.flex) {
            flexible::forward_kinematics(f, &mut w.data, &mut d.tree, &w.q, &w.v)
                .map_err(SystemError::from_error)?;
        }
        Ok(())
    }

    /// Linear momentum and angular momentum about the centre of mass (inertial axes) after
    /// [`Self::kinematics`] on the unpacked state.
    pub(super) fn momentum(&self) -> (Vec3, Vec3) {
        match (&self.model.flex, &self.data.flex) {
            (Some(f), Some(w)) => flexible::momentum(f, &self.data.tree, &w.q, &w.v),
            _ => momentum(&self.model.tree, &self.data.tree),
        }
    }

    /// Stage 3: every effect's `apply`, in order, from the constant torques: own derivatives into
    /// `own_dot` (the right-hand side's `dx`) or, when `None`, into the scratch buffer.
    /// `rhs`: the right-hand side's pass, which counts the calls and, with the energy budget,
    /// measures each effect's power (`Σ Δτ_k q̇_k + Σ Δf_i · v_i` over what it added) and
    /// lets the effect split it. `velocities`: the bodies' velocities are current; without
    /// them a wrench's power is not measured, and the second value says whether an effect
    /// that reads it ([`Effect::power_reads_applied`]) added one.
    ///
    /// [`Effect::power_reads_applied`]: crate::effects::Effect::power_reads_applied
    pub(super) fn apply_effects(
        &mut self,
        t: f64,
        x: &[f64],
        kin: bool,
        velocities: bool,
        own_dot: Option<&mut [f64]>,
        rhs: bool,
    ) -> Result<(Power, bool), SystemError> {
        let track = rhs && !self.model.work.is_empty();
        let nb = self.model.tree.base_nv();
        self.with_context_power(t, x, kin, track, |ctx, h| {
            let own_dot = match own_dot {
                Some(dx) => dx,
                None => h.scratch,
            };
            h.forces.reset_to(h.base_tau);
            // Energy budget: the constant torques are an actuator's; each effect's forces
            // are measured by the change of the total power it makes.
            let mut hinges = if track {
                h.forces.hinge_power(ctx.v, nb) + h.forces.elastic_power(ctx.etadot)
            } else {
                0.0
            };
            let (mut wrenches, mut added, mut unmeasured) = (0.0, 0, false);
            let mut power = Power::actuator(hinges);
            for ((e, r), c) in h.effects.iter_mut().zip(h.own).zip(h.calls.iter_mut()) {
                if rhs {
                    *c += 1;
                }
                e.apply(ctx, h.forces, &x[r.clone()], &mut own_dot[r.clone()])?;
                if track {
                    let now = h.forces.hinge_power(ctx.v, nb) + h.forces.elastic_power(ctx.etadot);
                    let mut applied = now - hinges;
                    hinges = now;
                    if h.forces.wrenches_added() != added {
                        added = h.forces.wrenches_added();
                        if velocities {
                            let now = h.forces.wrench_power(&ctx.data.v);
                            applied += now - wrenches;
                            wrenches = now;
                        } else {
                            unmeasured |= e.power_reads_applied();
                        }
                    }
                    let p = e.power(ctx, &x[r.clone()], applied);
                    power.actuator += p.actuator;
                    power.dissipated += p.dissipated;
                }
            }
            if let Some(o) = h.net_force_to
                && h.forces.has_wrench
            {
                carry_net_force(
                    ctx,
                    h.forces,
                    &mut own_dot[h.own[o].start + 3..h.own[o].end],
                );
            }
            Ok((power, unmeasured))
        })
    }

    /// Stage 5, the positions' part: `q̇ = ½ q ⊗ (0, ω)` and the hinge angles' rates.
    fn pack_positions(&self, x: &[f64], dx: &mut [f64]) {
        let l = &self.model.layout;
        if l.free {
            // x = [attitude, angles, ω, v, rates, ...] (`StateLayout`).
            let (a, w) = (&x[..4], &x[l.omega.start..l.omega.start + 3]);
            let qd = crate::effects::quat_mul(&[a[0], a[1], a[2], a[3]], &[0.0, w[0], w[1], w[2]]);
            for (d, q) in dx[..4].iter_mut().zip(qd) {
                *d = 0.5 * q;
            }
        }
        dx[l.angles.clone()].copy_from_slice(&x[l.rates.clone()]);
        if !l.eta.is_empty() {
            dx[l.eta.clone()].copy_from_slice(&x[l.etadot.clone()]);
        }
    }

    /// Stages 4 and 5, the velocities' part: from the effects' hinge torques (in `data.tau`) and wrenches, `q̈` by forward
    /// dynamics with the hinges locked now, packed into `dx` (written straight into it where
    /// the tree's velocity vector is one run of the state). `kin`: the poses are current,
    /// so the generic ABA reuses their transforms (bit for bit the same result).
    pub(super) fn dynamics(&mut self, kin: bool, dx: &mut [f64]) -> Result<(), SystemError> {
        let (m, d) = (&self.model, &mut self.data);
        let fext = d.forces.has_wrench;
        let solve = Input::new(&d.q, &d.v, &d.tau)
            .fext(fext.then_some(d.forces.body_wrench.as_slice()))
            .locked((d.n_locked > 0).then_some(d.locked.as_slice()))
            .xup_current(kin);
        let err = |e: DynamicsError| m.dynamics_error(e);
        if let Some(s) = m.velocity_at {
            let nv = d.v.len();
            return forward_dynamics(m, &mut d.tree, solve, &mut dx[s..s + nv]).map_err(err);
        }
        match (&m.flex, &mut d.flex) {
            (Some(f), Some(w)) => {
                let locked = (d.n_locked > 0).then_some(d.locked.as_slice());
                let fext = fext.then_some(d.forces.body_wrench.as_slice());
                let ddq =
                    match flexible_dynamics(f, w, &d.tau, &d.forces.elastic, fext, locked, kin) {
                        Ok(ddq) => ddq,
                        Err(e) => return Err(m.flexible_error(e, &w.q)),
                    };
                let nv = d.ddq.len();
                d.ddq.copy_from_slice(&ddq[..nv]);
                dx[m.layout.etadot.clone()].copy_from_slice(&ddq[nv..]);
            }
            _ => forward_dynamics(m, &mut d.tree, solve, &mut d.ddq).map_err(err)?,
        }
        self.pack_accelerations(dx);
        Ok(())
    }

    /// Stage 5, the accelerations in `data.ddq` into `dx` (where the tree's velocity vector
    /// is not one run of the state).
    pub(super) fn pack_accelerations(&self, dx: &mut [f64]) {
        let (m, d) = (&self.model, &self.data);
        let nb = m.tree.base_nv();
        let (l, n, ddq) = (&m.layout, m.n_user, &d.ddq);
        if l.free {
            dx[l.omega.start..l.omega.start + 6 + n].copy_from_slice(&ddq[..6 + n]);
        } else {
            dx[l.rates.clone()].copy_from_slice(&ddq[..n]);
        }
        if let Some(i) = m.rotor_effect {
            let r = m.own[i].clone();
            dx[r].copy_from_slice(&ddq[nb + n..nb + n + m.n_rotors]);
        }
    }
}

/// The attitude and the hinge angles of `x` into the rigid tree's coordinates `q` (the rest
/// of `q`, the base's position and the rotors' angles, is no state and is left as it is).
#[inline(always)]
pub(super) fn unpack_positions(m: &SimModel, x: &[f64], q: &mut [f64]) {
    let (l, n) = (&m.layout, m.n_user);
    if l.free {
        // x = [attitude, angles, ω, v, rates, ...] (`StateLayout`); a fixed-size copy
        // where the length is known (no `memcpy` call).
        q[..4].copy_from_slice(&x[..4]);
        q[7..7 + n].copy_from_slice(&x[4..4 + n]);
    } else {
        q[..n].copy_from_slice(&x[l.angles.clone()]);
    }
}

/// Moves the net external force of the body wrenches to the orbit ([`Needs::net_force`]):
/// `F = Σ R_i f_i` (inertial), the orbit's acceleration `orbit_dv` gains `F / M`, and each
/// body receives `−m_i F / M` at its centre of mass (the falling frame's inertial force), so
/// the tree's centre of mass stays at rest in that frame. The added forces sum to `−F` and
/// their moment about the centre of mass is zero; their power is `−(F/M)·p`, zero for the
/// tree's momentum `p` (zero in that frame).
///
/// [`Needs::net_force`]: crate::effects::Needs::net_force
fn carry_net_force(ctx: &Context, forces: &mut Forces, orbit_dv: &mut [f64]) {
    let bodies = ctx.model.bodies();
    let mut f = Vec3::zeros();
    for (w, rot) in forces.body_wrench.iter().zip(&ctx.data.rotation) {
        f += rot * w.lin;
    }
    let a = f / ctx.model.total_mass();
    for (d, ai) in orbit_dv.iter_mut().zip(a.iter()) {
        *d += ai;
    }
    for (i, body) in bodies.iter().enumerate() {
        if body.mass() > 0.0 {
            let lin = ctx.data.rotation[i].tr_mul(&(-body.mass() * a));
            forces.add_wrench(i, Force::new(body.com().cross(&lin), lin));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Simulation;
    use crate::effects::{Effect, HingeSprings, Links, ReactionWheels, Wheel};
    use satsim_tree::spatial::Vec3;
    use satsim_tree::{BaseKind, samples};

    /// Free wheels (no torque, no friction) skip `ReactionWheels::apply`'s loop: the
    /// right-hand side is bit for bit what the loop gives.
    #[test]
    fn idle_wheels_give_the_loops_bits() {
        let wheels: Vec<Wheel> = [(Vec3::x(), 100.0), (Vec3::y(), -50.0), (Vec3::z(), 30.0)]
            .into_iter()
            .enumerate()
            .map(|(k, (axis, speed))| {
                let mut w = Wheel::new(format!("w{k}"), axis, 0.1);
                (w.mass, w.at, w.speed) = (2.0, 0.3 * axis, speed);
                w
            })
            .collect();
        let mut sim = Simulation::builder(samples::chain(3, BaseKind::Free))
            .effect(HingeSprings {
                damping: vec![0.4, 0.1],
                ..HingeSprings::new(vec![5.0, 2.0])
            })
            .effect(ReactionWheels::new(wheels.clone()))
            .build()
            .unwrap();
        let mut x = sim.x0().to_vec();
        for (k, v) in x.iter_mut().enumerate().skip(4) {
            *v += 0.01 * (k as f64).sin();
        }
        let rhs = |sim: &mut Simulation| {
            let mut dx = vec![0.0; x.len()];
            sim.forget_ahead();
            sim.right_hand_side(0.0, &x, &mut dx).unwrap();
            dx
        };
        let idle = rhs(&mut sim);
        let k = sim
            .effect_names()
            .iter()
            .position(|&n| n == "reaction_wheels")
            .unwrap();
        // The same wheels, never connected: `idle` stays false and `apply` takes the loop.
        let full = ReactionWheels::new(wheels.clone());
        assert!(!full.idle);
        sim.effects[k] = Box::new(full);
        let looped = rhs(&mut sim);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&idle), bits(&looped));
        // The build's wheels took the idle path: these wheels, connected as the build does.
        let mut connected = ReactionWheels::new(wheels);
        connected.connect(&Links {
            rotors: &[],
            rotors_commanded: false,
            torquers: &[],
            dipoles_commanded: false,
            thrusters: &[],
            model: sim.model(),
            flex: None,
        });
        assert!(connected.idle);
    }
}
