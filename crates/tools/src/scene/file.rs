//! The scene file's top level as written: `model`, `initial`, `duration`, `armature`,
//! `[integrator]`, `[output]`, `[orbit]`, `[sensors]`, `[fsw]` and the `[effects.<name>]`
//! sections (read by the effects themselves, see [`satsim_spacecraft::effects::registry`]).

use super::flexible::ElasticFile;
use satsim_tree::io::{BaseStateFile, HingesStateFile, ModelFile, StateFile, exact};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::collections::BTreeMap;
use std::fmt;
use toml::Spanned;

/// `model = "path"` or an inline `[model]` table.
#[derive(Clone, Debug)]
pub enum ModelSource {
    /// A model file, relative to the scene file.
    Path(String),
    /// An inline model (the model file's keys).
    Inline(Box<ModelFile>),
}

/// `initial = "path"` or an inline `[initial]` table.
#[derive(Clone, Debug)]
pub enum StateSource {
    /// A state file, relative to the scene file.
    Path(String),
    /// An inline state (the state file's keys) and its `flexible` entries (see
    /// [`super::flexible`]), in the order of their bodies' names.
    Inline(StateFile, Vec<(String, Spanned<ElasticFile>)>),
}

/// An inline `[initial]` table: the state file's keys and `flexible`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InitialTable {
    #[serde(default)]
    base: Option<BaseStateFile>,
    #[serde(default)]
    hinges: Option<HingesStateFile>,
    #[serde(default)]
    flexible: Option<BTreeMap<String, Spanned<ElasticFile>>>,
}

struct SourceVisitor<T>(std::marker::PhantomData<T>);

impl<'de> Visitor<'de> for SourceVisitor<ModelSource> {
    type Value = ModelSource;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a model file path or a [model] table")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
        Ok(ModelSource::Path(v.to_owned()))
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        ModelFile::deserialize(de::value::MapAccessDeserializer::new(map))
            .map(|m| ModelSource::Inline(Box::new(m)))
    }
}

impl<'de> Visitor<'de> for SourceVisitor<StateSource> {
    type Value = StateSource;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a state file path or an [initial] table")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
        Ok(StateSource::Path(v.to_owned()))
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        InitialTable::deserialize(de::value::MapAccessDeserializer::new(map)).map(|t| {
            let state = StateFile {
                base: t.base,
                hinges: t.hinges,
            };
            StateSource::Inline(state, t.flexible.unwrap_or_default().into_iter().collect())
        })
    }
}

impl<'de> Deserialize<'de> for ModelSource {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(SourceVisitor::<ModelSource>(std::marker::PhantomData))
    }
}

impl<'de> Deserialize<'de> for StateSource {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(SourceVisitor::<StateSource>(std::marker::PhantomData))
    }
}

/// The scene file's top level.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// The spacecraft.
    pub model: Spanned<ModelSource>,
    /// Its initial state (default: at rest, identity attitude, zero angles).
    #[serde(default)]
    pub initial: Option<Spanned<StateSource>>,
    /// Duration (s, > 0).
    pub duration: Spanned<f64>,
    /// `epoch = "2026-03-20T12:00:00 UTC"`: t = 0 as a date (UTC, TAI, TT or GPST), needed
    /// by the effects that depend on the date (the Sun, the Earth's rotation, the field).
    #[serde(default)]
    pub epoch: Option<Spanned<String>>,
    /// Hinge armature (kg m², >= 0) replacing the model's: one number for every hinge, or one
    /// per hinge (file order). The opt-in regularisation of a gimbal lock.
    #[serde(default)]
    pub armature: Option<Spanned<ArmatureFile>>,
    /// Integrator settings.
    #[serde(default)]
    pub integrator: Option<Spanned<IntegratorFile>>,
    /// Output settings.
    #[serde(default)]
    pub output: Option<Spanned<OutputFile>>,
    /// The orbit of the centre of mass.
    #[serde(default)]
    pub orbit: Option<Spanned<OrbitFile>>,
    /// The `[effects.<name>]` sections, raw: each is read by the effect registered under
    /// its name ([`satsim_spacecraft::effects::Registry`]).
    #[serde(default)]
    pub effects: Option<Spanned<BTreeMap<String, Spanned<toml::Value>>>>,
    /// `[sensors]`: gyros, star trackers, Sun sensors, magnetometers ([`super::sensors`]).
    #[serde(default)]
    pub sensors: Option<Spanned<super::sensors::SensorsFile>>,
    /// `[fsw]`: built-in flight software on the sensors ([`super::fsw`]).
    #[serde(default)]
    pub fsw: Option<Spanned<super::fsw::FswFile>>,
    /// `[[faults]]`: faults injected at a time ([`super::faults`]).
    #[serde(default)]
    pub faults: Vec<Spanned<super::faults::FaultFile>>,
    /// `[campaign]`: read by `satsim campaign` ([`crate::campaign`]); a single run ignores it
    /// and runs the nominal scene.
    #[serde(default)]
    pub campaign: Option<toml::Value>,
}

/// `armature = 1e-3` (every hinge) or `armature = [1e-3, 1e-3, 1e-3, 0.0, 0.0]` (per hinge).
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged, expecting = "a number or an array of numbers, one per hinge")]
pub enum ArmatureFile {
    /// The same armature for every hinge.
    All(f64),
    /// One armature per hinge, file order.
    PerHinge(Vec<f64>),
}

/// `[integrator]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorFile {
    /// Method name (default `dp54`).
    #[serde(default)]
    pub method: Option<Spanned<String>>,
    /// Fixed step, or first step of adaptive methods (s).
    #[serde(default)]
    pub step: Option<Spanned<f64>>,
    /// Relative tolerance (default 1e-9).
    #[serde(default)]
    pub rtol: Option<Spanned<f64>>,
    /// Absolute tolerance (default 1e-12).
    #[serde(default)]
    pub atol: Option<Spanned<f64>>,
    /// Largest adaptive step (s).
    #[serde(default)]
    pub max_step: Option<Spanned<f64>>,
    /// Largest number of steps (default 10 000 000).
    #[serde(default)]
    pub max_steps: Option<Spanned<i64>>,
    /// Whether the flexible bodies' elastic coordinates count in the adaptive methods' error
    /// (default true).
    #[serde(default)]
    pub elastic_error: Option<Spanned<bool>>,
}

/// `[output]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputFile {
    /// Seconds between rows (default: duration / 100).
    #[serde(default)]
    pub every: Option<Spanned<f64>>,
    /// Draw SVG plots at the end (default true).
    #[serde(default)]
    pub plots: Option<bool>,
    /// Write the 3-D playback `view.html` and its kept poses (default true).
    #[serde(default)]
    pub view: Option<bool>,
    /// Integrate the energy budget's works (actuators, dissipation) and write its columns
    /// (default true).
    #[serde(default)]
    pub energy_budget: Option<bool>,
}

/// `[orbit]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitFile {
    /// `"kepler"` (default) or `"j2"`.
    #[serde(default)]
    pub model: Option<Spanned<String>>,
    /// The Earth's field: `"point"`, `"j2"`, `"egm2008"`, or a table
    /// `{ model = "egm2008", degree = 20, order = 20 }` (replaces `model`; see
    /// `scene/orbit.rs`).
    #[serde(default)]
    pub gravity: Option<Spanned<toml::Value>>,
    /// Point-mass third bodies: `["sun", "moon"]`.
    #[serde(default)]
    pub third_body: Option<Spanned<Vec<Spanned<String>>>>,
    /// Altitude of a circular orbit above R_E (m): an alternative to `semi_major_axis`.
    #[serde(default)]
    pub altitude: Option<Spanned<f64>>,
    /// Semi-major axis (m).
    #[serde(default)]
    pub semi_major_axis: Option<Spanned<f64>>,
    /// Eccentricity (default 0).
    #[serde(default)]
    pub eccentricity: Option<Spanned<f64>>,
    /// Inclination (deg, default 0).
    #[serde(default)]
    pub inclination_deg: Option<f64>,
    /// Right ascension of the ascending node (deg, default 0).
    #[serde(default)]
    pub raan_deg: Option<f64>,
    /// Argument of periapsis (deg, default 0).
    #[serde(default)]
    pub arg_periapsis_deg: Option<f64>,
    /// True anomaly (deg, default 0).
    #[serde(default)]
    pub true_anomaly_deg: Option<f64>,
    /// Initial position (m, inertial): with `velocity`, instead of elements.
    #[serde(default, deserialize_with = "exact")]
    pub position: Option<[f64; 3]>,
    /// Initial velocity (m/s, inertial).
    #[serde(default, deserialize_with = "exact")]
    pub velocity: Option<[f64; 3]>,
    /// Gravitational parameter (m³/s², default 3.986004418e14).
    #[serde(default)]
    pub mu: Option<f64>,
    /// J2 (default 1.08262668e-3).
    #[serde(default)]
    pub j2: Option<f64>,
    /// Equatorial radius for J2 (m, default 6378137).
    #[serde(default)]
    pub radius: Option<f64>,
}
