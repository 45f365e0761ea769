//! Aerodynamic drag on every facet of every body (contract section 12).
//!
//! Per facet of area `A`, outward unit normal `n` and drag coefficient `C_D`, with `v` the
//! velocity of the facet's centroid relative to the atmosphere, `v̂ = v/|v|` and
//! `cos α = n·v̂ > 0` (the facet meets the flow on its normal's side):
//!
//! `F = −½ ρ |v|² C_D A cos α v̂`
//!
//! at the centroid. `v` is the orbit's velocity plus the centroid's own velocity in the
//! frame falling with the centre of mass (the bus turning, a panel deploying), minus, when
//! the atmosphere turns with the Earth (`co_rotating`, the default), `ω_E × r` at the
//! centroid's position `r`. The density is the exponential atmosphere's (Vallado's Table
//! 8-4, [`satsim_environment::atmosphere`]) at the centre of mass' altitude (over a
//! spacecraft's size it changes by 1e-4 of itself per 10 m at 500 km). Facets do not shield
//! each other from the flow.
//!
//! Output: `density` (kg/m³) and `drag_torque_x/y/z`, the moment of all the facets' forces
//! about the spacecraft's centre of mass, bus axes (N m).
//!
//! Energy: the power of the drag forces on the motion in the falling frame (the bodies'
//! own velocities `u` at the centroids) is split in two. The steady flow (the orbit's
//! velocity and the Earth's rotation alone, `V`) does the work `Σ F(V)·u`, booked as an
//! actuator's: the wind that turns a panel. The rest, `Σ (F(V + u) − F(V))·u`, the damping
//! by the bodies' own motion through the air, is booked as dissipation.

use super::facets::Facets;
use super::{Context, Effect, Forces, Needs, Power, SceneEffect, Section};
use satsim_environment::Epoch;
use satsim_environment::atmosphere::density;
use satsim_environment::earth::earth_rotation_gcrf;
use satsim_integrate::SystemError;
use satsim_tree::io::FileError;
use satsim_tree::spatial::{Force, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// Which atmosphere.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Atmosphere {
    /// The exponential atmosphere of Vallado's Table 8-4.
    #[default]
    Exponential,
}

/// The drag effect.
#[derive(Clone, Debug)]
pub struct Drag {
    atmosphere: Atmosphere,
    /// `Some(epoch)`: the atmosphere turns with the Earth (the pole's direction of date from
    /// the epoch); `None`: it is at rest in the inertial frame.
    co_rotating: Option<Epoch>,
    facets: Facets,
    density: f64,
    torque: Vec3,
    /// `Σ F(V)·u` at the last `apply` (W): the steady flow's work rate (see the module docs).
    flow_power: f64,
}

/// The drag force (N) on a flat surface of area `area`, outward unit normal `n` and drag
/// coefficient `cd`, moving at `v` (m/s) through air of density `rho` (kg/m³): zero when
/// the surface faces away from the flow it meets.
///
/// ```
/// use satsim_spacecraft::effects::drag::plate_force;
/// use satsim_tree::spatial::Vec3;
/// // A plate moving along its normal at 7.6 km/s.
/// let f = plate_force(&Vec3::new(7600.0, 0.0, 0.0), &Vec3::x(), 1.0, 2.2, 1e-12);
/// assert!((f.x + 0.5 * 1e-12 * 7600.0f64.powi(2) * 2.2).abs() < 1e-18);
/// ```
pub fn plate_force(v: &Vec3, n: &Vec3, area: f64, cd: f64, rho: f64) -> Vec3 {
    #[cfg(test)]
    tests::PLATES.with(|k| k.set(k.get() + 1));
    let speed = v.norm();
    if speed == 0.0 {
        return Vec3::zeros();
    }
    let vh = v / speed;
    let c = n.dot(&vh);
    if c <= 0.0 {
        return Vec3::zeros();
    }
    -0.5 * rho * speed * speed * cd * area * c * vh
}

impl Drag {
    /// Drag on `facets` in `atmosphere`; `co_rotating`: the epoch, when the atmosphere
    /// turns with the Earth.
    pub fn new(atmosphere: Atmosphere, co_rotating: Option<Epoch>, facets: Facets) -> Self {
        Self {
            atmosphere,
            co_rotating,
            facets,
            density: 0.0,
            torque: Vec3::zeros(),
            flow_power: 0.0,
        }
    }
    /// The density (kg/m³) at distance `r` (m) from the Earth's centre.
    pub fn density(&self, r: f64) -> f64 {
        match self.atmosphere {
            Atmosphere::Exponential => density(r),
        }
    }
    /// The density at the last evaluation (kg/m³).
    pub fn last_density(&self) -> f64 {
        self.density
    }
}

impl Effect for Drag {
    fn name(&self) -> &str {
        "drag"
    }
    fn needs(&self) -> Needs {
        Needs::SURFACE_LOADS
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let orbit = ctx.orbit_or_err("drag")?;
        let com = ctx.com_or_err("drag")?;
        self.density = self.density(orbit.r.norm());
        let earth = match self.co_rotating {
            Some(epoch) => earth_rotation_gcrf(epoch, ctx.t),
            None => Vec3::zeros(),
        };
        self.facets.place(ctx.data);
        let mut moment = Vec3::zeros();
        let mut flow_power = 0.0;
        for k in 0..self.facets.len() {
            let facet = self.facets.facet(k);
            let i = self.facets.body(k);
            let rot = &ctx.data.rotation[i];
            // The centroid's velocity in the falling frame (body axes, then inertial).
            let vb = &ctx.data.v[i];
            let own = rot * (vb.lin + vb.ang.cross(&facet.at));
            let c = self.facets.centroid(k) - com;
            let flow = orbit.v - earth.cross(&(orbit.r + c));
            let (n, area, cd) = (self.facets.normal(k), facet.area, facet.drag);
            let f = plate_force(&(flow + own), n, area, cd, self.density);
            // The steady flow's force only for the energy budget: nothing else reads it.
            if ctx.power {
                flow_power += plate_force(&flow, n, area, cd, self.density).dot(&own);
            }
            if f == Vec3::zeros() {
                continue;
            }
            let lin = rot.tr_mul(&f);
            forces.add_wrench(i, Force::new(facet.at.cross(&lin), lin));
            moment += c.cross(&f);
        }
        self.torque = ctx.attitude.inverse_transform_vector(&moment);
        self.flow_power = flow_power;
        Ok(())
    }
    /// The steady flow's work is an actuator's, the rest dissipation (see the module docs).
    fn power(&self, _ctx: &Context, _own: &[f64], applied: f64) -> Power {
        Power {
            actuator: self.flow_power,
            dissipated: self.flow_power - applied,
        }
    }
    fn output_columns(&self) -> Vec<String> {
        ["density", "drag_torque_x", "drag_torque_y", "drag_torque_z"]
            .map(String::from)
            .into()
    }
    fn output(&self, _ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        row.push(self.density);
        row.extend_from_slice(self.torque.as_slice());
    }
}

/// `[effects.drag]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DragFile {
    /// `"exponential"` (default).
    #[serde(default)]
    pub atmosphere: Option<Spanned<String>>,
    /// Whether the atmosphere turns with the Earth (default true; needs the scene's epoch).
    #[serde(default)]
    pub co_rotating: Option<bool>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for Drag {
    const SECTION: &'static str = "drag";
    type File = DragFile;
    fn from_section(file: DragFile, section: &Section) -> Result<Self, FileError> {
        let atmosphere = match &file.atmosphere {
            None => Atmosphere::Exponential,
            Some(a) if a.get_ref() == "exponential" => Atmosphere::Exponential,
            Some(a) => {
                return Err(section.error(
                    Some(a.span()),
                    format!(
                        "`effects.drag.atmosphere`: unknown value `{}`, expected \"exponential\"",
                        a.get_ref()
                    ),
                ));
            }
        };
        let facets = Facets::of_section(section)?;
        let co_rotating = match file.co_rotating.unwrap_or(true) {
            true => Some(section.epoch()?),
            false => None,
        };
        Ok(Drag::new(atmosphere, co_rotating, facets))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::orbit::{Elements, Orbit, OrbitModel};
    use crate::simulation::Simulation;
    use satsim_integrate::System;
    use satsim_tree::spatial::Mat3;
    use satsim_tree::{BaseKind, Body, BoxShape, ModelBuilder, facets_of_box};
    use std::cell::Cell;

    thread_local! {
        /// Calls of [`plate_force`] on this thread.
        pub(super) static PLATES: Cell<usize> = const { Cell::new(0) };
    }

    #[test]
    fn each_facet_is_evaluated_once_per_rhs_unless_the_energy_budget_asks_for_the_flows() {
        let shape = BoxShape::new(Vec3::new(1.0, 2.0, 3.0));
        let model = ModelBuilder::new(BaseKind::Free)
            .body(
                Body::new("bus", 100.0, 10.0 * Mat3::identity())
                    .with_facets(facets_of_box(&shape, &Vec3::zeros())),
            )
            .build()
            .unwrap();
        let rhs = |budget: bool| {
            let mut sim = Simulation::builder(model.clone())
                .effect(Orbit::from_elements(
                    OrbitModel::Kepler,
                    &Elements::circular(6.778e6, 0.9),
                ))
                .effect(Drag::new(
                    Atmosphere::Exponential,
                    None,
                    Facets::of_model(&model),
                ))
                .energy_budget(budget)
                .build()
                .unwrap();
            let mut x = sim.x0().to_vec();
            // The bus turning: its facets' own velocities add to the flow's.
            x[sim.layout().omega.clone()].copy_from_slice(&[0.01, -0.02, 0.03]);
            let mut dx = vec![0.0; x.len()];
            PLATES.with(|k| k.set(0));
            sim.rhs(0.0, &x, &mut dx).unwrap();
            (PLATES.with(Cell::get), sim.layout().clone(), dx)
        };
        let (plain, layout, dx) = rhs(false);
        let (budget, with_layout, dx_budget) = rhs(true);
        assert_eq!(plain, 6, "one plate per facet");
        assert_eq!(budget, 12, "and the steady flow's for the budget");
        // The same motion, bit for bit (the budget's states come after it).
        assert_eq!(dx[..layout.len], dx_budget[..layout.len]);
        assert!(with_layout.len >= layout.len);
    }
}
