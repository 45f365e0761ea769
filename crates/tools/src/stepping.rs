//! A scene stepped from the caller's code ("flight software in the loop"): [`SceneStepper`],
//! what `satsim.Simulation` wraps.
//!
//! The scene's simulation is advanced a piece at a time with the scene's integrator
//! ([`Stepping`], whose documentation states the contract), inputs held between pieces.
//! Rows are recorded as `satsim run` records them ([`api::run_scene`](crate::api::run_scene)):
//! at `t0 + i · output.every` (the row at `t0 + duration` included, snapped to it as a run
//! does, and the grid continued past it), kept in memory and, with an output folder,
//! streamed to `DIR/trajectory.csv` by the same writer. The rows kept in memory are bounded
//! as a run's are ([`SceneStepper::max_rows`], default [`DEFAULT_MAX_ROWS`]): an `advance`
//! that would keep more is refused before it integrates, so memory never grows with `dt`
//! or with the time stepped past the scene's end. [`SceneStepper::close`] then writes
//! the rest of what `satsim run` writes there: `events.csv`, the plots the scene asks for
//! and `view.html` when the scene has the view on.

use crate::api::Trajectory;
use crate::output::{CsvWriter, PlotRecorder, write_events};
use crate::scene::step_limit::{held_steps_message, may_be_held, stable_step};
use crate::scene::{DEFAULT_MAX_ROWS, Scene};
use crate::view::PoseRecorder;
use satsim_integrate::Options;
use satsim_spacecraft::sensors::Sensors;
use satsim_spacecraft::simulation::{EventRecord, OutputGrid, SimError, StepError, Stepping};
use satsim_tree::error::{Count, Num};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Why a [`SceneStepper`] call failed.
#[derive(Debug)]
pub enum StepFailure {
    /// Bad input (an unknown input, a non-finite value, a bad `dt`): nothing changed.
    Input(String),
    /// The simulation could not be set up, the integration failed, or an output could not
    /// be written.
    Failed(String),
}

impl fmt::Display for StepFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StepFailure::Input(m) | StepFailure::Failed(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for StepFailure {}

impl<E: fmt::Display> From<StepError<E>> for StepFailure {
    fn from(e: StepError<E>) -> Self {
        match e {
            StepError::Input(m) => StepFailure::Input(m),
            other => StepFailure::Failed(other.to_string()),
        }
    }
}

/// Where rows are streamed: `DIR/trajectory.csv`, and what `close` writes beside it.
struct OutDir {
    dir: PathBuf,
    csv: CsvWriter,
    plots: Option<PlotRecorder>,
    poses: Option<PoseRecorder>,
}

/// A scene stepped from the caller's code: see the module documentation.
pub struct SceneStepper {
    stepping: Stepping,
    options: Options,
    trajectory: Trajectory,
    out: Option<OutDir>,
    closed: bool,
    max_rows: u64,
    /// Each sensor's name and kind (`gyro`, `star_tracker`, ...), in the scene's order.
    sensors: Vec<(String, &'static str)>,
    /// The scene, where its method is explicit and adaptive (its steps may be held by a
    /// stiff motion: [`SceneStepper::warnings`]), and that motion's stability limit once
    /// worked out.
    explicit: Option<Box<Scene>>,
    limit: OnceLock<Option<(f64, String)>>,
}

impl SceneStepper {
    /// The scene's simulation at its initial state, rows on the scene's output grid; with
    /// `out`, `out/trajectory.csv` is created now (its header and the first row) and
    /// streamed to. `title` names the scene in `view.html`.
    pub fn new(scene: &Scene, out: Option<&Path>, title: &str) -> Result<Self, StepFailure> {
        Self::with_seed(scene, out, title, None)
    }

    /// [`SceneStepper::new`] with the sensors' noise drawn from `seed` instead of the scene's
    /// `[sensors] seed` (when given; a scene without sensors ignores it).
    pub fn with_seed(
        scene: &Scene,
        out: Option<&Path>,
        title: &str,
        seed: Option<u64>,
    ) -> Result<Self, StepFailure> {
        let mut effects = scene.effects.clone();
        if let (Some(seed), Some(s)) = (seed, effects.get_mut::<Sensors>()) {
            s.set_seed(seed);
        }
        let sensors = effects.get::<Sensors>().map_or_else(Vec::new, |s| {
            s.sensors()
                .iter()
                .map(|x| (x.name().to_owned(), x.kind().name()))
                .collect()
        });
        let scene = &Scene {
            effects,
            ..scene.clone()
        };
        let sim = scene
            .simulation()
            .map_err(|e: SimError| StepFailure::Failed(e.to_string()))?;
        let grid = OutputGrid {
            t0: sim.t0(),
            every: scene.every,
            t_end: sim.t0() + scene.duration,
        };
        let columns = sim.columns();
        let out = match out {
            None => None,
            Some(dir) => {
                std::fs::create_dir_all(dir).map_err(|e| {
                    StepFailure::Failed(format!(
                        "cannot create the output folder {}: {e}",
                        dir.display()
                    ))
                })?;
                let path = dir.join("trajectory.csv");
                let csv = CsvWriter::create(&path, &columns).map_err(|e| {
                    StepFailure::Failed(format!("cannot write {}: {e}", path.display()))
                })?;
                let poses = match scene.view {
                    true => Some(
                        PoseRecorder::new(sim.model(), &columns, title)
                            .and_then(|r| match sim.flex_model() {
                                Some(f) => r.with_flexible(f, &columns),
                                None => Ok(r),
                            })
                            .and_then(|r| {
                                r.with_rotors(sim.model().n_hinges() - sim.layout().n_hinges)
                            })
                            .map_err(|e| StepFailure::Failed(e.to_string()))?,
                    ),
                    false => None,
                };
                Some(OutDir {
                    dir: dir.to_path_buf(),
                    csv,
                    plots: scene.plots.then(|| PlotRecorder::new(&columns)),
                    poses,
                })
            }
        };
        let mut stepper = Self {
            stepping: Stepping::new(sim, grid),
            options: scene.options.clone(),
            trajectory: Trajectory {
                columns,
                values: Vec::new(),
            },
            out,
            closed: false,
            max_rows: DEFAULT_MAX_ROWS,
            sensors,
            explicit: scene
                .options
                .method
                .is_explicit_adaptive()
                .then(|| Box::new(scene.clone())),
            limit: OnceLock::new(),
        };
        stepper.record_start()?;
        Ok(stepper)
    }

    /// The most rows kept ([`SceneStepper::trajectory`]), the first included.
    pub fn max_rows(&self) -> u64 {
        self.max_rows
    }
    /// Sets [`SceneStepper::max_rows`] (at least 1: the row at the start is kept already).
    pub fn set_max_rows(&mut self, max_rows: u64) {
        self.max_rows = max_rows.max(1);
    }

    /// Records the row at the start (the first output time), as a run's first row.
    fn record_start(&mut self) -> Result<(), StepFailure> {
        let mut row = Vec::new();
        self.stepping
            .row(&mut row)
            .map_err(|e| StepFailure::Failed(e.to_string()))?;
        Self::record(&mut self.trajectory, &mut self.out, &row)?;
        self.stepping.skip_outputs_until_now();
        Ok(())
    }

    fn record(
        trajectory: &mut Trajectory,
        out: &mut Option<OutDir>,
        row: &[f64],
    ) -> Result<(), StepFailure> {
        trajectory.values.extend_from_slice(row);
        if let Some(o) = out {
            o.csv.row(row).map_err(|e| {
                StepFailure::Failed(format!(
                    "cannot write {}: {e}",
                    o.dir.join("trajectory.csv").display()
                ))
            })?;
            if let Some(p) = o.plots.as_mut() {
                p.push(row);
            }
            if let Some(p) = o.poses.as_mut() {
                p.record(row)
                    .map_err(|e| StepFailure::Failed(e.to_string()))?;
            }
        }
        Ok(())
    }

    /// What `satsim run` warns of after a run, for the steps taken so far
    /// ([`after_run_warnings`](crate::api::after_run_warnings)): a flexible body bent beyond
    /// what its modal model holds, an energy budget that did not close, and an explicit
    /// method's steps held by a stiff motion. The last weighs the steps the integrator set,
    /// not those cut to end a piece ([`Stepping::steps`], [`held`](crate::scene::step_limit::held)):
    /// pieces shorter than about the stability limit are the caller's steps, which Radau IIA
    /// would take as they are.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = self.stepping.simulation().run_warnings();
        if let Some(scene) = &self.explicit {
            let steps = self.stepping.steps();
            if may_be_held(scene.options.method, steps.accepted) {
                let limit = self
                    .limit
                    .get_or_init(|| stable_step(scene, scene.options.method));
                if let Some(limit) = limit {
                    warnings.extend(held_steps_message(scene, &steps, limit));
                }
            }
        }
        warnings
    }

    /// The underlying [`Stepping`] (time, state, inputs, the simulation).
    pub fn stepping(&self) -> &Stepping {
        &self.stepping
    }
    /// The time (s).
    pub fn t(&self) -> f64 {
        self.stepping.t()
    }
    /// The trajectory's column names (as `trajectory.csv`'s header).
    pub fn columns(&self) -> &[String] {
        &self.trajectory.columns
    }
    /// The row at the current time (the truth), in [`SceneStepper::columns`]' order.
    pub fn row(&mut self) -> Result<Vec<f64>, StepFailure> {
        let mut row = Vec::new();
        self.stepping
            .row(&mut row)
            .map_err(|e| StepFailure::Failed(e.to_string()))?;
        Ok(row)
    }
    /// Every sensor's reading at the current time, `(name, values)` in the scene's order
    /// ([`Stepping::measure`]): gyro, Sun sensor, magnetometer `[x, y, z]`, star tracker
    /// `[w, x, y, z]`.
    pub fn measure(&mut self) -> Result<Vec<(String, Vec<f64>)>, StepFailure> {
        self.stepping
            .measure()
            .map_err(|e| StepFailure::Failed(e.to_string()))
    }
    /// Each sensor's name and kind (`gyro`, `star_tracker`, `sun_sensor`, `magnetometer`),
    /// in the scene's order (the order of [`SceneStepper::measure`]).
    pub fn sensors(&self) -> &[(String, &'static str)] {
        &self.sensors
    }
    /// The input names ([`Stepping::inputs`]).
    pub fn inputs(&self) -> &[String] {
        self.stepping.inputs()
    }
    /// Sets inputs by name, held until changed ([`Stepping::set_inputs`]); an unknown name
    /// or a non-finite value is a [`StepFailure::Input`] and sets nothing.
    pub fn set_inputs(&mut self, values: &[(&str, f64)]) -> Result<(), StepFailure> {
        self.check_open()?;
        self.stepping
            .set_inputs::<StepFailure>(values)
            .map_err(StepFailure::from)
    }
    /// Integrates from `t` to `t + dt` with the scene's integrator, recording the rows on the
    /// way; returns the events that fired. A `dt` that is not finite and > 0, or one whose
    /// rows would take the rows kept past [`SceneStepper::max_rows`], is a
    /// [`StepFailure::Input`] and changes nothing. Past the scene's end the rows go on, on
    /// the same grid.
    pub fn advance(&mut self, dt: f64) -> Result<Vec<EventRecord>, StepFailure> {
        self.check_open()?;
        if !(dt > 0.0 && dt.is_finite() && (self.t() + dt).is_finite()) {
            return Err(StepFailure::Input(format!(
                "dt must be a finite number > 0, got {dt}"
            )));
        }
        self.advance_to(self.t() + dt)
    }

    /// As [`SceneStepper::advance`], to the time `t_end` (after [`SceneStepper::t`]): a loop
    /// that advances to `t0 + i · period` lands on those instants exactly, where adding
    /// `period` again and again would drift by round-off.
    pub fn advance_to(&mut self, t_end: f64) -> Result<Vec<EventRecord>, StepFailure> {
        self.check_open()?;
        if !(t_end.is_finite() && t_end > self.t()) {
            return Err(StepFailure::Input(format!(
                "the end time must be a finite number after t = {}, got {t_end}",
                self.t()
            )));
        }
        let dt = t_end - self.t();
        let kept = self.trajectory.n_rows() as u64;
        let room = self.max_rows.saturating_sub(kept);
        let cap = usize::try_from(room).unwrap_or(usize::MAX - 1);
        if self.stepping.rows_in(&self.options, dt, cap) as u64 > room {
            let every = self.stepping.output_grid().every;
            return Err(StepFailure::Input(format!(
                "advancing by dt = {} s would record about {} rows (`output.every` = {} s), \
                 more than the {room} left of the limit of {} rows kept: advance by less, or \
                 raise `output.every` or the limit (`max_rows`)",
                Num(dt),
                Count((dt / every).floor().max(1.0)),
                Num(every),
                self.max_rows
            )));
        }
        let Self {
            stepping,
            options,
            trajectory,
            out,
            ..
        } = self;
        stepping
            .advance_to(options, t_end, |_, row| Self::record(trajectory, out, row))
            .map_err(|e| match e {
                StepError::Sink { error, .. } => error,
                other => StepFailure::from(other),
            })
    }
    /// The rows so far (as [`api::run_scene`](crate::api::run_scene) returns them).
    pub fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }
    /// Whether [`SceneStepper::close`] was called.
    pub fn is_closed(&self) -> bool {
        self.closed
    }
    fn check_open(&self) -> Result<(), StepFailure> {
        if self.closed {
            return Err(StepFailure::Input("the simulation is closed".into()));
        }
        Ok(())
    }
    /// Ends the simulation: with an output folder, flushes `trajectory.csv` and writes
    /// `events.csv`, the plots (when the scene asks for them) and `view.html` (when the
    /// scene's view is on), as `satsim run` does. Returns the files written. Calling it
    /// again does nothing.
    pub fn close(&mut self) -> Result<Vec<PathBuf>, StepFailure> {
        if self.closed {
            return Ok(Vec::new());
        }
        self.closed = true;
        let Some(mut o) = self.out.take() else {
            return Ok(Vec::new());
        };
        let io = |what: &Path, e: &dyn fmt::Display| {
            StepFailure::Failed(format!("cannot write {}: {e}", what.display()))
        };
        let csv_path = o.dir.join("trajectory.csv");
        o.csv.flush().map_err(|e| io(&csv_path, &e))?;
        let mut written = vec![csv_path];
        let events_path = o.dir.join("events.csv");
        write_events(&events_path, self.stepping.simulation().event_records())
            .map_err(|e| io(&events_path, &e))?;
        written.push(events_path);
        if let Some(p) = &o.plots
            && p.rows() > 0
        {
            let names = p.write(&o.dir).map_err(|e| io(&o.dir, &e))?;
            written.extend(names.into_iter().map(|n| o.dir.join(n)));
        }
        if let Some(p) = o.poses.take() {
            let path = p
                .finish(self.stepping.simulation().event_log())
                .write(&o.dir)
                .map_err(|e| StepFailure::Failed(format!("cannot write the 3-D view: {e}")))?;
            written.push(path);
        }
        Ok(written)
    }
}
