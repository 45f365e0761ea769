//! Campaigns stepped by the user's flight software (contract section 15): the native half
//! of `satsim.campaign(scene, controller=..., period=...)`.
//!
//! - [`NativeCampaign`]: a scene with a `[campaign]` table, read once per process; draws
//!   run `k`'s values and seed, and makes run `k` with the user's controller stepping it
//!   ([`Campaign::run_stepped`]): at each control instant the controller's
//!   `step(t, measurements, row)` is called from here (no Python loop: the dicts are built
//!   from interned keys, the inputs it returns set at once) and the rows are reduced to
//!   the record `satsim campaign` makes.
//! - [`NativeFolder`]: the campaign folder ([`Folder`]): opened (fresh or resumed) by the
//!   process that writes it, records appended as they come from any worker, finished.
//!
//! A record crosses processes as a plain tuple ([`Rec`]), pickled bit for bit, so the files
//! are the same whatever made the runs.

use crate::{RunOut, err, to_python};
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use satsim_tools::campaign::stepped::{Stepped, Tick};
use satsim_tools::campaign::{Campaign, CampaignError, Folder, RunRecord, RunStats, Shard};
use satsim_tools::stepping::SceneStepper;
use std::path::PathBuf;
use std::sync::Mutex;

/// A run's record as a tuple: `(k, values, failure, last, min, max, peaks, held, trace,
/// metrics)`; `failure` is `None` for a finished run (then `last`, `min`, `max`, `peaks` and
/// `held` are its statistics), else why it failed. The metrics come last: the Python side replaces
/// them.
type Rec = (
    u64,
    Vec<f64>,
    Option<String>,
    Vec<f64>,
    Vec<f64>,
    Vec<f64>,
    Vec<f64>,
    bool,
    Vec<Vec<f64>>,
    Vec<(String, f64)>,
);

fn to_rec(r: RunRecord) -> Rec {
    let (failure, stats) = match r.outcome {
        Ok(s) => (None, Some(s)),
        Err(why) => (Some(why), None),
    };
    let (last, min, max, peaks, held) = stats.map_or_else(Default::default, |s| {
        (s.last, s.min, s.max, s.peaks, s.held)
    });
    (
        r.k, r.values, failure, last, min, max, peaks, held, r.trace, r.metrics,
    )
}

fn from_rec(r: Rec) -> RunRecord {
    let (k, values, failure, last, min, max, peaks, held, trace, metrics) = r;
    RunRecord {
        k,
        values,
        outcome: match failure {
            None => Ok(RunStats {
                last,
                min,
                max,
                peaks,
                held,
            }),
            Some(why) => Err(why),
        },
        trace,
        metrics,
    }
}

/// A scene with a `[campaign]` table, read and checked (`satsim campaign`'s reader).
#[pyclass(module = "satsim._satsim", name = "NativeCampaign", frozen)]
pub(crate) struct NativeCampaign {
    c: Campaign,
}

/// The exception's last line, as a traceback ends: `ValueError: boom` (line breaks as
/// spaces: it goes into one CSV field).
fn last_line(py: Python<'_>, e: &PyErr) -> String {
    let name = e
        .get_type(py)
        .name()
        .map_or_else(|_| "Exception".to_owned(), |n| n.to_string());
    let text = e
        .value(py)
        .str()
        .map_or_else(|_| String::new(), |s| s.to_string());
    let text = text.trim().replace(['\n', '\r'], " ");
    if text.is_empty() {
        name
    } else {
        format!("{name}: {text}")
    }
}

/// The keys of `measure()`'s dict for one sensor: its name, then one per value (as
/// `satsim.Simulation.measure`: `_q_w`.. for a star tracker's quaternion, `_x`.. `_vz` for a
/// GPS's position and velocity, `_x`.. for a vector, none for a single value).
fn sensor_keys<'py>(py: Python<'py>, name: &str, n: usize) -> Vec<Bound<'py, PyString>> {
    let suffixes: &[&str] = match n {
        1 => &[],
        4 => &["_q_w", "_q_x", "_q_y", "_q_z"],
        6 => &["_x", "_y", "_z", "_vx", "_vy", "_vz"],
        _ => &["_x", "_y", "_z"],
    };
    let mut keys = vec![PyString::intern(py, name)];
    keys.extend(
        suffixes
            .iter()
            .take(n)
            .map(|s| PyString::intern(py, &format!("{name}{s}"))),
    );
    keys
}

/// One control instant: `step(t, measure(), row())`, the inputs it returns set.
struct Controller<'py> {
    py: Python<'py>,
    step: Bound<'py, PyAny>,
    columns: Vec<Bound<'py, PyString>>,
    sensors: Option<Vec<Vec<Bound<'py, PyString>>>>,
    /// Ctrl-C (or another signal's exception), to raise once the run is left out.
    interrupt: Option<PyErr>,
}

impl<'py> Controller<'py> {
    fn tick(&mut self, t: f64, s: &mut SceneStepper) -> Result<(), Tick> {
        let py = self.py;
        if let Err(e) = py.check_signals() {
            self.interrupt = Some(e);
            return Err(Tick::Stopped);
        }
        let failed = |what: &str, e: PyErr| Tick::Failed(format!("{what}: {e}"));
        let readings = s.measure().map_err(|e| Tick::Failed(e.to_string()))?;
        let meas = PyDict::new(py);
        let keys = self.sensors.get_or_insert_with(|| {
            readings
                .iter()
                .map(|(n, v)| sensor_keys(py, n, v.len()))
                .collect()
        });
        for ((_, values), keys) in readings.iter().zip(keys.iter()) {
            let list = PyList::new(py, values).map_err(|e| failed("measure", e))?;
            meas.set_item(&keys[0], list)
                .map_err(|e| failed("measure", e))?;
            for (k, v) in keys[1..].iter().zip(values) {
                meas.set_item(k, v).map_err(|e| failed("measure", e))?;
            }
        }
        let values = s.row().map_err(|e| Tick::Failed(e.to_string()))?;
        let row = PyDict::new(py);
        for (k, v) in self.columns.iter().zip(&values) {
            row.set_item(k, v).map_err(|e| failed("row", e))?;
        }
        let out = match self.step.call1((t, meas, row)) {
            Ok(out) => out,
            Err(e) if e.is_instance_of::<PyKeyboardInterrupt>(py) => {
                self.interrupt = Some(e);
                return Err(Tick::Stopped);
            }
            Err(e) => {
                return Err(Tick::Failed(format!(
                    "the controller raised {}",
                    last_line(py, &e)
                )));
            }
        };
        let Ok(dict) = out.cast::<PyDict>() else {
            let what = out
                .get_type()
                .name()
                .map_or_else(|_| "?".to_owned(), |n| n.to_string());
            return Err(Tick::Failed(format!(
                "the controller's step returned {what}, not a dict of inputs ({{}} to leave them as they are)"
            )));
        };
        if dict.is_empty() {
            return Ok(());
        }
        let mut inputs: Vec<(String, f64)> = Vec::with_capacity(dict.len());
        for (k, v) in dict.iter() {
            let name: String = k.extract().map_err(|_| {
                Tick::Failed(format!(
                    "the controller returned an input named {k}, not a string"
                ))
            })?;
            let value: f64 = v.extract().map_err(|_| {
                Tick::Failed(format!(
                    "the controller returned input `{name}` = {v}, not a number"
                ))
            })?;
            inputs.push((name, value));
        }
        let pairs: Vec<(&str, f64)> = inputs.iter().map(|(n, v)| (n.as_str(), *v)).collect();
        s.set_inputs(&pairs)
            .map_err(|e| Tick::Failed(format!("the controller's inputs were refused: {e}")))
    }
}

#[pymethods]
impl NativeCampaign {
    /// Reads the scene file at `origin` (or parses `text`, named `origin`) and its
    /// `[campaign]` table; `max_rows` bounds each run's rows (default `satsim campaign`'s).
    #[new]
    #[pyo3(signature = (origin, text=None, max_rows=None))]
    fn new(
        py: Python<'_>,
        origin: PathBuf,
        text: Option<String>,
        max_rows: Option<u64>,
    ) -> PyResult<Self> {
        if max_rows == Some(0) {
            return Err(err("max_rows must be at least 1"));
        }
        let mut c = py
            .detach(|| match &text {
                Some(t) => Campaign::parse(t, &origin),
                None => Campaign::read(&origin),
            })
            .map_err(|e| err(e.to_string()))?;
        if let Some(m) = max_rows {
            c.set_max_rows(m);
        }
        Ok(Self { c })
    }
    /// Runs in the campaign.
    #[getter]
    fn runs(&self) -> u64 {
        self.c.runs
    }
    /// The master seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.c.seed
    }
    /// The dispersed values' column names (`runs.csv`'s, in draw order).
    #[getter]
    fn dispersed(&self) -> Vec<String> {
        self.c.dispersed.iter().map(|d| d.column.clone()).collect()
    }
    /// `runs.csv`'s header (without the user's metrics).
    #[getter]
    fn header(&self) -> Vec<String> {
        self.c.header()
    }
    /// The scene's digest (`campaign.json`'s `scene_digest`).
    #[getter]
    fn digest(&self) -> String {
        self.c.scene_digest()
    }
    /// The values run `k` uses.
    fn draw(&self, k: u64) -> Vec<f64> {
        self.c.draw(k)
    }
    /// Run `k`'s sensor seed.
    fn sensor_seed(&self, k: u64) -> u64 {
        self.c.sensor_seed(k)
    }
    /// Run `k`'s scene as TOML text: the drawn values in place, its sensor seed, the model
    /// and the initial state inline (`satsim run` of it gives run `k`'s row).
    fn run_text(&self, k: u64) -> PyResult<String> {
        if k >= self.c.runs {
            return Err(err(format!(
                "run {k} is not in the campaign (runs 0 to {})",
                self.c.runs.saturating_sub(1)
            )));
        }
        Ok(self.c.run_text(k, &self.c.draw(k)))
    }
    /// Refuses a `period` that cannot step the scene.
    fn check_period(&self, period: f64) -> PyResult<()> {
        self.c.check_period(period).map_err(err)
    }
    /// The flight software's name in `campaign.json`.
    #[staticmethod]
    #[pyo3(signature = (factory, period, metrics=None))]
    fn identity(factory: &str, period: f64, metrics: Option<&str>) -> String {
        Stepped::identity(factory, period, metrics)
    }
    /// Makes run `k` with `fsw.step(t, measurements, row)` at `t0 + i · period`: its record
    /// and, for a finished run, its rows `(columns, data)`. Raises what stopped it (Ctrl-C).
    fn run_stepped<'py>(
        &self,
        py: Python<'py>,
        k: u64,
        fsw: Bound<'py, PyAny>,
        period: f64,
    ) -> PyResult<(Rec, Option<RunOut<'py>>)> {
        if k >= self.c.runs {
            return Err(err(format!(
                "run {k} is not in the campaign (runs 0 to {})",
                self.c.runs.saturating_sub(1)
            )));
        }
        let step = match fsw.getattr("step") {
            Ok(s) if s.is_callable() => Some(s),
            _ => None,
        };
        let Some(step) = step else {
            let why = format!(
                "run {k}: the controller has no step(t, measurements, row) method (got {})",
                fsw.get_type()
                    .name()
                    .map_or_else(|_| "?".to_owned(), |n| n.to_string())
            );
            let r = RunRecord::failed(k, self.c.draw(k), why);
            return Ok((to_rec(r), None));
        };
        let mut ctl = Controller {
            py,
            step,
            columns: self
                .c
                .columns
                .iter()
                .map(|c| PyString::intern(py, c))
                .collect(),
            sensors: None,
            interrupt: None,
        };
        let done = self.c.run_stepped(k, period, &mut |t, s| ctl.tick(t, s));
        match done {
            None => Err(ctl
                .interrupt
                .take()
                .unwrap_or_else(|| PyKeyboardInterrupt::new_err("stopped"))),
            Some(Stepped { record, trajectory }) => {
                let rows = trajectory.map(|t| to_python(py, t)).transpose()?;
                Ok((to_rec(record), rows))
            }
        }
    }
    /// A failed run's record (`why` its message), for a run the factory could not start.
    fn failed(&self, k: u64, why: String) -> Rec {
        to_rec(RunRecord::failed(k, self.c.draw(k), why))
    }
}

/// A campaign folder being written ([`Folder`]).
#[pyclass(module = "satsim._satsim", name = "NativeFolder", frozen)]
pub(crate) struct NativeFolder {
    campaign: Py<NativeCampaign>,
    inner: Mutex<Option<Folder>>,
    todo: Vec<u64>,
    skipped: u64,
}

fn campaign_err(e: CampaignError) -> PyErr {
    err(e.to_string())
}

#[pymethods]
impl NativeFolder {
    /// Opens `dir` for the shard `(i, n)` (default all) of `campaign`, fresh or resumed.
    #[new]
    #[pyo3(signature = (campaign, dir, shard=None, resume=false, controller=None, metrics=false))]
    fn new(
        py: Python<'_>,
        campaign: Py<NativeCampaign>,
        dir: PathBuf,
        shard: Option<(u64, u64)>,
        resume: bool,
        controller: Option<String>,
        metrics: bool,
    ) -> PyResult<Self> {
        let shard = match shard {
            Some((i, n)) => Shard::new(i, n).map_err(|e| err(format!("shard: {e}")))?,
            None => Shard::ALL,
        };
        let c = &campaign.get().c;
        let folder = py
            .detach(|| Folder::open(c, &dir, shard, resume, controller, metrics))
            .map_err(campaign_err)?;
        Ok(Self {
            todo: folder.todo().to_vec(),
            skipped: folder.skipped(),
            campaign,
            inner: Mutex::new(Some(folder)),
        })
    }
    /// The runs to make, ascending.
    #[getter]
    fn todo(&self) -> Vec<u64> {
        self.todo.clone()
    }
    /// The runs the folder held already.
    #[getter]
    fn skipped(&self) -> u64 {
        self.skipped
    }
    /// Appends a record; whether the run finished (`ok`).
    fn emit(&self, py: Python<'_>, rec: Rec) -> PyResult<bool> {
        let c = &self.campaign.get().c;
        let mut g = self
            .inner
            .lock()
            .map_err(|_| err("the campaign folder failed in another thread"))?;
        let f = g
            .as_mut()
            .ok_or_else(|| err("the campaign folder is closed"))?;
        py.detach(|| f.emit(c, from_rec(rec))).map_err(campaign_err)
    }
    /// Finishes the folder (sorted files, `summary.json`, plots): `(runs, ok, failed,
    /// missing, files)`. Raises `SatsimError` when runs are missing (interrupted: the
    /// folder stays as streamed, for a resume).
    fn close(&self, py: Python<'_>) -> PyResult<(u64, u64, u64, u64, Vec<String>)> {
        let f = self
            .inner
            .lock()
            .map_err(|_| err("the campaign folder failed in another thread"))?
            .take()
            .ok_or_else(|| err("the campaign folder is closed"))?;
        let done = py.detach(|| f.close()).map_err(campaign_err)?;
        Ok((done.runs, done.ok, done.failed, done.missing, done.files))
    }
}

/// The shard to run, as `satsim campaign` chooses it: `flag` (`I/N`) if given, else the
/// scheduler's environment (a Slurm job array, a Kubernetes indexed Job with `shards`, an
/// AWS Batch array job), else the whole campaign. `(index, count, where it came from)`.
#[pyfunction]
#[pyo3(signature = (flag=None, shards=None))]
pub(crate) fn choose_shard(
    flag: Option<&str>,
    shards: Option<u64>,
) -> PyResult<(u64, u64, String)> {
    let flag = flag
        .map(|f| f.parse::<Shard>().map_err(|e| err(format!("--shard: {e}"))))
        .transpose()?;
    let c = satsim_tools::campaign::choose_shard(flag, shards, |v| std::env::var(v).ok())
        .map_err(err)?;
    Ok((c.shard.index, c.shard.count, c.source))
}
