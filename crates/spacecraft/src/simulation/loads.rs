//! [`Simulation::loads`]: what each effect applies at one time and state, body by body and
//! as generalised forces (what `satsim environment` prints, contract section 12).

use super::Simulation;
use super::run::{RunError, Shared};
use satsim_integrate::{IntegrateError, Options, Output, System, SystemError, stop_due};
use satsim_tree::flexible::{self, FlexData};
use satsim_tree::spatial::{Force, Vec3};
use satsim_tree::{Data, rnea};
use std::cell::RefCell;
use std::convert::Infallible;

/// The loads one effect applies.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectLoads {
    /// The effect's name.
    pub name: String,
    /// Per body of the scene's model (file order): the wrench it applies, in the body's
    /// axes, about the body frame's origin (force N, torque N m).
    pub wrenches: Vec<Force>,
    /// Per degree of freedom of the scene's model (`satsim dynamics`'s order: a free base's
    /// 6, angular first, the hinges in file order, then the flexible bodies' modal
    /// coordinates): `Σ_i J_iᵀ f_i` plus its hinge torques (N m, N) and, on the modes, the
    /// generalised forces it puts on them directly (its loads at points of a flexible body,
    /// facets riding it, the gravity gradient over it; N √kg⁻¹).
    pub generalized: Vec<f64>,
}

impl EffectLoads {
    /// Whether the effect applies no load at all (a controller, the orbit).
    pub fn is_empty(&self) -> bool {
        self.wrenches.iter().all(|w| *w == Force::zero())
            && self.generalized.iter().all(|g| *g == 0.0)
    }
}

impl Simulation {
    /// Every effect's loads at time `t` and state `x`, one entry per effect in the order
    /// they run (each sees what the effects before it wrote, as in a right-hand side). The
    /// constant hinge torques and the frame's inertial forces (see
    /// [`Needs::net_force`](crate::effects::Needs::net_force)) belong to no effect and are
    /// left out.
    pub fn loads(&mut self, t: f64, x: &[f64]) -> Result<Vec<EffectLoads>, SystemError> {
        self.check_len(x.len(), "loads")?;
        self.unpack(x);
        self.kinematics(true)?;
        let n_bodies = self.model.tree.n_bodies() - self.model.n_rotors;
        let n_user = self.model.n_user;
        let nb = self.model.tree.base_nv();
        type Step = (String, Vec<Force>, Vec<f64>, Vec<f64>);
        let mut steps: Vec<Step> = Vec::new();
        self.with_context(t, x, true, |ctx, h| {
            h.forces.reset_to(&vec![0.0; h.forces.hinge_torque.len()]);
            let mut wrench_before = h.forces.body_wrench.clone();
            let mut tau_before = h.forces.hinge_torque.clone();
            let mut elastic_before = h.forces.elastic.clone();
            for (e, r) in h.effects.iter_mut().zip(h.own) {
                e.apply(ctx, h.forces, &x[r.clone()], &mut h.scratch[r.clone()])?;
                let w: Vec<Force> = h.forces.body_wrench[..n_bodies]
                    .iter()
                    .zip(&wrench_before)
                    .map(|(a, b)| *a - *b)
                    .collect();
                let tau: Vec<f64> = h.forces.hinge_torque[..n_user]
                    .iter()
                    .zip(&tau_before)
                    .map(|(a, b)| a - b)
                    .collect();
                let elastic: Vec<f64> = h
                    .forces
                    .elastic
                    .iter()
                    .zip(&elastic_before)
                    .map(|(a, b)| a - b)
                    .collect();
                steps.push((e.name().to_owned(), w, tau, elastic));
                wrench_before.clone_from(&h.forces.body_wrench);
                tau_before.clone_from(&h.forces.hinge_torque);
                elastic_before.clone_from(&h.forces.elastic);
            }
            Ok::<(), SystemError>(())
        })?;
        // Σ J_iᵀ f_i = −RNEA(q, 0, 0, f): inverse dynamics at rest, no other force.
        let tree = &self.model.tree;
        let mut data = Data::new(tree);
        let zero = vec![0.0; tree.nv()];
        let mut fext = vec![Force::zero(); tree.n_bodies()];
        let mut out = Vec::with_capacity(steps.len());
        // A flexible tree's: the same at rest in its deformation, less that of no force (its
        // stiffness's `K η`), so that each mode gets the work of the wrenches through it (a
        // body hung on a node moves with the mode).
        let mut flex = match (&self.model.flex, &self.data.flex) {
            (Some(f), Some(w)) => {
                let mut data = FlexData::new(f);
                let zero = vec![0.0; f.nv()];
                let unloaded = flexible::rnea(f, &mut data, &w.q, &zero, &zero, None)
                    .map_err(SystemError::from_error)?
                    .clone();
                Some((f, data, zero, unloaded, &w.q))
            }
            _ => None,
        };
        for (name, wrenches, tau, elastic) in steps {
            fext[..n_bodies].copy_from_slice(&wrenches);
            let mut generalized: Vec<f64> = match &mut flex {
                None => rnea(tree, &mut data, &self.data.q, &zero, &zero, Some(&fext))
                    .map_err(SystemError::from_error)?
                    .iter()
                    .take(nb + n_user)
                    .map(|v| -v)
                    .collect(),
                Some((f, data, zero, unloaded, q)) => {
                    let id = flexible::rnea(f, data, q, zero, zero, Some(&fext))
                        .map_err(SystemError::from_error)?;
                    let modes = f.nv() - f.n_elastic()..f.nv();
                    let rows = (0..nb + n_user).chain(modes);
                    let mut g: Vec<f64> = rows.map(|r| unloaded[r] - id[r]).collect();
                    for (g, e) in g[nb + n_user..].iter_mut().zip(&elastic) {
                        *g += e;
                    }
                    g
                }
            };
            for (g, t) in generalized[nb..nb + n_user].iter_mut().zip(&tau) {
                *g += t;
            }
            out.push(EffectLoads {
                name,
                wrenches,
                generalized,
            });
        }
        Ok(out)
    }

    /// The state a run of this simulation reaches at `t_end` (from its initial state, events
    /// handled as in [`Simulation::run`]), with the time it reached. The effects' samples due
    /// at the time reached are taken (at `t0` too: a thruster that fires from the start is
    /// on), so that [`Simulation::loads`] there shows what the run applies from then on.
    pub fn state_at(
        &mut self,
        options: &Options,
        t_end: f64,
    ) -> Result<(f64, Vec<f64>), RunError<Infallible>> {
        let mut x0 = self.x0.clone();
        let t0 = self.t0;
        if t_end <= t0 {
            // The samples due at the start, as a run takes them before its first step (a
            // thruster firing from t0 is on there).
            if stop_due(t0, self.next_stop()) {
                let system = |source| RunError::Integrate(IntegrateError::System { t: t0, source });
                self.on_stop(t0, &mut x0).map_err(system)?;
                if stop_due(t0, self.next_stop()) {
                    return Err(system(SystemError::new(format!(
                        "the time stop at {} was handled at t = {t0} but did not move past it",
                        self.next_stop()
                    ))));
                }
            }
            return Ok((t0, x0));
        }
        let cell = RefCell::new(self);
        let mut shared = Shared(&cell);
        let mut last = (t0, x0.clone());
        satsim_integrate::integrate(
            &mut shared,
            options,
            t0,
            &x0,
            t_end,
            &Output::Interval(t_end - t0),
            |t, x| {
                last = (t, x.to_vec());
                std::ops::ControlFlow::Continue(())
            },
        )
        .map_err(RunError::Integrate)?;
        Ok(last)
    }
}

/// The moment about `point` of a wrench `w` (body axes, about the body origin) of a body at
/// `origin` with attitude `rot` (body to inertial), inertial axes.
pub fn moment_about(
    w: &Force,
    rot: &satsim_tree::spatial::Mat3,
    origin: &Vec3,
    point: &Vec3,
) -> Vec3 {
    rot * w.ang + (origin - point).cross(&(rot * w.lin))
}
