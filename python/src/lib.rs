//! `satsim._satsim`: the native half of the Python package `satsim` (contract section 10).
//!
//! Every function here reads its input with the same readers as the `satsim` command line and
//! computes with the same library functions ([`satsim_tools::api`]), so the numbers are
//! the command line's to the last bit. The GIL is released ([`Python::detach`]) while a
//! file is read and parsed and while anything is computed; a long run re-attaches about five
//! times a second only to let Ctrl-C (`KeyboardInterrupt`) stop it.
//!
//! Errors are `satsim.SatsimError` (a `ValueError`) carrying the command line's message
//! without its `error: ` prefix: the file (or `<...>` for text and dicts), the line or the
//! field, and what is wrong. The friendly argument handling (a path, a text or a dict) lives in
//! `python/satsim/__init__.py`.

#![forbid(unsafe_code)]

mod fsw;
mod stepped;

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, ToPyArray};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use satsim_tools::api::{self, DynamicsFailure, RunFailure, Trajectory};
use satsim_tools::campaign::{Campaign, Shard};
use satsim_tools::linearize::linearize as linearize_scene;
use satsim_tools::modes::{Mode, modes as modes_of_scene};
use satsim_tools::output::{CsvWriter, write_plots};
use satsim_tools::scene::Scene;
use satsim_tools::scene::flexible::{CoupledModes, Elastic};
use satsim_tools::stepping::SceneStepper;
use satsim_tree::io::FileError;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

pyo3::create_exception!(
    _satsim,
    SatsimError,
    PyValueError,
    "Bad input or a failed computation; the message is the `satsim` command line's (file, line or field, what is wrong)."
);

fn err(message: impl Into<String>) -> PyErr {
    SatsimError::new_err(message.into())
}

fn file_err(e: FileError) -> PyErr {
    err(e.to_string())
}

/// A model (contract section 1), read and checked; with flexible bodies (section 14), its
/// flexible model too.
#[pyclass(module = "satsim._satsim", name = "NativeModel", frozen)]
struct NativeModel {
    model: api::DynamicsModel,
    origin: PathBuf,
}

/// `(omega, shapes)`: the coupled modes' angular frequencies (rad/s) and shapes (`dof x n`).
type ModesOut<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

#[pymethods]
impl NativeModel {
    /// Reads the model file at `path`.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let model = py
            .detach(|| api::DynamicsModel::read(&path))
            .map_err(file_err)?;
        Ok(Self {
            model,
            origin: path,
        })
    }

    /// Parses a model file's text; `origin` names it in messages.
    #[staticmethod]
    fn from_toml(py: Python<'_>, text: String, origin: PathBuf) -> PyResult<Self> {
        let model = py
            .detach(|| api::DynamicsModel::parse(&text, &origin))
            .map_err(file_err)?;
        Ok(Self { model, origin })
    }

    /// Where the model came from (a path, or `<model text>`).
    #[getter]
    fn origin(&self) -> String {
        self.origin.display().to_string()
    }

    /// `"free"` or `"fixed"`.
    #[getter]
    fn base(&self) -> &'static str {
        match self.model.rigid.base() {
            satsim_tree::BaseKind::Free => "free",
            satsim_tree::BaseKind::Fixed => "fixed",
        }
    }

    /// Degrees of freedom (the length of the generalised velocity, the modes included).
    #[getter]
    fn dof(&self) -> usize {
        self.model.dof()
    }

    /// Body names, the root first (the engine's order: parents before children).
    #[getter]
    fn body_names(&self) -> Vec<String> {
        self.model
            .rigid
            .bodies()
            .iter()
            .map(|b| b.name().to_owned())
            .collect()
    }

    /// Hinge names in the model file's order (the order of the state's arrays).
    #[getter]
    fn hinge_names(&self) -> Vec<String> {
        self.model.rigid.hinge_names().to_vec()
    }

    /// Total mass (kg).
    #[getter]
    fn total_mass(&self) -> f64 {
        self.model.rigid.total_mass()
    }

    /// The flexible bodies and their numbers of modes, in the model's order.
    #[getter]
    fn flexible(&self) -> Vec<(String, usize)> {
        self.model.flexible_bodies()
    }

    /// The flexible bodies and their clamped modal frequencies (Hz), in the model's order.
    #[getter]
    fn modal_frequencies(&self) -> Vec<(String, Vec<f64>)> {
        self.model.modal_frequencies()
    }

    /// The dynamics of the state file at `path`.
    fn dynamics_file<'py>(&self, py: Python<'py>, path: PathBuf) -> PyResult<DynamicsOut<'py>> {
        let result = py.detach(|| {
            let (state, elastic) = self.model.read_state(&path).map_err(|e| e.to_string())?;
            self.compute(&state, &elastic, &path)
        });
        dynamics_out(py, result.map_err(err)?)
    }

    /// The dynamics of a state given as JSON text; `origin` names it in messages.
    fn dynamics_json<'py>(
        &self,
        py: Python<'py>,
        text: String,
        origin: PathBuf,
    ) -> PyResult<DynamicsOut<'py>> {
        let result = py.detach(|| {
            let (state, elastic) = self
                .model
                .parse_state(&text, &origin)
                .map_err(|e| e.to_string())?;
            self.compute(&state, &elastic, &origin)
        });
        dynamics_out(py, result.map_err(err)?)
    }

    /// The coupled undamped modes at the state file at `path`.
    fn modes_file<'py>(&self, py: Python<'py>, path: PathBuf) -> PyResult<ModesOut<'py>> {
        let result = py.detach(|| {
            let (state, elastic) = self.model.read_state(&path).map_err(|e| e.to_string())?;
            self.coupled(&state, &elastic, &path)
        });
        modes_out(py, result.map_err(err)?)
    }

    /// The coupled undamped modes at a state given as JSON text.
    fn modes_json<'py>(
        &self,
        py: Python<'py>,
        text: String,
        origin: PathBuf,
    ) -> PyResult<ModesOut<'py>> {
        let result = py.detach(|| {
            let (state, elastic) = self
                .model
                .parse_state(&text, &origin)
                .map_err(|e| e.to_string())?;
            self.coupled(&state, &elastic, &origin)
        });
        modes_out(py, result.map_err(err)?)
    }
}

impl NativeModel {
    /// `satsim dynamics`' computation and messages.
    fn compute(
        &self,
        state: &satsim_tree::State,
        elastic: &Elastic,
        state_origin: &Path,
    ) -> Result<api::Dynamics, String> {
        self.model.dynamics(state, elastic).map_err(|e| match e {
            DynamicsFailure::Engine(e) => format!(
                "{}: {e} (model {})",
                state_origin.display(),
                self.origin.display()
            ),
            DynamicsFailure::NonFinite => format!("{}: {e}", state_origin.display()),
        })
    }

    /// The coupled modes, the message naming the state.
    fn coupled(
        &self,
        state: &satsim_tree::State,
        elastic: &Elastic,
        state_origin: &Path,
    ) -> Result<CoupledModes, String> {
        self.model.modes(state, elastic).map_err(|e| {
            format!(
                "{}: {e} (model {})",
                state_origin.display(),
                self.origin.display()
            )
        })
    }
}

/// numpy arrays of [`CoupledModes`].
fn modes_out(py: Python<'_>, m: CoupledModes) -> PyResult<ModesOut<'_>> {
    Ok((m.omega.into_pyarray(py), matrix(py, &m.shapes)?))
}

/// `(dof, mass_matrix, bias, acceleration, kinetic_energy)`.
type DynamicsOut<'py> = (
    usize,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    f64,
);

/// numpy arrays of a [`api::Dynamics`].
fn dynamics_out(py: Python<'_>, d: api::Dynamics) -> PyResult<DynamicsOut<'_>> {
    {
        let n = d.dof;
        // nalgebra is column-major; numpy's default is row-major: copy by rows.
        let rows: Vec<f64> = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| d.mass_matrix[(i, j)])
            .collect();
        let m = rows.into_pyarray(py).reshape([n, n])?;
        Ok((
            n,
            m,
            d.bias.as_slice().to_vec().into_pyarray(py),
            d.acceleration.as_slice().to_vec().into_pyarray(py),
            d.kinetic_energy,
        ))
    }
}

/// How often a run re-attaches to Python to check for Ctrl-C.
const SIGNAL_CHECK: Duration = Duration::from_millis(200);

/// A run's result handed to Python: `(columns, data)` with `data` of shape `(rows, columns)`.
type RunOut<'py> = (Vec<String>, Bound<'py, PyArray2<f64>>);

fn to_python<'py>(py: Python<'py>, t: Trajectory) -> PyResult<RunOut<'py>> {
    let (n, c) = (t.n_rows(), t.columns.len());
    let data = t.values.into_pyarray(py).reshape([n, c])?;
    Ok((t.columns, data))
}

/// A finished run handed to Python: [`RunOut`] and the warnings `satsim run` prints after
/// it (the scene reader's, a beam bent beyond its modal model).
type RanOut<'py> = (Vec<String>, Bound<'py, PyArray2<f64>>, Vec<String>);

/// What a run left: the trajectory and its warnings, or the failure.
enum Ran {
    Done(Trajectory, Vec<String>),
    /// A message and the rows before the failure.
    Failed(String, Trajectory),
    /// Python raised (Ctrl-C) while the run was checking for signals.
    Interrupted(PyErr),
}

/// Reads (a path) or parses (a text) a scene, runs it with the GIL released, writes
/// `out/trajectory.csv` and the plots when `out` is given, and returns `(columns, data,
/// warnings)`.
fn run_scene<'py>(
    py: Python<'py>,
    source: SceneSource,
    out: Option<PathBuf>,
) -> PyResult<RanOut<'py>> {
    let ran = py.detach(|| -> Result<Ran, String> {
        let scene = match &source {
            SceneSource::File(path) => Scene::read(path),
            SceneSource::Text(text, origin) => Scene::parse(text, origin),
        }
        .map_err(|e| e.to_string())?;
        // The rows are held in memory: a tiny `output.every` is refused before the run.
        scene
            .check_rows(satsim_tools::scene::DEFAULT_MAX_ROWS)
            .map_err(|e| e.to_string())?;
        let mut interrupted: Option<PyErr> = None;
        let mut last_check = Instant::now();
        let result = api::run_scene_warned(&scene, || {
            if last_check.elapsed() < SIGNAL_CHECK {
                return false;
            }
            last_check = Instant::now();
            match Python::attach(|py| py.check_signals()) {
                Ok(()) => false,
                Err(e) => {
                    interrupted = Some(e);
                    true
                }
            }
        });
        let path = source.origin().display().to_string();
        let ran = match result {
            Ok((t, warnings)) => Ran::Done(t, warnings),
            Err(RunFailure::Setup(e)) => return Err(format!("{path}: {e}")),
            Err(RunFailure::Stopped { partial }) => match interrupted {
                Some(e) => Ran::Interrupted(e),
                None => Ran::Failed(format!("{path}: stopped"), partial),
            },
            Err(RunFailure::Failed { why, partial }) => {
                let kept = match partial.last_t() {
                    Some(t) => format!("the rows up to t = {t} s are kept"),
                    None => "no row was produced".to_owned(),
                };
                Ran::Failed(format!("{path}: the run failed: {why}; {kept}"), partial)
            }
        };
        if let (Some(dir), Ran::Done(t, _) | Ran::Failed(_, t)) = (&out, &ran) {
            write_output(dir, t, scene.plots)?;
        }
        Ok(ran)
    });
    match ran.map_err(err)? {
        Ran::Done(t, warnings) => {
            let (columns, data) = to_python(py, t)?;
            Ok((columns, data, warnings))
        }
        Ran::Interrupted(e) => Err(e),
        Ran::Failed(message, partial) => {
            let e = err(message);
            e.value(py).setattr("partial", to_python(py, partial)?)?;
            Err(e)
        }
    }
}

/// `DIR/trajectory.csv` (the same writer as `satsim run`) and, when the scene asks for them,
/// the plots.
fn write_output(dir: &Path, t: &Trajectory, plots: bool) -> Result<(), String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create the output folder {}: {e}", dir.display()))?;
    let csv_path = dir.join("trajectory.csv");
    let write = || -> std::io::Result<()> {
        let mut csv = CsvWriter::create(&csv_path, &t.columns)?;
        for row in t.rows() {
            csv.row(row)?;
        }
        Ok(())
    };
    write().map_err(|e| format!("cannot write {}: {e}", csv_path.display()))?;
    if plots && t.n_rows() > 0 {
        let rows: Vec<Vec<f64>> = t.rows().map(<[f64]>::to_vec).collect();
        write_plots(dir, &t.columns, &rows)
            .map_err(|e| format!("cannot write the plots in {}: {e}", dir.display()))?;
    }
    Ok(())
}

/// A scene file, or a scene's text and the path that names it (and anchors its relative
/// paths).
enum SceneSource {
    File(PathBuf),
    Text(String, PathBuf),
}

impl SceneSource {
    fn origin(&self) -> &Path {
        match self {
            SceneSource::File(p) | SceneSource::Text(_, p) => p,
        }
    }
}

/// `satsim campaign`'s warning where `beyond` of its `ok` finished runs bent a body past
/// `SMALL_DEFLECTION` of its length.
#[pyfunction]
fn beyond_warning(beyond: u64, ok: u64) -> String {
    satsim_tools::campaign::beyond_warning(beyond, ok)
}

/// Whether a finished run's campaign row (`values`, named by `columns`) moved its energy
/// budget beyond `BUDGET_DRIFT` of its largest term, as `satsim campaign` counts it.
#[pyfunction]
fn budget_drifted_row(columns: Vec<String>, values: Vec<f64>) -> PyResult<bool> {
    if columns.len() != values.len() {
        return Err(PyValueError::new_err(format!(
            "{} columns for {} values",
            columns.len(),
            values.len()
        )));
    }
    Ok(satsim_tools::campaign::budget_drifted_row(
        &columns, &values,
    ))
}

/// `satsim campaign`'s warning where `drifted` of its `ok` finished runs moved their energy
/// budget beyond `BUDGET_DRIFT` of its largest term.
#[pyfunction]
fn budget_warning(drifted: u64, ok: u64) -> String {
    satsim_tools::campaign::budget_warning(drifted, ok)
}

/// `satsim campaign`'s warning where `held` of its `ok` finished runs had their steps held by
/// their explicit method's stability limit (`stability_held`).
#[pyfunction]
fn held_warning(held: u64, ok: u64) -> String {
    satsim_tools::campaign::held_warning(held, ok)
}

/// Runs the scene file at `path`; writes `out/trajectory.csv` (and the plots) when `out` is
/// given. Returns `(columns, data, warnings)`.
#[pyfunction]
#[pyo3(signature = (path, out=None))]
fn run_file<'py>(py: Python<'py>, path: PathBuf, out: Option<PathBuf>) -> PyResult<RanOut<'py>> {
    run_scene(py, SceneSource::File(path), out)
}

/// Runs a scene given as TOML text; `origin` names it in messages and its folder anchors
/// the scene's relative paths.
#[pyfunction]
#[pyo3(signature = (text, origin, out=None))]
fn run_text<'py>(
    py: Python<'py>,
    text: String,
    origin: PathBuf,
    out: Option<PathBuf>,
) -> PyResult<RanOut<'py>> {
    run_scene(py, SceneSource::Text(text, origin), out)
}

/// Reads the scene file at `origin`, or parses `text` (named `origin`) when given.
fn read_scene(origin: &Path, text: Option<&str>) -> Result<Scene, String> {
    match text {
        Some(t) => Scene::parse(t, origin),
        None => Scene::read(origin),
    }
    .map_err(|e| e.to_string())
}

/// [`read_scene`] for a linearisation, which integrates nothing: without the fixed step's
/// checks ([`Scene::read_to_linearise`]).
fn read_scene_to_linearise(origin: &Path, text: Option<&str>) -> Result<Scene, String> {
    match text {
        Some(t) => Scene::parse_to_linearise(t, origin),
        None => Scene::read_to_linearise(origin, &[]),
    }
    .map_err(|e| e.to_string())
}

/// A campaign's `runs.csv` in memory: `(columns, data, status, messages)`; see
/// [`api::campaign_table`] for the encoding of the text columns in `data`.
type CampaignOut<'py> = (
    Vec<String>,
    Bound<'py, PyArray2<f64>>,
    Vec<String>,
    Vec<String>,
);

/// Runs a campaign (the scene file `origin`, or `text` named `origin`) in memory, on
/// `threads` threads (default every core), the shard `(index, count)` (default all).
#[pyfunction]
#[pyo3(signature = (origin, text=None, threads=None, shard=None))]
fn campaign<'py>(
    py: Python<'py>,
    origin: PathBuf,
    text: Option<String>,
    threads: Option<usize>,
    shard: Option<(u64, u64)>,
) -> PyResult<CampaignOut<'py>> {
    if threads == Some(0) {
        return Err(err("threads must be at least 1 (or None: every core)"));
    }
    let shard = match shard {
        Some((i, n)) => Shard::new(i, n).map_err(|e| err(format!("shard: {e}")))?,
        None => Shard::ALL,
    };
    let c = py
        .detach(|| match &text {
            Some(t) => Campaign::parse(t, &origin),
            None => Campaign::read(&origin),
        })
        .map_err(|e| err(e.to_string()))?;
    // Ctrl-C: Python sees signals on this (the main) thread only, so the runs go on another
    // one while this one checks for signals; on one, no run starts and the running ones stop
    // at their next output row (as `satsim campaign` does), and Python raises.
    let stop = AtomicBool::new(false);
    let mut interrupted: Option<PyErr> = None;
    let table = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            api::campaign_table_until(&c, threads, shard, &|| stop.load(Ordering::Relaxed))
        });
        while !worker.is_finished() {
            py.detach(|| std::thread::sleep(Duration::from_millis(20)));
            if interrupted.is_none()
                && let Err(e) = py.check_signals()
            {
                interrupted = Some(e);
                stop.store(true, Ordering::Relaxed);
            }
        }
        worker.join()
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    let table = table
        .map_err(|_| err("internal error (a bug in satsim): the campaign thread panicked"))?
        .map_err(|e| err(e.to_string()))?;
    let (n, w) = (table.n_rows(), table.columns.len());
    let data = table.values.into_pyarray(py).reshape([n, w])?;
    Ok((table.columns, data, table.status, table.messages))
}

/// `satsim linearize`: a dict `states`, `inputs`, `A`, `B` (numpy), `error_estimate`,
/// `locked`, `released`.
#[pyfunction]
#[pyo3(signature = (origin, text=None))]
fn linearize<'py>(
    py: Python<'py>,
    origin: PathBuf,
    text: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let lin = py
        .detach(|| {
            let scene = read_scene_to_linearise(&origin, text.as_deref())?;
            linearize_scene(&scene).map_err(|e| format!("{}: {e}", origin.display()))
        })
        .map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("states", &lin.states)?;
    d.set_item("inputs", &lin.inputs)?;
    d.set_item("A", matrix(py, &lin.a)?)?;
    d.set_item("B", matrix(py, &lin.b)?)?;
    d.set_item("error_estimate", lin.error_estimate)?;
    d.set_item("locked", &lin.locked)?;
    d.set_item("released", &lin.released)?;
    d.set_item("residual", lin.residual.to_pyarray(py))?;
    Ok(d)
}

/// `satsim modes`: a dict `frequencies_hz`, `damping_ratios` (numpy), `rigid_modes`, `modes`
/// (a list of dicts: `frequency_hz`, `damping_ratio`, `eigenvalue` `[re, im]`, `shape` and
/// `shape_imag` as `{state name: value}`), `real_eigenvalues`, `locked`, `released`.
#[pyfunction]
#[pyo3(signature = (origin, text=None))]
fn modes<'py>(
    py: Python<'py>,
    origin: PathBuf,
    text: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = py
        .detach(|| {
            let scene = read_scene_to_linearise(&origin, text.as_deref())?;
            modes_of_scene(&scene).map_err(|e| format!("{}: {e}", origin.display()))
        })
        .map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("frequencies_hz", m.frequencies_hz.clone().into_pyarray(py))?;
    d.set_item("damping_ratios", m.damping_ratios.clone().into_pyarray(py))?;
    d.set_item("rigid_modes", m.rigid_modes)?;
    let list: Vec<Bound<'py, PyDict>> = m
        .modes
        .iter()
        .map(|x| mode_dict(py, x))
        .collect::<PyResult<_>>()?;
    d.set_item("modes", list)?;
    d.set_item(
        "real_eigenvalues",
        m.real_eigenvalues.clone().into_pyarray(py),
    )?;
    d.set_item("locked", &m.locked)?;
    d.set_item("released", &m.released)?;
    Ok(d)
}

fn mode_dict<'py>(py: Python<'py>, m: &Mode) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("frequency_hz", m.frequency_hz)?;
    d.set_item("damping_ratio", m.damping_ratio)?;
    d.set_item(
        "eigenvalue",
        vec![m.eigenvalue.0, m.eigenvalue.1].into_pyarray(py),
    )?;
    for (key, shape) in [("shape", &m.shape), ("shape_imag", &m.shape_imag)] {
        let s = PyDict::new(py);
        for (name, v) in shape {
            s.set_item(name, *v)?;
        }
        d.set_item(key, s)?;
    }
    Ok(d)
}

/// A matrix as a row-major numpy array.
fn matrix<'py>(py: Python<'py>, m: &nalgebra::DMatrix<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (r, c) = m.shape();
    let rows: Vec<f64> = (0..r)
        .flat_map(|i| (0..c).map(move |j| (i, j)))
        .map(|(i, j)| m[(i, j)])
        .collect();
    rows.into_pyarray(py).reshape([r, c])
}

/// A scene stepped from Python (`satsim.Simulation`, contract section 13): see
/// [`satsim_tools::stepping`]. The GIL is released while it reads the scene and while it
/// integrates; a mutex makes it safe to share between Python threads (one call at a time).
#[pyclass(module = "satsim._satsim", name = "NativeSimulation", frozen)]
struct NativeSimulation {
    inner: Mutex<SceneStepper>,
    origin: PathBuf,
}

impl NativeSimulation {
    fn lock(&self) -> PyResult<MutexGuard<'_, SceneStepper>> {
        self.inner
            .lock()
            .map_err(|_| err("the simulation failed in another thread"))
    }
}

#[pymethods]
impl NativeSimulation {
    /// Reads the scene file at `origin` (or parses `text`, named `origin`); with `out`,
    /// streams `out/trajectory.csv`; with `seed`, the sensors' noise is drawn from it
    /// instead of the scene's `[sensors] seed`; `max_rows` bounds the rows kept (default
    /// `satsim run`'s limit).
    #[new]
    #[pyo3(signature = (origin, text=None, out=None, seed=None, max_rows=None))]
    fn new(
        py: Python<'_>,
        origin: PathBuf,
        text: Option<String>,
        out: Option<PathBuf>,
        seed: Option<u64>,
        max_rows: Option<u64>,
    ) -> PyResult<Self> {
        if max_rows == Some(0) {
            return Err(err("max_rows must be at least 1"));
        }
        let inner = py
            .detach(|| {
                let scene = read_scene(&origin, text.as_deref())?;
                let title = origin.file_name().map_or_else(
                    || origin.display().to_string(),
                    |n| n.to_string_lossy().into(),
                );
                let mut s = SceneStepper::with_seed(&scene, out.as_deref(), &title, seed)
                    .map_err(|e| format!("{}: {e}", origin.display()))?;
                if let Some(m) = max_rows {
                    s.set_max_rows(m);
                }
                Ok::<_, String>(s)
            })
            .map_err(err)?;
        Ok(Self {
            inner: Mutex::new(inner),
            origin,
        })
    }
    /// The time (s).
    #[getter]
    fn t(&self) -> PyResult<f64> {
        Ok(self.lock()?.t())
    }
    /// The trajectory's column names.
    #[getter]
    fn columns(&self) -> PyResult<Vec<String>> {
        Ok(self.lock()?.columns().to_vec())
    }
    /// The scene's end, `t0 + duration` (s): where `satsim run` stops.
    #[getter]
    fn t_end(&self) -> PyResult<f64> {
        Ok(self.lock()?.stepping().output_grid().t_end)
    }
    /// Each sensor's `(name, kind)`: `gyro`, `star_tracker`, `sun_sensor`, `magnetometer`.
    #[getter]
    fn sensors(&self) -> PyResult<Vec<(String, String)>> {
        Ok(self
            .lock()?
            .sensors()
            .iter()
            .map(|(n, k)| (n.clone(), (*k).to_owned()))
            .collect())
    }
    /// The most rows kept for `trajectory`.
    #[getter]
    fn max_rows(&self) -> PyResult<u64> {
        Ok(self.lock()?.max_rows())
    }
    /// The integrator's work over the advances so far: `(name, count)` pairs. `steps_capped`
    /// counts the accepted steps that landed on a piece's end or a time stop (or that
    /// `h_max` cut), as `satsim run`'s summary does.
    #[getter]
    fn work(&self) -> PyResult<Vec<(&'static str, usize)>> {
        let guard = self.lock()?;
        let (w, steps) = (guard.stepping().work(), guard.stepping().steps());
        Ok(vec![
            ("rhs_evals", w.rhs_evals),
            ("steps_accepted", w.steps_accepted),
            ("steps_rejected", w.steps_rejected),
            ("steps_capped", steps.capped),
            ("jacobian_evals", w.jacobian_evals),
            ("jacobian_updates", w.jacobian_updates),
            ("lu_decompositions", w.lu_decompositions),
        ])
    }
    /// The input names.
    #[getter]
    fn inputs(&self) -> PyResult<Vec<String>> {
        Ok(self.lock()?.inputs().to_vec())
    }
    /// The row at the current time, in the columns' order.
    fn row(&self) -> PyResult<Vec<f64>> {
        self.lock()?.row().map_err(|e| err(e.to_string()))
    }
    /// Every sensor's reading at the current time: `(name, values)` in the scene's order.
    fn measure(&self) -> PyResult<Vec<(String, Vec<f64>)>> {
        self.lock()?.measure().map_err(|e| err(e.to_string()))
    }
    /// Sets inputs by name (all checked before any is set).
    fn set_inputs(&self, values: Vec<(String, f64)>) -> PyResult<()> {
        let values: Vec<(&str, f64)> = values.iter().map(|(n, v)| (n.as_str(), *v)).collect();
        self.lock()?
            .set_inputs(&values)
            .map_err(|e| err(e.to_string()))
    }
    /// Integrates from `t` to `t + dt` (GIL released); the events that fired.
    fn advance(&self, py: Python<'_>, dt: f64) -> PyResult<Vec<(f64, String, String)>> {
        let origin = &self.origin;
        py.detach(|| match self.inner.lock() {
            Ok(mut inner) => inner
                .advance(dt)
                .map_err(|e| format!("{}: {e}", origin.display())),
            Err(_) => Err("the simulation failed in another thread".to_owned()),
        })
        .map_err(err)
    }
    /// The rows so far: `(columns, data)`.
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<RunOut<'py>> {
        let t = self.lock()?.trajectory().clone();
        to_python(py, t)
    }
    /// Ends the simulation; writes the rest of the output folder. The files written.
    fn close(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        let written = py
            .detach(|| match self.inner.lock() {
                Ok(mut inner) => inner.close().map_err(|e| e.to_string()),
                Err(_) => Err("the simulation failed in another thread".to_owned()),
            })
            .map_err(err)?;
        Ok(written.iter().map(|p| p.display().to_string()).collect())
    }
    /// What `satsim run` warns of after a run, for the steps taken so far: a flexible body
    /// bent past a tenth of its length, beyond what its modal model holds; an energy budget
    /// that did not close; an explicit method's steps held by a stiff motion (over the
    /// advances it took in more than one step).
    fn warnings(&self) -> PyResult<Vec<String>> {
        Ok(self.lock()?.warnings())
    }
    /// Whether `close` was called.
    #[getter]
    fn closed(&self) -> PyResult<bool> {
        Ok(self.lock()?.is_closed())
    }
}

/// The native module.
#[pymodule]
fn _satsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SatsimError", m.py().get_type::<SatsimError>())?;
    m.add_class::<NativeModel>()?;
    m.add_class::<NativeSimulation>()?;
    m.add_class::<stepped::NativeCampaign>()?;
    m.add_class::<stepped::NativeFolder>()?;
    m.add_function(wrap_pyfunction!(stepped::choose_shard, m)?)?;
    m.add_class::<fsw::NativeMekf>()?;
    m.add("MIN_SIGMA", satsim_spacecraft::fsw::estimator::MIN_SIGMA)?;
    m.add_function(wrap_pyfunction!(fsw::attitude_error_py, m)?)?;
    m.add_class::<fsw::NativeGuidance>()?;
    m.add_class::<fsw::NativeSlew>()?;
    m.add_class::<fsw::NativePid>()?;
    m.add_function(wrap_pyfunction!(fsw::triad_py, m)?)?;
    m.add_function(wrap_pyfunction!(fsw::triad_covariance_py, m)?)?;
    m.add_function(wrap_pyfunction!(fsw::gyro_mean_py, m)?)?;
    m.add_function(wrap_pyfunction!(fsw::bdot_dipole_py, m)?)?;
    m.add_function(wrap_pyfunction!(fsw::momentum_dipole_py, m)?)?;
    m.add_function(wrap_pyfunction!(run_file, m)?)?;
    m.add_function(wrap_pyfunction!(run_text, m)?)?;
    m.add_function(wrap_pyfunction!(campaign, m)?)?;
    m.add_function(wrap_pyfunction!(beyond_warning, m)?)?;
    m.add_function(wrap_pyfunction!(budget_drifted_row, m)?)?;
    m.add_function(wrap_pyfunction!(budget_warning, m)?)?;
    m.add_function(wrap_pyfunction!(held_warning, m)?)?;
    m.add("SMALL_DEFLECTION", satsim_tree::flexible::SMALL_DEFLECTION)?;
    m.add_function(wrap_pyfunction!(linearize, m)?)?;
    m.add_function(wrap_pyfunction!(modes, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
