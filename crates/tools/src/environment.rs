//! The environment a scene's spacecraft meets at one time (`satsim environment`, contract
//! section 12): its orbit, the Sun and the Earth's shadow, the air's density, the
//! geomagnetic field, and every enabled effect's loads on every body and as generalised
//! forces, at the state the scene's run reaches at that time.
//!
//! The environment quantities come from the same models the effects use: the shadow from
//! `[effects.solar_radiation]`'s model (conical without it), the density from
//! `[effects.drag]`'s atmosphere (0 without it), the field from `[effects.magnetic]`'s
//! (zeros without it). With an orbit, `gravity` is the Earth's gravitational acceleration
//! in the orbit's field (point mass, J2 or EGM2008's harmonics: [`Orbit::gravity`]); with
//! third bodies, `moon` is the Moon's position (when it is one of them) and `third_body` their
//! perturbing acceleration ([`Orbit::third_body`]), from the same tracks the orbit follows.
//! The gravity-gradient torque in `effects` keeps the point-mass gradient (`μ/r³`) whatever
//! the orbit's field. With `[effects.solar_radiation] albedo = true`, the solar-radiation
//! effect's loads are reported as two: `solar_radiation`, the Sun's light, and
//! `earth_radiation`, the Earth's reflected and emitted light, each computed at the same
//! state by a copy of the scene's simulation applying that light alone (they add up to what
//! the run applies).

use crate::scene::Scene;
use satsim_environment::shadow::{ShadowModel, shadow_fraction};
use satsim_environment::sun::SunTrack;
use satsim_integrate::SystemError;
use satsim_spacecraft::effects::solar_radiation::LightSources;
use satsim_spacecraft::effects::{Drag, Magnetic, Orbit, SolarRadiation};
use satsim_spacecraft::simulation::{EffectLoads, RunError, SimError};
use satsim_tree::spatial::Vec3;
use std::convert::Infallible;
use thiserror::Error;

/// One body's load from one effect: force (N) and torque about the body frame's origin
/// (N m), both in the body's axes.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyLoad {
    /// The body's name.
    pub body: String,
    /// Force (N), body axes.
    pub force: Vec3,
    /// Torque about the body frame's origin (N m), body axes.
    pub torque: Vec3,
}

/// One effect's loads.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectReport {
    /// The effect's name (its scene section).
    pub name: String,
    /// Per body of the model, file order.
    pub bodies: Vec<BodyLoad>,
    /// One per degree of freedom, `satsim dynamics`'s order (a free base's 6, angular
    /// first, then the hinges in file order).
    pub generalized_forces: Vec<f64>,
}

/// What `satsim environment` prints.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    /// The time (s) reached.
    pub t: f64,
    /// The scene's epoch as written by hifitime, when it has one.
    pub epoch: Option<String>,
    /// The orbit's position and velocity (m, m/s, GCRF), when the scene has an orbit.
    pub orbit: Option<(Vec3, Vec3)>,
    /// Unit vector from the spacecraft to the Sun (GCRF) and the distance (m): with an
    /// orbit and an epoch.
    pub sun: Option<(Vec3, f64)>,
    /// The fraction of the Sun's disk visible (with an orbit and an epoch).
    pub shadow: Option<f64>,
    /// The air's density (kg/m³, 0 without drag), with an orbit.
    pub density: Option<f64>,
    /// The geomagnetic field (T, GCRF; zeros without the magnetic effect), with an orbit.
    pub magnetic_field: Option<Vec3>,
    /// The Earth's gravitational acceleration at the position (m/s², GCRF) in the orbit's
    /// field, with an orbit.
    pub gravity: Option<Vec3>,
    /// The Moon's position from the Earth's centre (m, GCRF), when it is a third body.
    pub moon: Option<Vec3>,
    /// The third bodies' perturbing acceleration (m/s², GCRF), when the orbit has any.
    pub third_body: Option<Vec3>,
    /// Every enabled effect that applies loads, in the order they run.
    pub effects: Vec<EffectReport>,
}

/// Why the environment could not be computed.
#[derive(Debug, Error)]
pub enum EnvironmentError {
    /// The scene's simulation could not be built.
    #[error("{0}")]
    Setup(#[from] SimError),
    /// The run to the requested time failed.
    #[error("the run to t = {at} s failed: {source}")]
    Run {
        /// The requested time.
        at: f64,
        /// Why.
        source: RunError<Infallible>,
    },
    /// Evaluating the loads failed.
    #[error("{0}")]
    Loads(#[from] SystemError),
    /// A time that is negative, beyond the scene's duration or not finite.
    #[error(
        "--at {0}: the time must be a finite number of seconds from 0 to the scene's duration ({1} s)"
    )]
    Time(f64, f64),
}

/// The solar-radiation effect's loads at `t`, `x` split by the light's source (the Sun's,
/// named `solar_radiation`, and the Earth's, `earth_radiation`) when the Earth's light is on;
/// `None` when it is off.
fn split_light(
    scene: &Scene,
    t: f64,
    x: &[f64],
) -> Result<Option<[EffectLoads; 2]>, EnvironmentError> {
    if scene
        .effects
        .get::<SolarRadiation>()
        .and_then(|s| s.earth_radiation())
        .is_none()
    {
        return Ok(None);
    }
    let alone = |sources: LightSources, name: &str| -> Result<EffectLoads, EnvironmentError> {
        let mut one = scene.clone();
        if let Some(s) = one.effects.get_mut::<SolarRadiation>() {
            s.set_sources(sources);
        }
        let mut loads = one.simulation()?.loads(t, x)?;
        let i = loads
            .iter()
            .position(|l| l.name == "solar_radiation")
            .ok_or_else(|| SystemError::new("the solar-radiation effect is missing"))?;
        let mut l = loads.swap_remove(i);
        l.name = name.to_owned();
        Ok(l)
    };
    Ok(Some([
        alone(LightSources::Sun, "solar_radiation")?,
        alone(LightSources::Earth, "earth_radiation")?,
    ]))
}

/// The environment and loads of `scene` at time `at` (s, from 0 to its duration): at the
/// initial state for 0, otherwise at the state its run reaches at `at`.
pub fn environment(scene: &Scene, at: f64) -> Result<Environment, EnvironmentError> {
    if !(at.is_finite() && (0.0..=scene.duration).contains(&at)) {
        return Err(EnvironmentError::Time(at, scene.duration));
    }
    let mut sim = scene.simulation()?;
    let (t, x) = sim
        .state_at(&scene.options, at)
        .map_err(|source| EnvironmentError::Run { at, source })?;
    let mut loads = sim.loads(t, &x)?;
    if let Some(i) = loads.iter().position(|l| l.name == "solar_radiation")
        && let Some([sun, earth]) = split_light(scene, t, &x)?
    {
        loads.splice(i..=i, [sun, earth]);
    }
    let model = &scene.model;
    let effects = loads
        .into_iter()
        .filter(|l| !l.is_empty())
        .map(|l| EffectReport {
            bodies: model
                .bodies()
                .iter()
                .zip(&l.wrenches)
                .map(|(b, w)| BodyLoad {
                    body: b.name().to_owned(),
                    force: w.lin,
                    torque: w.ang,
                })
                .collect(),
            generalized_forces: l.generalized,
            name: l.name,
        })
        .collect();
    let orbit = sim.layout().effect("orbit").map(|r| {
        let o = &x[r];
        (Vec3::new(o[0], o[1], o[2]), Vec3::new(o[3], o[4], o[5]))
    });
    let srp = scene.effects.get::<SolarRadiation>();
    let sun = match (orbit, scene.epoch) {
        (Some((r, _)), Some(epoch)) => {
            // As the solar-pressure effect sees it (the same knots, the same bits).
            let r_sun = SunTrack::new(epoch).position(t);
            let to_sun = r_sun - r;
            let model = srp.map_or(ShadowModel::Conical, |s| s.shadow_model());
            Some((
                to_sun.normalize(),
                to_sun.norm(),
                shadow_fraction(model, &r, &r_sun),
            ))
        }
        _ => None,
    };
    // The drag effect's atmosphere at (t, r): the run's `density` column's bits.
    let density = match (orbit, scene.effects.get::<Drag>()) {
        (Some((r, _)), Some(d)) => Some(d.density(t, &r)?),
        (Some(_), None) => Some(0.0),
        (None, _) => None,
    };
    let magnetic_field = orbit.map(|(r, _)| {
        scene
            .effects
            .get::<Magnetic>()
            .map_or(Vec3::zeros(), |m| m.field().field_gcrf(t, &r))
    });
    let orbit_effect = scene.effects.get::<Orbit>();
    let gravity = match (orbit, orbit_effect) {
        (Some((r, _)), Some(o)) => Some(o.gravity(t, &r)?),
        _ => None,
    };
    let (moon, third_body) = match (orbit, orbit_effect) {
        (Some((r, _)), Some(o)) if o.third_bodies.any() => {
            // A fresh copy: its tracks' knots depend on t only, so it sees the orbit's bits.
            let mut o = o.clone();
            let (_, moon) = o.third_body_positions(t);
            (moon, Some(o.third_body(t, &r)?))
        }
        _ => (None, None),
    };
    Ok(Environment {
        t,
        epoch: scene.epoch.map(|e| e.to_string()),
        orbit,
        sun: sun.map(|(s, d, _)| (s, d)),
        shadow: sun.map(|(_, _, nu)| nu),
        density,
        magnetic_field,
        gravity,
        moon,
        third_body,
        effects,
    })
}
