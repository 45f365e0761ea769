//! `satsim environment SCENE.toml [--at T]` (contract section 12): the orbit, the Sun and
//! the Earth's shadow, the density, the geomagnetic field, the gravity (and the Moon and the
//! third bodies' pull, when the orbit has them), and every enabled effect's loads
//! on every body and as generalised forces, at the state the scene's run reaches at `T`
//! (default 0, the initial state), as one JSON object. The work is
//! [`satsim_tools::environment`]'s.

use super::linearize::scene_error;
use super::{CliError, Output, to_json};
use satsim_tools::environment::{EffectReport, Environment, environment};
use satsim_tools::scene::Scene;
use serde::ser::{Serialize, SerializeMap, Serializer};
use std::path::PathBuf;

/// The flags of `satsim environment`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (TOML, cli-contract section 7)
    #[arg(value_name = "SCENE.toml")]
    pub scene: PathBuf,
    /// The time (s, from 0 to the scene's duration): the state the scene's run reaches then
    #[arg(
        long,
        value_name = "T",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub at: f64,
    /// Override a scene value by its dotted path, e.g. `--set duration=60` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::run::parse_override)]
    pub set: Vec<satsim_tools::scene_keys::Override>,
}

/// Runs `satsim environment`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let scene = Scene::read_with(&args.scene, &args.set)?;
    super::print_warnings(&scene.warnings);
    let env = environment(&scene, args.at).map_err(|e| scene_error(&args.scene, e))?;
    to_json(&Json(&env))
}

/// The printed object, in the contract's key order; quantities the scene cannot give (no
/// orbit, no epoch) are left out.
struct Json<'a>(&'a Environment);

impl Serialize for Json<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let e = self.0;
        let v = |x: &satsim_tree::spatial::Vec3| [x.x, x.y, x.z];
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("t", &e.t)?;
        if let Some(epoch) = &e.epoch {
            m.serialize_entry("epoch", epoch)?;
        }
        if let Some((r, vel)) = &e.orbit {
            m.serialize_entry("position", &v(r))?;
            m.serialize_entry("velocity", &v(vel))?;
        }
        if let Some((sun, d)) = &e.sun {
            m.serialize_entry("sun", &v(sun))?;
            m.serialize_entry("sun_distance", d)?;
        }
        if let Some(nu) = e.shadow {
            m.serialize_entry("shadow", &nu)?;
        }
        if let Some(rho) = e.density {
            m.serialize_entry("density", &rho)?;
        }
        if let Some(b) = &e.magnetic_field {
            m.serialize_entry("magnetic_field", &v(b))?;
        }
        if let Some(g) = &e.gravity {
            m.serialize_entry("gravity", &v(g))?;
        }
        if let Some(r) = &e.moon {
            m.serialize_entry("moon", &v(r))?;
        }
        if let Some(a) = &e.third_body {
            m.serialize_entry("third_body", &v(a))?;
        }
        m.serialize_entry("effects", &Effects(&e.effects))?;
        m.end()
    }
}

struct Effects<'a>(&'a [EffectReport]);

impl Serialize for Effects<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for e in self.0 {
            m.serialize_entry(&e.name, &Effect(e))?;
        }
        m.end()
    }
}

struct Effect<'a>(&'a EffectReport);

impl Serialize for Effect<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(2))?;
        m.serialize_entry("bodies", &Bodies(self.0))?;
        m.serialize_entry("generalized_forces", &self.0.generalized_forces)?;
        m.end()
    }
}

struct Bodies<'a>(&'a EffectReport);

impl Serialize for Bodies<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.bodies.len()))?;
        for b in &self.0.bodies {
            let mut w = serde_json::Map::new();
            w.insert("force".into(), [b.force.x, b.force.y, b.force.z].into());
            w.insert("torque".into(), [b.torque.x, b.torque.y, b.torque.z].into());
            m.serialize_entry(&b.body, &w)?;
        }
        m.end()
    }
}
