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
//!
//! Each `[effects.<name>]` section is read by the effect registered under that name
//! ([`satsim_spacecraft::effects::Registry`]; [`Scene::read`] knows the built-in ones,
//! [`Scene::read_with_registry`] a registry with a user's effects too); the reader here
//! handles the rest of the file:
//!
//! - [`file`](mod@file), the top level as written (serde structs);
//! - [`flexible`](mod@flexible), flexible bodies and their initial elastic state;
//! - [`parse`], the reader (model, initial state, armature, the effect sections);
//! - [`integrator`], the `[integrator]` table;
//! - [`orbit`], the `[orbit]` table;
//! - [`sensors`](mod@sensors), the `[sensors]` table;
//! - [`fsw`](mod@fsw), the `[fsw]` table (built-in flight software on the sensors);
//! - [`faults`](mod@faults), the `[[faults]]` (each handed to the effect that owns its
//!   target).

pub mod faults;
pub mod file;
pub mod flexible;
pub mod fsw;
pub mod integrator;
pub mod orbit;
pub mod parse;
pub mod sampled_loop;
pub mod sensors;
pub mod step_limit;

pub use file::OrbitFile;
pub use file::{ArmatureFile, IntegratorFile, ModelSource, OutputFile, SceneFile, StateSource};
pub use flexible::Elastic;
pub use orbit::MIN_ALTITUDE;
pub use satsim_spacecraft::effects::SceneText;

use crate::scene_keys::{self, Override};
use satsim_integrate::Options;
use satsim_spacecraft::effects::{EffectSet, Registry};
use satsim_spacecraft::simulation::{SimError, Simulation};
use satsim_tree::error::{Count, Num};
use satsim_tree::flexible::FlexModel;
use satsim_tree::io::FileError;
use satsim_tree::{Model, State};
use std::path::{Path, PathBuf};

/// A scene, read and checked.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file (for messages); `<inline>` for scenes built in code.
    pub path: PathBuf,
    /// The spacecraft (with flexible bodies, their rigid tree: `flexible`'s `rigid()`).
    pub model: Model,
    /// Its flexible bodies' modes (`[body.flexible]`), when it has any.
    pub flexible: Option<FlexModel>,
    /// Its initial state (the rigid coordinates).
    pub initial: State,
    /// Its initial elastic state (`[initial] flexible`), in `flexible`'s coordinate order;
    /// empty without flexible bodies.
    pub elastic: Elastic,
    /// Duration (s).
    pub duration: f64,
    /// t = 0 as a date (the scene's `epoch`), when it has one.
    pub epoch: Option<satsim_environment::Epoch>,
    /// Integrator options.
    pub options: Options,
    /// Whether the elastic coordinates count in the adaptive methods' error
    /// (`integrator.elastic_error`, default true; see
    /// [`SimulationBuilder::elastic_error`](satsim_spacecraft::simulation::SimulationBuilder::elastic_error)).
    pub elastic_error: bool,
    /// Seconds between output rows.
    pub every: f64,
    /// Draw SVG plots.
    pub plots: bool,
    /// Write the 3-D playback `view.html` (and `poses.csv`, `view.json`): see [`crate::view`].
    pub view: bool,
    /// Integrate the energy budget (two more states) and write its columns `work_actuators`,
    /// `energy_dissipated`, `energy_budget`: see [`satsim_spacecraft::simulation`].
    pub energy_budget: bool,
    /// The enabled effects (the orbit included): look one up by type,
    /// `scene.effects.get::<HingeSprings>()`.
    pub effects: EffectSet,
    /// The scene's sampled laws (its sensors, thrusters, controllers with a `period`), whose
    /// samples [`Scene::check_rows`] bounds.
    pub clocks: Vec<Clock>,
    /// What the reader accepted but the user should hear about (a nearly unit attitude
    /// quaternion normalised…), each naming the file; the command line prints them on
    /// standard error.
    pub warnings: Vec<String>,
}

/// A sampled law of a scene, as written: each of its samples is a stop of the integrator (a
/// step cut to land on it), so a tiny period holds a run for hours however few rows it writes.
#[derive(Clone, Debug, PartialEq)]
pub struct Clock {
    /// What samples, as a message names it (``sensor `gyro1` ``, `` `effects.thrusters` ``).
    pub what: String,
    /// The line of its `period` in the scene file.
    pub line: Option<usize>,
    /// The period (s, > 0).
    pub period: f64,
}

/// The most output rows a run writes unless told otherwise (`satsim run --max-rows`): about
/// 1 GB of `trajectory.csv` for the preprint satellite. A row costs a right-hand side and a
/// line of text whatever the step, so a tiny `output.every` is refused before the run starts
/// rather than filling the disk.
pub const DEFAULT_MAX_ROWS: u64 = 1_000_000;

impl Scene {
    /// The initial positions in the flexible tree's order: the rigid tree's `q`, then the
    /// elastic coordinates `η` (none for a rigid scene).
    pub fn initial_q(&self) -> Vec<f64> {
        self.initial
            .q
            .iter()
            .chain(&self.elastic.eta)
            .copied()
            .collect()
    }

    /// The initial velocities of the model with its flexible bodies: the model's `v`, then
    /// the elastic rates (as [`Scene::initial_q`]).
    pub fn initial_v(&self) -> Vec<f64> {
        self.initial
            .v
            .iter()
            .chain(&self.elastic.etadot)
            .copied()
            .collect()
    }

    /// How many rows a run writes: `t = 0, every, 2 every, …` and the end (counted as a
    /// float, since `duration / every` may exceed every integer type).
    pub fn output_rows(&self) -> f64 {
        let intervals = (self.duration / self.every).floor();
        let on_grid = intervals * self.every >= self.duration;
        intervals + if on_grid { 1.0 } else { 2.0 }
    }

    /// Refuses a scene whose run would write more than `max_rows` rows, naming
    /// `output.every`, the row count and the limit; or in which a sampled law ([`Clock`])
    /// would take more than `max_rows` samples, naming it, its line, the count and the limit
    /// (a sample costs at least a step, more than a row's right-hand side).
    pub fn check_rows(&self, max_rows: u64) -> Result<(), FileError> {
        let rows = self.output_rows();
        if rows <= max_rows as f64 {
            return self.check_samples(max_rows);
        }
        Err(FileError::Schema {
            path: self.path.clone(),
            line: None,
            message: format!(
                "`output.every` = {} s over `duration` = {} s makes {} rows, more than the limit of {max_rows}: raise `output.every` (at least {:.3e} s) or the limit (`--max-rows`)",
                Num(self.every),
                Num(self.duration),
                Count(rows),
                self.duration / (max_rows.max(2) - 1) as f64
            ),
        })
    }

    /// [`Scene::check_rows`]'s bound on each clock's samples: `t = 0, period, …` up to the
    /// duration.
    fn check_samples(&self, max: u64) -> Result<(), FileError> {
        for c in &self.clocks {
            let samples = (self.duration / c.period).floor() + 1.0;
            if samples > max as f64 {
                return Err(FileError::Schema {
                    path: self.path.clone(),
                    line: c.line,
                    message: format!(
                        "{}: `period` = {} s over `duration` = {} s makes {} samples, more than the limit of {max}: each sample is a stop of the integrator; raise the period (at least {:.3e} s) or the limit (`--max-rows`)",
                        c.what,
                        Num(c.period),
                        Num(self.duration),
                        Count(samples),
                        self.duration / (max.max(2) - 1) as f64
                    ),
                });
            }
        }
        Ok(())
    }

    /// A torque-free scene of `model` from `initial`, integrated by DP54 at the given
    /// tolerances, with rows every `duration / 100`. Add effects through [`Scene::effects`].
    pub fn new(model: Model, initial: State, duration: f64) -> Self {
        Self {
            path: PathBuf::from("<inline>"),
            model,
            flexible: None,
            initial,
            elastic: Elastic::default(),
            duration,
            epoch: None,
            options: integrator::default_options(),
            elastic_error: true,
            every: duration / 100.0,
            plots: true,
            view: true,
            energy_budget: true,
            effects: EffectSet::default(),
            clocks: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// A fresh [`Simulation`] with exactly the enabled effects (fresh copies of them, in the
    /// order their dependencies give, see [`satsim_spacecraft::effects::order`]).
    pub fn simulation(&self) -> Result<Simulation, SimError> {
        let mut b = Simulation::builder(self.model.clone());
        if let Some(f) = &self.flexible {
            b = b
                .flexible(f.clone())
                .elastic(self.elastic.eta.clone(), self.elastic.etadot.clone());
        }
        b.initial(self.initial.clone())
            .energy_budget(self.energy_budget)
            .elastic_error(self.elastic_error)
            .effects(&self.effects)
            .build()
    }

    /// Reads the scene file at `path`, with the built-in effects.
    pub fn read(path: impl AsRef<Path>) -> Result<Scene, FileError> {
        Scene::read_with_registry(path, &Registry::with_builtins())
    }

    /// Reads the scene file at `path`; its `[effects.<name>]` sections are looked up in
    /// `registry` (see [`satsim_spacecraft::effects::registry`]).
    pub fn read_with_registry(
        path: impl AsRef<Path>,
        registry: &Registry,
    ) -> Result<Scene, FileError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Scene::parse_with_registry(&text, path, registry)
    }

    /// Reads the scene file at `path` with `overrides` (`--set KEY=VALUE`, see
    /// [`crate::scene_keys`]) applied in order. With overrides, an error found in the
    /// rewritten scene names the scene file and says which overrides were applied.
    pub fn read_with(path: impl AsRef<Path>, overrides: &[Override]) -> Result<Scene, FileError> {
        Scene::read_overridden(path, overrides, &Registry::with_builtins())
    }

    /// [`Scene::read_with`] with the effects of `registry`.
    pub fn read_overridden(
        path: impl AsRef<Path>,
        overrides: &[Override],
        registry: &Registry,
    ) -> Result<Scene, FileError> {
        Scene::read_as(path.as_ref(), overrides, registry, true)
    }

    /// [`Scene::read_with`] for a linearisation (`satsim modes`, `satsim linearize`), which
    /// integrates nothing: a fixed `integrator.step` is not checked against the scene's
    /// linear motions (RK4's stability) or `max_steps`, so a scene whose step is too long
    /// for its modes can still have them listed.
    pub fn read_to_linearise(
        path: impl AsRef<Path>,
        overrides: &[Override],
    ) -> Result<Scene, FileError> {
        Scene::read_as(path.as_ref(), overrides, &Registry::with_builtins(), false)
    }

    /// [`Scene::parse`] for a linearisation ([`Scene::read_to_linearise`]).
    pub fn parse_to_linearise(text: &str, path: &Path) -> Result<Scene, FileError> {
        Scene::parse_as(text, path, &Registry::with_builtins(), false)
    }

    fn read_as(
        path: &Path,
        overrides: &[Override],
        registry: &Registry,
        integrates: bool,
    ) -> Result<Scene, FileError> {
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        if overrides.is_empty() {
            return Scene::parse_as(&text, path, registry, integrates);
        }
        let rewritten = scene_keys::overridden_text(&text, path, overrides)?;
        let mut scene = Scene::parse_as(&rewritten, path, registry, integrates)
            .map_err(|e| scene_keys::relocate(e, &text, path, &rewritten, overrides))?;
        // A line of the rewritten text means nothing to the user: name where it was written.
        if !scene.warnings.is_empty() || !scene.clocks.is_empty() {
            let origins = scene_keys::Origins::new(&text, path, &rewritten);
            for w in &mut scene.warnings {
                *w = origins.warning(w);
            }
            for c in &mut scene.clocks {
                c.line = c.line.and_then(|l| origins.place(l).1);
            }
        }
        Ok(scene)
    }

    /// Parses a scene's text; `path` names it in errors and anchors its relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, FileError> {
        Scene::parse_with_registry(text, path, &Registry::with_builtins())
    }

    /// A campaign's drawn run: [`Scene::parse`] without the warnings that take time to work
    /// out (whether each sampled law is stable at its period), which a drawn run does not
    /// print (the nominal scene's are). Its errors are [`Scene::parse`]'s.
    pub(crate) fn parse_drawn(text: &str, path: &Path) -> Result<Scene, FileError> {
        parse::Parser::new(SceneText::new(text, path), &Registry::with_builtins())
            .without_advice()
            .scene()
    }

    /// [`Scene::parse`] with the effects of `registry`.
    pub fn parse_with_registry(
        text: &str,
        path: &Path,
        registry: &Registry,
    ) -> Result<Scene, FileError> {
        parse::Parser::new(SceneText::new(text, path), registry).scene()
    }

    fn parse_as(
        text: &str,
        path: &Path,
        registry: &Registry,
        integrates: bool,
    ) -> Result<Scene, FileError> {
        let parser = parse::Parser::new(SceneText::new(text, path), registry);
        if integrates {
            parser.scene()
        } else {
            parser.for_linearisation().scene()
        }
    }
}
