//! The scene file (TOML): a spacecraft model, its initial state, the effects to include,
//! the integrator, the duration and the output. `docs/src/reference/scene.md` lists every key.
//!
//! ```toml
//! model = "satellite.toml"     # or an inline [model] table (model-file keys)
//! initial = "state.json"       # or an inline [initial] table (state-file keys); default: rest
//! duration = 600.0             # s
//!
//! [integrator]
//! method = "rk4"               # rk4, dp54, dop853, radau5
//! step = 0.01                  # s
//!
//! [output]
//! every = 1.0                  # s
//!
//! [effects.hinge_springs]
//! stiffness = [50.0, 20.0]
//! ```
//!
//! Parsing is strict: an unknown key, a missing required key or a value of the wrong type is
//! an error naming the scene file and line; so is a negative duration, step, tolerance or
//! output interval, and an effect whose needs are not met (the message says what to add).
//! [`Scene::simulation`] turns a scene into a [`Simulation`] holding exactly the enabled
//! effects.

use crate::effects::{
    AttitudeControl, Elements, GravityGradient, GravityModel, HingeControl, HingeProfile,
    HingeSprings, HingeStop, HingeStops, Orbit, OrbitModel, ReactionWheels, StopAction, Target,
    Wheel,
};
use crate::scene_keys::{self, Override};
use crate::simulation::{SimError, Simulation};
use nalgebra::{Quaternion, UnitQuaternion};
use satsim_integrate::{Method, Options};
use satsim_tree::io::{FileError, ModelFile, StateFile, line_of, with_key};
use satsim_tree::spatial::Vec3;
use satsim_tree::{Model, State};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

// ---------------------------------------------------------------------------------------------
// The file, as written

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
    /// An inline state (the state file's keys).
    Inline(StateFile),
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
        StateFile::deserialize(de::value::MapAccessDeserializer::new(map)).map(StateSource::Inline)
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
    /// The effects.
    #[serde(default)]
    pub effects: Option<Spanned<EffectsFile>>,
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
}

/// `[orbit]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitFile {
    /// `"kepler"` (default) or `"j2"`.
    #[serde(default)]
    pub model: Option<Spanned<String>>,
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
    #[serde(default)]
    pub position: Option<[f64; 3]>,
    /// Initial velocity (m/s, inertial).
    #[serde(default)]
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

/// `[effects]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsFile {
    /// `[effects.gravity_gradient]`.
    #[serde(default)]
    pub gravity_gradient: Option<Spanned<GravityFile>>,
    /// `[effects.hinge_springs]`.
    #[serde(default)]
    pub hinge_springs: Option<Spanned<SpringsFile>>,
    /// `[effects.hinge_control]`.
    #[serde(default)]
    pub hinge_control: Option<Spanned<HingeControlFile>>,
    /// `[effects.hinge_stops]`.
    #[serde(default)]
    pub hinge_stops: Option<Spanned<HingeStopsFile>>,
    /// `[effects.reaction_wheels]`.
    #[serde(default)]
    pub reaction_wheels: Option<Spanned<WheelsFile>>,
    /// `[effects.attitude_control]`.
    #[serde(default)]
    pub attitude_control: Option<Spanned<AttitudeFile>>,
}

/// `[effects.gravity_gradient]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravityFile {
    /// `"preprint"` (default) or `"full"`.
    #[serde(default)]
    pub model: Option<Spanned<String>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[effects.hinge_springs]` (contract section 7).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringsFile {
    /// N m/rad, one per hinge, file order.
    pub stiffness: Spanned<Vec<f64>>,
    /// N m s/rad (default zeros).
    #[serde(default)]
    pub damping: Option<Spanned<Vec<f64>>>,
    /// rad (default zeros).
    #[serde(default)]
    pub reference: Option<Spanned<Vec<f64>>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[effects.hinge_control]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HingeControlFile {
    /// `[[effects.hinge_control.hinge]]`.
    #[serde(default)]
    pub hinge: Vec<Spanned<HingeProfileFile>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// One `[[effects.hinge_control.hinge]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HingeProfileFile {
    /// The hinge's name.
    pub name: Spanned<String>,
    /// Start angle (rad).
    pub start: f64,
    /// End angle (rad).
    pub end: f64,
    /// Ramp start (s, default 0).
    #[serde(default)]
    pub t_start: Option<f64>,
    /// Ramp duration (s, > 0).
    pub duration: Spanned<f64>,
    /// N m/rad.
    pub kp: f64,
    /// N m s/rad (default 0).
    #[serde(default)]
    pub kd: Option<f64>,
    /// N m (default unlimited).
    #[serde(default)]
    pub torque_limit: Option<Spanned<f64>>,
}

/// `[effects.hinge_stops]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HingeStopsFile {
    /// `[[effects.hinge_stops.stop]]`.
    #[serde(default)]
    pub stop: Vec<Spanned<StopFile>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// One `[[effects.hinge_stops.stop]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StopFile {
    /// The hinge's name.
    pub hinge: Spanned<String>,
    /// Lower stop (rad).
    #[serde(default)]
    pub lower: Option<f64>,
    /// Upper stop (rad).
    #[serde(default)]
    pub upper: Option<f64>,
    /// `"latch"` (default) or `"rebound"`.
    #[serde(default)]
    pub action: Option<Spanned<String>>,
    /// Coefficient of restitution of a rebound, in [0, 1] (default 0.5).
    #[serde(default)]
    pub restitution: Option<Spanned<f64>>,
    /// A rebound slower than this latches (rad/s, default 1e-3).
    #[serde(default)]
    pub min_rebound_rate: Option<f64>,
}

/// `[effects.reaction_wheels]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelsFile {
    /// `[[effects.reaction_wheels.wheel]]`.
    #[serde(default)]
    pub wheel: Vec<Spanned<WheelFile>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// One `[[effects.reaction_wheels.wheel]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// Spin axis, bus axes (normalised).
    pub axis: Spanned<[f64; 3]>,
    /// Axial inertia (kg m², > 0).
    pub inertia: Spanned<f64>,
    /// Transverse inertia (kg m², default inertia / 2, >= inertia / 2).
    #[serde(default)]
    pub transverse: Option<f64>,
    /// Rotor mass (kg, default 0).
    #[serde(default)]
    pub mass: Option<f64>,
    /// Rotor centre, bus frame (m, default origin).
    #[serde(default)]
    pub at: Option<[f64; 3]>,
    /// Torque limit (N m, default unlimited).
    #[serde(default)]
    pub max_torque: Option<f64>,
    /// Speed limit (rad/s, default unlimited).
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// Coulomb friction α0 (N m, default 0).
    #[serde(default)]
    pub coulomb: Option<f64>,
    /// Stribeck friction α1 (N m, default 0).
    #[serde(default)]
    pub stribeck: Option<f64>,
    /// Stribeck speed Ω0 (rad/s, default 1).
    #[serde(default)]
    pub stribeck_speed: Option<f64>,
    /// Viscous friction α2 (N m s/rad, default 0).
    #[serde(default)]
    pub viscous: Option<f64>,
    /// Initial speed relative to the bus (rad/s, default 0).
    #[serde(default)]
    pub speed: Option<f64>,
    /// Constant motor torque without a controller (N m, default 0).
    #[serde(default)]
    pub torque: Option<f64>,
}

/// `[effects.attitude_control]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttitudeFile {
    /// `"inertial"` (default) or `"orbital"`.
    #[serde(default)]
    pub target: Option<Spanned<String>>,
    /// Target attitude (inertial) or offset from the orbital frame, `[w, x, y, z]`.
    #[serde(default)]
    pub attitude: Option<Spanned<[f64; 4]>>,
    /// Proportional gain (N m/rad).
    pub kp: f64,
    /// Derivative gain (N m s/rad).
    pub kd: f64,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

// ---------------------------------------------------------------------------------------------
// The resolved scene

/// The effects a scene enables, resolved against its model.
#[derive(Clone, Debug, Default)]
pub struct EffectSet {
    /// `[orbit]`.
    pub orbit: Option<Orbit>,
    /// Gravity gradient.
    pub gravity_gradient: Option<GravityGradient>,
    /// Hinge springs.
    pub hinge_springs: Option<HingeSprings>,
    /// Hinge controllers.
    pub hinge_control: Option<HingeControl>,
    /// Hinge stops.
    pub hinge_stops: Option<HingeStops>,
    /// Reaction wheels.
    pub reaction_wheels: Option<ReactionWheels>,
    /// Attitude control.
    pub attitude_control: Option<AttitudeControl>,
}

/// A scene, read and checked.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file (for messages); `<inline>` for scenes built in code.
    pub path: PathBuf,
    /// The spacecraft.
    pub model: Model,
    /// Its initial state.
    pub initial: State,
    /// Duration (s).
    pub duration: f64,
    /// Integrator options.
    pub options: Options,
    /// Seconds between output rows.
    pub every: f64,
    /// Draw SVG plots.
    pub plots: bool,
    /// Write the 3-D playback `view.html` (and `poses.csv`, `view.json`): see [`crate::view`].
    pub view: bool,
    /// The enabled effects.
    pub effects: EffectSet,
    /// What the reader accepted but the user should hear about (a nearly unit attitude
    /// quaternion normalised…), each naming the file; the command line prints them on
    /// standard error.
    pub warnings: Vec<String>,
}

impl Scene {
    /// A torque-free scene of `model` from `initial`, integrated by DP54 at the given
    /// tolerances, with rows every `duration / 100`. Add effects through [`Scene::effects`].
    pub fn new(model: Model, initial: State, duration: f64) -> Self {
        Self {
            path: PathBuf::from("<inline>"),
            model,
            initial,
            duration,
            options: Options::new(Method::Dp54)
                .with_tolerances(1e-9, 1e-12)
                .with_max_steps(10_000_000),
            every: duration / 100.0,
            plots: true,
            view: true,
            effects: EffectSet::default(),
            warnings: Vec::new(),
        }
    }

    /// A fresh [`Simulation`] with exactly the enabled effects.
    pub fn simulation(&self) -> Result<Simulation, SimError> {
        let e = self.effects.clone();
        let mut b = Simulation::builder(self.model.clone()).initial(self.initial.clone());
        if let Some(x) = e.orbit {
            b = b.effect(x);
        }
        if let Some(x) = e.gravity_gradient {
            b = b.effect(x);
        }
        if let Some(x) = e.hinge_springs {
            b = b.effect(x);
        }
        if let Some(x) = e.hinge_control {
            b = b.effect(x);
        }
        if let Some(x) = e.hinge_stops {
            b = b.effect(x);
        }
        if let Some(mut x) = e.reaction_wheels {
            x.commanded = e.attitude_control.is_some();
            b = b.effect(x);
        }
        if let Some(x) = e.attitude_control {
            b = b.effect(x);
        }
        b.build()
    }

    /// Reads the scene file at `path`.
    pub fn read(path: impl AsRef<Path>) -> Result<Scene, FileError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Scene::parse(&text, path)
    }

    /// Reads the scene file at `path` with `overrides` (`--set KEY=VALUE`, see
    /// [`crate::scene_keys`]) applied in order. With overrides, an error found in the
    /// rewritten scene names the scene file and says which overrides were applied.
    pub fn read_with(path: impl AsRef<Path>, overrides: &[Override]) -> Result<Scene, FileError> {
        let path = path.as_ref();
        if overrides.is_empty() {
            return Scene::read(path);
        }
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let rewritten = scene_keys::overridden_text(&text, path, overrides)?;
        let mut scene = Scene::parse(&rewritten, path)
            .map_err(|e| scene_keys::after_overrides(e, path, overrides))?;
        // A line of the rewritten text means nothing to the user: drop it.
        let prefix = format!("{}:", path.display());
        for w in &mut scene.warnings {
            if let Some(rest) = w.strip_prefix(&prefix)
                && let Some((line, msg)) = rest.split_once(':')
                && line.parse::<usize>().is_ok()
            {
                *w = format!("{} (with --set):{msg}", path.display());
            }
        }
        Ok(scene)
    }

    /// Parses a scene's text; `path` names it in errors and anchors its relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, FileError> {
        let p = Parser { text, path };
        p.scene()
    }
}

/// The lowest orbit altitude a scene accepts (m): below it the atmosphere ends an orbit
/// within hours, and a smaller number is almost always kilometres written as metres.
pub const MIN_ALTITUDE: f64 = 100e3;

struct Parser<'a> {
    text: &'a str,
    path: &'a Path,
}

impl Parser<'_> {
    fn err(&self, span: Option<Range<usize>>, message: impl Into<String>) -> FileError {
        FileError::Schema {
            path: self.path.to_path_buf(),
            line: span.map(|s| line_of(self.text, s.start)),
            message: message.into(),
        }
    }

    /// `dir/written`, which must exist: else an error at the scene's line of `key`.
    fn existing(
        &self,
        dir: &Path,
        written: &str,
        span: Range<usize>,
        key: &str,
    ) -> Result<PathBuf, FileError> {
        let file = dir.join(written);
        if file.is_file() {
            Ok(file)
        } else {
            Err(scene_keys::missing_source(
                self.path,
                Some(line_of(self.text, span.start)),
                key,
                written,
                &file,
            ))
        }
    }

    fn positive(&self, x: &Spanned<f64>, what: &str) -> Result<f64, FileError> {
        let v = *x.get_ref();
        if !(v > 0.0 && v.is_finite()) {
            return Err(self.err(
                Some(x.span()),
                format!("`{what}` must be a finite number > 0, got {v}"),
            ));
        }
        Ok(v)
    }

    fn non_negative(&self, x: &Spanned<f64>, what: &str) -> Result<f64, FileError> {
        let v = *x.get_ref();
        if !(v >= 0.0 && v.is_finite()) {
            return Err(self.err(
                Some(x.span()),
                format!("`{what}` must be a finite number >= 0, got {v}"),
            ));
        }
        Ok(v)
    }

    /// Every given value is finite (TOML accepts `nan` and `inf`), and those marked
    /// non-negative are `>= 0`; the error names the key and the table's line.
    fn check_numbers(
        &self,
        span: Range<usize>,
        table: &str,
        values: &[(&str, Option<f64>, bool)],
    ) -> Result<(), FileError> {
        for &(key, v, non_negative) in values {
            let Some(v) = v else { continue };
            if !v.is_finite() || (non_negative && v < 0.0) {
                let what = if non_negative {
                    "a finite number >= 0"
                } else {
                    "a finite number"
                };
                return Err(self.err(
                    Some(span),
                    format!("`{table}{key}` must be {what}, got {v}"),
                ));
            }
        }
        Ok(())
    }

    fn scene(&self) -> Result<Scene, FileError> {
        let path = self.path.to_path_buf();
        if self.text.trim().is_empty() {
            return Err(FileError::Empty { path });
        }
        let located = |e: &toml::de::Error| e.span().map(|s| line_of(self.text, s.start));
        if let Err(e) = self.text.parse::<toml::Table>() {
            return Err(FileError::Syntax {
                line: located(&e),
                message: e.message().trim_end().to_owned(),
                path,
            });
        }
        let file: SceneFile = toml::from_str(self.text).map_err(|e| FileError::Schema {
            line: located(&e),
            message: with_key(&e, reword(e.message())),
            path: path.clone(),
        })?;
        let dir = self.path.parent().unwrap_or(Path::new("")).to_path_buf();

        // Model and initial state.
        let model = match file.model.get_ref() {
            ModelSource::Path(p) => {
                satsim_tree::read_model(self.existing(&dir, p, file.model.span(), "model")?)?
            }
            ModelSource::Inline(m) => m.build().map_err(|e| e.in_file(self.text, self.path))?,
        };
        let model = match &file.armature {
            Some(a) => self.armature(model, a)?,
            None => model,
        };
        let mut warnings = Vec::new();
        let initial = match file.initial.as_ref().map(|s| (s.get_ref(), s.span())) {
            None => State::rest(&model),
            Some((StateSource::Path(p), span)) => {
                let state_path = self.existing(&dir, p, span, "initial")?;
                let text =
                    std::fs::read_to_string(&state_path).map_err(|source| FileError::Read {
                        path: state_path.clone(),
                        source,
                    })?;
                let sf = satsim_tree::io::parse_state_file(&text, &state_path)?;
                warnings.extend(
                    sf.warnings()
                        .into_iter()
                        .map(|w| format!("{}: {w}", state_path.display())),
                );
                sf.resolve(&model).map_err(|e| e.in_file(&state_path))?
            }
            Some((StateSource::Inline(s), span)) => {
                warnings.extend(s.warnings().into_iter().map(|w| {
                    format!(
                        "{}:{}: initial.{w}",
                        self.path.display(),
                        line_of(self.text, span.start)
                    )
                }));
                s.resolve(&model).map_err(|e| {
                    self.err(Some(span), format!("initial.{}: {}", e.field, e.message))
                })?
            }
        };

        let duration = self.positive(&file.duration, "duration")?;
        let options = self.integrator(file.integrator.as_ref())?;
        let (every, plots, view) = match &file.output {
            None => (duration / 100.0, true, true),
            Some(o) => {
                let o = o.get_ref();
                let every = match &o.every {
                    Some(e) => self.positive(e, "output.every")?,
                    None => duration / 100.0,
                };
                (every, o.plots.unwrap_or(true), o.view.unwrap_or(true))
            }
        };
        let mut effects = EffectSet::default();
        if let Some(o) = &file.orbit {
            effects.orbit = Some(self.orbit(o)?);
        }
        if let Some(e) = &file.effects {
            self.effects(e.get_ref(), &model, &mut effects)?;
            self.check_needs(&file, e.get_ref(), &effects)?;
        }
        let scene = Scene {
            path,
            model,
            initial,
            duration,
            options,
            every,
            plots,
            view,
            effects,
            warnings,
        };
        // Build once to surface any remaining setup error with the scene's name.
        scene
            .simulation()
            .map_err(|e| self.err(None, e.to_string()))?;
        Ok(scene)
    }

    /// The model with the scene's `armature` on its hinges.
    fn armature(&self, model: Model, a: &Spanned<ArmatureFile>) -> Result<Model, FileError> {
        let n = model.n_hinges();
        let values = match a.get_ref() {
            ArmatureFile::All(v) => vec![*v; n],
            ArmatureFile::PerHinge(v) if v.len() == n => v.clone(),
            ArmatureFile::PerHinge(v) => {
                return Err(self.err(
                    Some(a.span()),
                    format!(
                        "`armature`: expected {n} entries (one per hinge, file order), got {}",
                        v.len()
                    ),
                ));
            }
        };
        if let Some(v) = values.iter().find(|v| !(**v >= 0.0 && v.is_finite())) {
            return Err(self.err(
                Some(a.span()),
                format!("`armature` must be finite numbers >= 0 (kg m²), got {v}"),
            ));
        }
        // A built model never changes: the armature goes through the builder (which also
        // stops treating a rotor with armature as a gyrostat).
        let mut builder = model.to_builder();
        for (hinge, v) in builder.hinges_mut().iter_mut().zip(values) {
            hinge.armature = v;
        }
        builder
            .build()
            .map_err(|e| self.err(Some(a.span()), format!("`armature`: {e}")))
    }

    fn integrator(&self, f: Option<&Spanned<IntegratorFile>>) -> Result<Options, FileError> {
        let Some(f) = f else {
            return Ok(Options::new(Method::Dp54)
                .with_tolerances(1e-9, 1e-12)
                .with_max_steps(10_000_000));
        };
        let i = f.get_ref();
        let method = match &i.method {
            None => Method::Dp54,
            Some(m) => m
                .get_ref()
                .parse::<Method>()
                .map_err(|e| self.err(Some(m.span()), format!("`integrator.method`: {e}")))?,
        };
        let mut o = Options::new(method).with_max_steps(10_000_000);
        let rtol = match &i.rtol {
            Some(r) => self.non_negative(r, "integrator.rtol")?,
            None => 1e-9,
        };
        let atol = match &i.atol {
            Some(a) => self.non_negative(a, "integrator.atol")?,
            None => 1e-12,
        };
        if rtol == 0.0 && atol == 0.0 {
            return Err(self.err(
                Some(f.span()),
                "`integrator.rtol` and `integrator.atol` cannot both be 0",
            ));
        }
        o = o.with_tolerances(rtol, atol);
        match (&i.step, method) {
            (Some(s), Method::Rk4) => o = o.with_fixed_step(self.positive(s, "integrator.step")?),
            (Some(s), _) => o = o.with_h0(self.positive(s, "integrator.step")?),
            (None, Method::Rk4) => {
                return Err(self.err(
                    Some(f.span()),
                    "`integrator.step` is required by the fixed-step method rk4",
                ));
            }
            (None, _) => {}
        }
        if let Some(h) = &i.max_step {
            o = o.with_h_max(self.positive(h, "integrator.max_step")?);
        }
        if let Some(n) = &i.max_steps {
            if *n.get_ref() <= 0 {
                return Err(self.err(Some(n.span()), "`integrator.max_steps` must be > 0"));
            }
            o = o.with_max_steps(*n.get_ref() as usize);
        }
        Ok(o)
    }

    fn orbit(&self, o: &Spanned<OrbitFile>) -> Result<Orbit, FileError> {
        let span = Some(o.span());
        let f = o.get_ref();
        let model = match f.model.as_ref().map(|m| (m.get_ref().as_str(), m.span())) {
            None | Some(("kepler", _)) => OrbitModel::Kepler,
            Some(("j2", _)) => OrbitModel::J2,
            Some((other, s)) => {
                return Err(self.err(
                    Some(s),
                    format!(
                        "`orbit.model`: unknown value `{other}`, expected \"kepler\" or \"j2\""
                    ),
                ));
            }
        };
        let vec = |v: Option<[f64; 3]>, k: usize| v.map(|v| v[k]);
        self.check_numbers(
            o.span(),
            "orbit.",
            &[
                ("inclination_deg", f.inclination_deg, false),
                ("raan_deg", f.raan_deg, false),
                ("arg_periapsis_deg", f.arg_periapsis_deg, false),
                ("true_anomaly_deg", f.true_anomaly_deg, false),
                ("j2", f.j2, false),
                ("position", vec(f.position, 0), false),
                ("position", vec(f.position, 1), false),
                ("position", vec(f.position, 2), false),
                ("velocity", vec(f.velocity, 0), false),
                ("velocity", vec(f.velocity, 1), false),
                ("velocity", vec(f.velocity, 2), false),
            ],
        )?;
        for (key, v) in [("mu", f.mu), ("radius", f.radius)] {
            if let Some(v) = v
                && !(v > 0.0 && v.is_finite())
            {
                return Err(self.err(
                    Some(o.span()),
                    format!("`orbit.{key}` must be a finite number > 0, got {v}"),
                ));
            }
        }
        let mut orbit = Orbit::new(model, Vec3::zeros(), Vec3::zeros());
        if let Some(mu) = f.mu {
            orbit.mu = mu;
        }
        if let Some(j2) = f.j2 {
            orbit.j2 = j2;
        }
        if let Some(r) = f.radius {
            orbit.radius = r;
        }
        let has_elements = f.altitude.is_some() || f.semi_major_axis.is_some();
        match (has_elements, f.position, f.velocity) {
            (false, Some(r), Some(v)) => {
                orbit.r0 = Vec3::from(r);
                orbit.v0 = Vec3::from(v);
                if orbit.r0.norm().is_nan() || orbit.r0.norm() <= orbit.radius * 0.5 {
                    return Err(self.err(span, "`orbit.position` is inside the Earth"));
                }
                let h = orbit.r0.norm() - orbit.radius;
                if h < MIN_ALTITUDE {
                    return Err(self.err(
                        span,
                        format!(
                            "`orbit.position` is {h:.0} m above `radius`, below 100 km (no orbit lasts there); positions are in metres (7e6, not 7000)"
                        ),
                    ));
                }
            }
            (true, None, None) => {
                let a = match (&f.altitude, &f.semi_major_axis) {
                    (Some(h), None) => {
                        let v = self.positive(h, "orbit.altitude")?;
                        if v < MIN_ALTITUDE {
                            return Err(self.err(
                                Some(h.span()),
                                format!(
                                    "`orbit.altitude` is {v} m, below 100 km (no orbit lasts there); altitudes are in metres: for {v} km write `altitude = {v}e3`"
                                ),
                            ));
                        }
                        orbit.radius + v
                    }
                    (None, Some(a)) => self.positive(a, "orbit.semi_major_axis")?,
                    _ => {
                        return Err(self.err(
                            span,
                            "give `orbit.altitude` or `orbit.semi_major_axis`, not both",
                        ));
                    }
                };
                let e = match &f.eccentricity {
                    Some(e) => {
                        let v = self.non_negative(e, "orbit.eccentricity")?;
                        if v >= 1.0 {
                            return Err(
                                self.err(Some(e.span()), "`orbit.eccentricity` must be < 1")
                            );
                        }
                        v
                    }
                    None => 0.0,
                };
                let el = Elements {
                    a,
                    e,
                    i: f.inclination_deg.unwrap_or(0.0).to_radians(),
                    raan: f.raan_deg.unwrap_or(0.0).to_radians(),
                    argp: f.arg_periapsis_deg.unwrap_or(0.0).to_radians(),
                    nu: f.true_anomaly_deg.unwrap_or(0.0).to_radians(),
                };
                if a * (1.0 - e) < orbit.radius {
                    return Err(self.err(
                        span,
                        format!(
                            "the orbit's periapsis ({:.0} m) is inside the Earth",
                            a * (1.0 - e)
                        ),
                    ));
                }
                let hp = a * (1.0 - e) - orbit.radius;
                if hp < MIN_ALTITUDE {
                    return Err(self.err(
                        span,
                        format!(
                            "the orbit's periapsis altitude ({hp:.0} m) is below 100 km (no orbit lasts there); lengths are in metres (`semi_major_axis = 6878e3` for 500 km)"
                        ),
                    ));
                }
                let (r, v) = el.to_cartesian(orbit.mu);
                orbit.r0 = r;
                orbit.v0 = v;
            }
            _ => {
                return Err(self.err(span, "[orbit] needs either `altitude` or `semi_major_axis` (with optional elements), or both `position` and `velocity`"));
            }
        }
        Ok(orbit)
    }

    fn hinge_index(&self, model: &Model, name: &Spanned<String>) -> Result<usize, FileError> {
        model.hinge_index(name.get_ref()).ok_or_else(|| {
            self.err(
                Some(name.span()),
                format!(
                    "unknown hinge `{}` (the model's hinges: {})",
                    name.get_ref(),
                    model.hinge_names().join(", ")
                ),
            )
        })
    }

    fn per_hinge(
        &self,
        model: &Model,
        x: &Spanned<Vec<f64>>,
        what: &str,
    ) -> Result<Vec<f64>, FileError> {
        let n = model.n_hinges();
        if x.get_ref().len() != n {
            return Err(self.err(
                Some(x.span()),
                format!(
                    "`{what}`: expected {n} entries (one per hinge, file order), got {}",
                    x.get_ref().len()
                ),
            ));
        }
        if x.get_ref().iter().any(|v| !v.is_finite()) {
            return Err(self.err(Some(x.span()), format!("`{what}`: entries must be finite")));
        }
        Ok(x.get_ref().clone())
    }

    fn effects(
        &self,
        f: &EffectsFile,
        model: &Model,
        out: &mut EffectSet,
    ) -> Result<(), FileError> {
        let on = |e: Option<bool>| e.unwrap_or(true);
        if let Some(g) = f
            .gravity_gradient
            .as_ref()
            .filter(|g| on(g.get_ref().enabled))
        {
            let m = match g
                .get_ref()
                .model
                .as_ref()
                .map(|m| (m.get_ref().as_str(), m.span()))
            {
                None | Some(("preprint", _)) => GravityModel::Preprint,
                Some(("full", _)) => GravityModel::Full,
                Some((other, s)) => {
                    return Err(self.err(Some(s), format!("`effects.gravity_gradient.model`: unknown value `{other}`, expected \"preprint\" or \"full\"")));
                }
            };
            out.gravity_gradient = Some(GravityGradient::new(m));
        }
        if let Some(s) = f.hinge_springs.as_ref().filter(|s| on(s.get_ref().enabled)) {
            let s = s.get_ref();
            let n = model.n_hinges();
            let stiffness =
                self.per_hinge(model, &s.stiffness, "effects.hinge_springs.stiffness")?;
            let damping = match &s.damping {
                Some(d) => self.per_hinge(model, d, "effects.hinge_springs.damping")?,
                None => vec![0.0; n],
            };
            let reference = match &s.reference {
                Some(r) => self.per_hinge(model, r, "effects.hinge_springs.reference")?,
                None => vec![0.0; n],
            };
            out.hinge_springs = Some(HingeSprings {
                stiffness,
                damping,
                reference,
            });
        }
        if let Some(c) = f.hinge_control.as_ref().filter(|c| on(c.get_ref().enabled)) {
            let mut hinges = Vec::new();
            for h in &c.get_ref().hinge {
                let hf = h.get_ref();
                let hinge = self.hinge_index(model, &hf.name)?;
                self.check_numbers(
                    h.span(),
                    "effects.hinge_control.hinge.",
                    &[
                        ("start", Some(hf.start), false),
                        ("end", Some(hf.end), false),
                        ("t_start", hf.t_start, false),
                        ("kp", Some(hf.kp), true),
                        ("kd", hf.kd, true),
                    ],
                )?;
                if hinges.iter().any(|p: &HingeProfile| p.hinge == hinge) {
                    return Err(self.err(
                        Some(h.span()),
                        format!("hinge `{}` is controlled twice", hf.name.get_ref()),
                    ));
                }
                let torque_limit = match &hf.torque_limit {
                    Some(t) => self.positive(t, "torque_limit")?,
                    None => f64::INFINITY,
                };
                hinges.push(HingeProfile {
                    hinge,
                    start: hf.start,
                    end: hf.end,
                    t_start: hf.t_start.unwrap_or(0.0),
                    duration: self.positive(&hf.duration, "duration")?,
                    kp: hf.kp,
                    kd: hf.kd.unwrap_or(0.0),
                    torque_limit,
                });
            }
            out.hinge_control = Some(HingeControl { hinges });
        }
        if let Some(s) = f.hinge_stops.as_ref().filter(|s| on(s.get_ref().enabled)) {
            let mut stops = Vec::new();
            for st in &s.get_ref().stop {
                let sf = st.get_ref();
                let hinge = self.hinge_index(model, &sf.hinge)?;
                self.check_numbers(
                    st.span(),
                    "effects.hinge_stops.stop.",
                    &[
                        ("lower", sf.lower, false),
                        ("upper", sf.upper, false),
                        ("min_rebound_rate", sf.min_rebound_rate, true),
                    ],
                )?;
                if sf.lower.is_none() && sf.upper.is_none() {
                    return Err(self.err(Some(st.span()), "a stop needs `lower`, `upper` or both"));
                }
                if let (Some(l), Some(u)) = (sf.lower, sf.upper)
                    && l >= u
                {
                    return Err(self.err(Some(st.span()), "`lower` must be below `upper`"));
                }
                let action = match sf.action.as_ref().map(|a| (a.get_ref().as_str(), a.span())) {
                    None | Some(("latch", _)) => StopAction::Latch,
                    Some(("rebound", _)) => {
                        let e = match &sf.restitution {
                            Some(e) => {
                                let v = self.non_negative(e, "restitution")?;
                                if v > 1.0 {
                                    return Err(
                                        self.err(Some(e.span()), "`restitution` must be in [0, 1]")
                                    );
                                }
                                v
                            }
                            None => 0.5,
                        };
                        StopAction::Rebound { restitution: e }
                    }
                    Some((other, sp)) => {
                        return Err(self.err(Some(sp), format!("`action`: unknown value `{other}`, expected \"latch\" or \"rebound\"")));
                    }
                };
                stops.push(HingeStop {
                    hinge,
                    lower: sf.lower,
                    upper: sf.upper,
                    action,
                    min_rebound_rate: sf.min_rebound_rate.unwrap_or(1e-3),
                });
            }
            out.hinge_stops = Some(HingeStops::new(stops));
        }
        if let Some(w) = f
            .reaction_wheels
            .as_ref()
            .filter(|w| on(w.get_ref().enabled))
        {
            let mut wheels: Vec<Wheel> = Vec::new();
            for wf in &w.get_ref().wheel {
                let span = Some(wf.span());
                let f = wf.get_ref();
                let name = f.name.get_ref().clone();
                let at = |k: usize| f.at.map(|a| a[k]);
                self.check_numbers(
                    wf.span(),
                    "effects.reaction_wheels.wheel.",
                    &[
                        ("transverse", f.transverse, true),
                        ("at", at(0), false),
                        ("at", at(1), false),
                        ("at", at(2), false),
                        ("coulomb", f.coulomb, true),
                        ("stribeck", f.stribeck, true),
                        ("viscous", f.viscous, true),
                        ("speed", f.speed, false),
                        ("torque", f.torque, false),
                    ],
                )?;
                if wheels.iter().any(|o| o.name == name) {
                    return Err(self.err(
                        Some(f.name.span()),
                        format!("duplicate wheel name `{name}`"),
                    ));
                }
                let axis = Vec3::from(*f.axis.get_ref());
                if !axis.iter().all(|x| x.is_finite()) || axis.norm() <= 1e-9 {
                    return Err(self.err(
                        Some(f.axis.span()),
                        "`axis` must be a non-zero finite vector",
                    ));
                }
                let inertia = self.positive(&f.inertia, "inertia")?;
                let mut wheel = Wheel::new(name, axis, inertia);
                if let Some(t) = f.transverse {
                    if t < 0.5 * inertia * (1.0 - 1e-9) {
                        return Err(self.err(span, "`transverse` must be >= inertia / 2 (a rotor's moments obey the triangle inequality)"));
                    }
                    wheel.transverse = t;
                }
                let nn = |v: Option<f64>, what: &str, default: f64| -> Result<f64, FileError> {
                    match v {
                        Some(x) if x.is_nan() || x < 0.0 => {
                            Err(self.err(span.clone(), format!("`{what}` must be >= 0, got {x}")))
                        }
                        Some(x) => Ok(x),
                        None => Ok(default),
                    }
                };
                wheel.mass = nn(f.mass, "mass", 0.0)?;
                wheel.at = f.at.map(Vec3::from).unwrap_or_else(Vec3::zeros);
                wheel.max_torque = nn(f.max_torque, "max_torque", f64::INFINITY)?;
                wheel.max_speed = nn(f.max_speed, "max_speed", f64::INFINITY)?;
                wheel.coulomb = nn(f.coulomb, "coulomb", 0.0)?;
                wheel.stribeck = nn(f.stribeck, "stribeck", 0.0)?;
                wheel.viscous = nn(f.viscous, "viscous", 0.0)?;
                wheel.stribeck_speed = f.stribeck_speed.unwrap_or(1.0);
                if !(wheel.stribeck_speed.is_finite() && wheel.stribeck_speed > 0.0) {
                    return Err(self.err(span, "`stribeck_speed` must be a finite number > 0"));
                }
                wheel.speed = f.speed.unwrap_or(0.0);
                wheel.torque = f.torque.unwrap_or(0.0);
                wheels.push(wheel);
            }
            if wheels.is_empty() {
                return Err(self.err(Some(w.span()), "[effects.reaction_wheels] needs at least one [[effects.reaction_wheels.wheel]]"));
            }
            out.reaction_wheels = Some(ReactionWheels::new(wheels));
        }
        if let Some(a) = f
            .attitude_control
            .as_ref()
            .filter(|a| on(a.get_ref().enabled))
        {
            let af = a.get_ref();
            self.check_numbers(
                a.span(),
                "effects.attitude_control.",
                &[("kp", Some(af.kp), true), ("kd", Some(af.kd), true)],
            )?;
            let q = match &af.attitude {
                Some(q) => {
                    let [w, x, y, z] = *q.get_ref();
                    let quat = Quaternion::new(w, x, y, z);
                    if (quat.norm() - 1.0).abs().is_nan() || (quat.norm() - 1.0).abs() > 1e-6 {
                        return Err(self.err(
                            Some(q.span()),
                            format!("`attitude`: quaternion norm {} is not 1", quat.norm()),
                        ));
                    }
                    UnitQuaternion::from_quaternion(quat)
                }
                None => UnitQuaternion::identity(),
            };
            let target = match af.target.as_ref().map(|t| (t.get_ref().as_str(), t.span())) {
                None | Some(("inertial", _)) => Target::Inertial(q),
                Some(("orbital", _)) => Target::Orbital(q),
                Some((other, s)) => {
                    return Err(self.err(Some(s), format!("`target`: unknown value `{other}`, expected \"inertial\" or \"orbital\"")));
                }
            };
            let axes: Vec<Vec3> = out
                .reaction_wheels
                .as_ref()
                .map(|w| w.wheels.iter().map(|w| w.axis).collect())
                .unwrap_or_default();
            out.attitude_control = Some(AttitudeControl::new(target, af.kp, af.kd, &axes));
        }
        Ok(())
    }

    fn check_needs(
        &self,
        file: &SceneFile,
        f: &EffectsFile,
        e: &EffectSet,
    ) -> Result<(), FileError> {
        if file.orbit.is_none() {
            if let (Some(g), Some(_)) = (&f.gravity_gradient, &e.gravity_gradient) {
                return Err(self.err(Some(g.span()), "effects.gravity_gradient needs an [orbit] table (e.g. `[orbit]` with `altitude = 500e3`)"));
            }
            if let (
                Some(a),
                Some(AttitudeControl {
                    target: Target::Orbital(_),
                    ..
                }),
            ) = (&f.attitude_control, &e.attitude_control)
            {
                return Err(self.err(
                    Some(a.span()),
                    "effects.attitude_control with target = \"orbital\" needs an [orbit] table",
                ));
            }
        }
        if let (Some(a), Some(_), None) =
            (&f.attitude_control, &e.attitude_control, &e.reaction_wheels)
        {
            return Err(self.err(Some(a.span()), "effects.attitude_control needs [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]] to command"));
        }
        Ok(())
    }
}

/// Rewords serde's messages in the file's vocabulary.
fn reword(m: &str) -> String {
    let m = m.trim_end().replace("expected f64", "expected a number");
    if let Some(rest) = m.strip_prefix("unknown field ") {
        format!("unknown key {rest}")
    } else if let Some(rest) = m.strip_prefix("missing field ") {
        format!("missing required key {rest}")
    } else {
        m
    }
}
