//! `satsim run SCENE.toml [--out DIR] [--set KEY=VALUE]...` (contract section 7): integrates a
//! scene (with `--set` overrides, see [`satsim_tools::scene_keys`]), streams
//! `DIR/trajectory.csv` row by row (in blocks, flushed on success, failure and interrupt, so
//! a stopped run leaves a valid file up to its last row), writes every event to
//! `DIR/events.csv`, draws SVG plots of the main quantities at the end from a bounded min/max
//! decimation (memory does not grow with the number of rows), shows a progress bar on
//! standard error (indicatif, drawn only when it is a terminal), and prints a short summary on
//! standard output.
//!
//! Exit status: 0 on success, 2 for bad input (the scene, its model or state, the command
//! line), 1 for a run that fails part-way (the message says when and why), 130 for a run
//! interrupted by Ctrl-C (SIGINT): the run stops at the next output row, the CSV holds every
//! row up to it and standard error says `interrupted at t = … s; N rows written to …`.
//! Further Ctrl-Cs within 2 s of the first are ignored (the clean stop is finishing); one
//! after that ends the process at once (status 130). The handler is `ctrlc`'s.
//! `satsim` with no arguments runs the default scene `examples/scenes/deploy.toml`.

use super::{CliError, Output, stem};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use satsim_integrate::{Output as Times, Stats};
use satsim_spacecraft::simulation::{RunError, Simulation};
use satsim_tools::output::{CsvWriter, PlotRecorder, write_events};
use satsim_tools::scene::{DEFAULT_MAX_ROWS, Scene};
use satsim_tools::scene_keys::Override;
use satsim_tools::view::{PoseRecorder, ViewError};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The flags of `satsim run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (TOML, cli-contract section 7)
    #[arg(value_name = "SCENE.toml")]
    pub scene: PathBuf,
    /// Output folder for trajectory.csv, events.csv, the plots and view.html [default:
    /// out/<scene stem>]
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Override a scene value by its dotted path (the campaign's key syntax), e.g.
    /// `--set duration=60` or `--set model.body.2.mass=3.5` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_override)]
    pub set: Vec<Override>,
    /// Refuse a scene whose run would write more rows than this (`duration / output.every`)
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_ROWS)]
    pub max_rows: u64,
}

/// The value parser of `--set`: `KEY=VALUE` (the key and value are checked against the scene
/// when it is read).
pub fn parse_override(s: &str) -> Result<Override, String> {
    Override::parse(s).map_err(|e| e.to_string())
}

/// The exit status of a run that failed part-way.
pub const EXIT_RUN_FAILED: u8 = 1;

/// The exit status of a run interrupted by Ctrl-C (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

/// Why `satsim run` failed.
#[derive(Debug)]
pub enum Failure {
    /// Bad input (exit status 2).
    BadInput(CliError),
    /// The run failed part-way (exit status 1).
    Run(String),
    /// The run was interrupted by Ctrl-C (exit status 130); the message says where.
    Interrupted(String),
}

impl From<CliError> for Failure {
    fn from(e: CliError) -> Self {
        Failure::BadInput(e)
    }
}

impl Failure {
    /// The process exit status.
    pub fn exit_code(&self) -> u8 {
        match self {
            Failure::BadInput(_) => super::EXIT_BAD_INPUT,
            Failure::Run(_) => EXIT_RUN_FAILED,
            Failure::Interrupted(_) => EXIT_INTERRUPTED,
        }
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::BadInput(e) => write!(f, "{e}"),
            Failure::Run(m) => write!(f, "error: {m}"),
            Failure::Interrupted(m) => write!(f, "{m}"),
        }
    }
}

/// The default scene: `examples/scenes/deploy.toml` relative to the current directory, else
/// in the workspace this binary was built from.
pub fn default_scene() -> PathBuf {
    let local = Path::new("examples/scenes/deploy.toml");
    if local.is_file() {
        return local.to_path_buf();
    }
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/scenes/deploy.toml"
    ))
}

/// For the dispatcher: every failure as a [`CliError`] (exit status 2, 130 for Ctrl-C). The
/// binary calls [`command`] directly to tell run failures (status 1) apart.
pub fn run(args: &Args) -> Result<Output, CliError> {
    command(args).map_err(|f| match f {
        Failure::BadInput(e) => e,
        Failure::Run(m) => CliError::Other(m),
        Failure::Interrupted(m) => CliError::Interrupted(m),
    })
}

/// Runs `satsim run`.
pub fn command(args: &Args) -> Result<Output, Failure> {
    run_limited(&args.scene, args.out.clone(), &args.set, args.max_rows)
}

/// Runs the scene at `scene_path`, writing into `out` (default `out/<scene stem>`).
pub fn run_scene(scene_path: &Path, out: Option<PathBuf>) -> Result<Output, Failure> {
    run_scene_with(scene_path, out, &[])
}

/// [`run_scene`] with `--set KEY=VALUE` overrides applied to the scene.
pub fn run_scene_with(
    scene_path: &Path,
    out: Option<PathBuf>,
    overrides: &[Override],
) -> Result<Output, Failure> {
    run_limited(scene_path, out, overrides, DEFAULT_MAX_ROWS)
}

/// [`run_scene_with`], refusing a run of more than `max_rows` rows before it starts. Four
/// steps: read the scene, build its simulation and open its files, run it with every row
/// streamed out, then write what follows the run and the summary.
pub fn run_limited(
    scene_path: &Path,
    out: Option<PathBuf>,
    overrides: &[Override],
    max_rows: u64,
) -> Result<Output, Failure> {
    let scene = read(scene_path, overrides, max_rows)?;
    let mut sim = scene
        .simulation()
        .map_err(|e| CliError::Other(format!("{}: {e}", scene_path.display())))?;
    let mut files = RunFiles::open(scene_path, out, &scene, &sim)?;
    let streamed = stream(&scene, &mut sim, &mut files);
    let done = finish(scene_path, &scene, &sim, files, streamed)?;
    super::print_warnings(&satsim_tools::api::after_run_warnings(
        &scene,
        &sim,
        &done.stats,
    ));
    Ok(summary(scene_path, &scene, &sim, &done))
}

/// The scene with its overrides, its warnings printed, refused past `max_rows` rows.
fn read(scene_path: &Path, overrides: &[Override], max_rows: u64) -> Result<Scene, Failure> {
    let scene = Scene::read_with(scene_path, overrides).map_err(CliError::File)?;
    super::print_warnings(&scene.warnings);
    scene.check_rows(max_rows).map_err(CliError::File)?;
    Ok(scene)
}

/// What a run streams into: the output folder, `trajectory.csv` and the 3-D view's poses.
struct RunFiles {
    dir: PathBuf,
    csv_path: PathBuf,
    columns: Vec<String>,
    csv: CsvWriter,
    /// The 3-D playback (`view.html`, contract section 11): poses recorded at every row.
    poses: Option<PoseRecorder>,
}

impl RunFiles {
    /// Creates the folder (`out`, default `out/<scene stem>`) and the CSV's header, and the
    /// poses' recorder when the scene asks for the view.
    fn open(
        scene_path: &Path,
        out: Option<PathBuf>,
        scene: &Scene,
        sim: &Simulation,
    ) -> Result<Self, Failure> {
        let stem = stem(scene_path);
        let dir = out.unwrap_or_else(|| Path::new("out").join(&stem));
        std::fs::create_dir_all(&dir).map_err(|e| {
            CliError::Other(format!(
                "cannot create the output folder {}: {e}",
                dir.display()
            ))
        })?;
        let csv_path = dir.join("trajectory.csv");
        let columns = sim.columns();
        let csv = CsvWriter::create(&csv_path, &columns)
            .map_err(|e| CliError::Other(format!("cannot write {}: {e}", csv_path.display())))?;
        let title = scene_path
            .file_name()
            .map_or(stem.clone(), |n| n.to_string_lossy().into());
        let poses = match scene.view {
            true => Some(
                PoseRecorder::new(sim.model(), &columns, &title)
                    .and_then(|r| match sim.flex_model() {
                        Some(f) => r.with_flexible(f, &columns),
                        None => Ok(r),
                    })
                    .and_then(|r| r.with_rotors(sim.model().n_hinges() - sim.layout().n_hinges))
                    .map_err(|e| CliError::Other(e.to_string()))?,
            ),
            false => None,
        };
        Ok(Self {
            dir,
            csv_path,
            columns,
            csv,
            poses,
        })
    }
}

/// What the run left: its outcome, and what the rows' sink kept of the rows.
struct Streamed {
    result: Result<Stats, RunError<Stop>>,
    /// Wall-clock seconds of the run.
    elapsed: f64,
    /// The plots' min/max decimation: bounded memory, the rows never go into a list.
    plots: PlotRecorder,
    first_row: Option<Vec<f64>>,
    last_row: Vec<f64>,
    /// The CSV's flush, done whatever happened: every row written reaches the file.
    flushed: std::io::Result<()>,
}

/// Runs the scene, each row to the CSV, the poses and the plots' decimation as it comes,
/// with the progress bar and Ctrl-C checked after every row.
fn stream(scene: &Scene, sim: &mut Simulation, files: &mut RunFiles) -> Streamed {
    let (t0, t_end) = (sim.t0(), sim.t0() + scene.duration);
    let started = Instant::now();
    let bar = progress_bar(t0, t_end);
    let mut last_message = started;
    let mut plots = PlotRecorder::new(&files.columns);
    let mut first_row: Option<Vec<f64>> = None;
    let mut last_row: Vec<f64> = Vec::new();
    let (csv, poses) = (&mut files.csv, &mut files.poses);
    interrupt::install();
    let result = sim.run(
        &scene.options,
        t_end,
        &Times::Interval(scene.every),
        |t, row| -> Result<(), Stop> {
            csv.row(row).map_err(Stop::Write)?;
            if let Some(p) = poses.as_mut() {
                p.record(row).map_err(Stop::View)?;
            }
            plots.push(row);
            if first_row.is_none() {
                first_row = Some(row.to_vec());
            }
            last_row.clear();
            last_row.extend_from_slice(row);
            // indicatif draws at most a few times a second (and not at all without a terminal).
            bar.set_position(progress_units(t - t0));
            if !bar.is_hidden() && last_message.elapsed() >= Duration::from_millis(200) {
                last_message = Instant::now();
                bar.set_message(format!("{t:.1}"));
            }
            // Checked after the row is written, so the CSV ends with a complete row.
            if interrupt::requested() {
                return Err(Stop::Interrupted);
            }
            Ok(())
        },
    );
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    let flushed = files.csv.flush();
    Streamed {
        result,
        elapsed,
        plots,
        first_row,
        last_row,
        flushed,
    }
}

/// A finished run and the files written after it, for the summary.
struct Done {
    stats: Stats,
    elapsed: f64,
    columns: Vec<String>,
    csv_path: PathBuf,
    n_rows: usize,
    first_row: Option<Vec<f64>>,
    last_row: Vec<f64>,
    events_path: PathBuf,
    n_events: usize,
    /// The plots' file names.
    plots: Vec<String>,
    view: Option<PathBuf>,
}

/// After the run: `events.csv` always; then a failed run's message, or an interrupted run's
/// plots and message; else the CSV's flush checked, the plots and the 3-D view.
fn finish(
    scene_path: &Path,
    scene: &Scene,
    sim: &Simulation,
    files: RunFiles,
    streamed: Streamed,
) -> Result<Done, Failure> {
    let RunFiles {
        dir,
        csv_path,
        columns,
        poses,
        ..
    } = files;
    let n_rows = streamed.plots.rows();
    let draw = |plots: &PlotRecorder| {
        if scene.plots {
            plots.write(&dir).map_err(|e| {
                Failure::Run(format!("cannot write the plots in {}: {e}", dir.display()))
            })
        } else {
            Ok(Vec::new())
        }
    };
    // Every event, not only the ten in the summary (also for a run that failed or was interrupted).
    let events_path = dir.join("events.csv");
    let n_events = write_events(&events_path, sim.event_records())
        .map_err(|e| Failure::Run(format!("cannot write {}: {e}", events_path.display())))?;
    let stats = match streamed.result {
        Ok(stats) => stats,
        Err(RunError::Sink {
            t,
            error: Stop::Interrupted,
        }) => {
            // The plots of what ran, then the message.
            draw(&streamed.plots)?;
            return Err(Failure::Interrupted(format!(
                "interrupted at t = {t} s; {n_rows} rows written to {}",
                csv_path.display()
            )));
        }
        Err(e) => {
            let last_t = streamed.last_row.first().copied();
            return Err(run_failed(scene_path, &csv_path, e, last_t));
        }
    };
    streamed
        .flushed
        .map_err(|e| Failure::Run(format!("cannot write {}: {e}", csv_path.display())))?;
    let plots = draw(&streamed.plots)?;
    let view = match poses {
        Some(p) => Some(
            p.finish(sim.event_log())
                .write(&dir)
                .map_err(|e| Failure::Run(format!("cannot write the 3-D view: {e}")))?,
        ),
        None => None,
    };
    Ok(Done {
        stats,
        elapsed: streamed.elapsed,
        columns,
        csv_path,
        n_rows,
        first_row: streamed.first_row,
        last_row: streamed.last_row,
        events_path,
        n_events,
        plots,
        view,
    })
}

/// A run that failed part-way: why, and how far `trajectory.csv` got (`last_t`: its last
/// row's time).
fn run_failed(
    scene_path: &Path,
    csv_path: &Path,
    e: RunError<Stop>,
    last_t: Option<f64>,
) -> Failure {
    let why = match e {
        RunError::Integrate(e) => e.to_string(),
        RunError::Sink {
            t,
            error: Stop::View(e),
        } => format!("at t = {t} s: {e}"),
        RunError::Sink { t, error } => {
            format!("cannot write {} at t = {t} s: {error}", csv_path.display())
        }
    };
    let kept = match last_t {
        Some(t) => format!("{} holds the rows up to t = {t} s", csv_path.display()),
        None => format!("{} holds only the header", csv_path.display()),
    };
    Failure::Run(format!(
        "{}: the run failed: {why}; {kept}",
        scene_path.display()
    ))
}

/// The summary on standard output: the scene, the model, the effects, the state, the run's
/// counts, the first ten events, the energy and budget lines, the files written.
fn summary(scene_path: &Path, scene: &Scene, sim: &Simulation, done: &Done) -> Output {
    let (stats, t0) = (&done.stats, sim.t0());
    let model = sim.model();
    let n_rotors = model.n_hinges() - sim.layout().n_hinges;
    let mut s = String::new();
    let _ = writeln!(s, "scene      {}", scene_path.display());
    let _ = writeln!(
        s,
        "model      {} bodies, {} hinges{}",
        model.n_bodies() - n_rotors,
        sim.layout().n_hinges,
        if n_rotors > 0 {
            format!(", {n_rotors} wheel rotors")
        } else {
            String::new()
        }
    );
    let names = sim.effect_names();
    let _ = writeln!(
        s,
        "effects    {}",
        if names.is_empty() {
            "none (torque-free)".to_owned()
        } else {
            names.join(", ")
        }
    );
    let _ = writeln!(
        s,
        "state      {} components; integrator {}",
        sim.layout().len,
        scene.options.method
    );
    let _ = writeln!(
        s,
        "ran        t = {t0} .. {} s: {} steps ({} rejected), {} rhs evaluations{}, {} events, {:.3} s wall",
        stats.t_final,
        stats.steps_accepted,
        stats.steps_rejected,
        stats.rhs_evals,
        if stats.jacobian_evals > 0 {
            let updated = if stats.jacobian_updates > 0 {
                format!(" and {} updated", stats.jacobian_updates)
            } else {
                String::new()
            };
            format!(
                " ({} Jacobians{updated}, {} LU factorisations)",
                stats.jacobian_evals, stats.lu_decompositions
            )
        } else {
            String::new()
        },
        // Every event of the log (`events.csv`): the integrator's crossings and the effects'
        // own, a fault at its time among them.
        sim.event_log().len(),
        done.elapsed
    );
    for (t, what) in sim.event_log().iter().take(10) {
        let _ = writeln!(s, "  event    t = {t:.4} s: {what}");
    }
    if sim.event_log().len() > 10 {
        let _ = writeln!(s, "  ...      {} more events", sim.event_log().len() - 10);
    }
    if done.n_events > 0 {
        let _ = writeln!(
            s,
            "events     {} in {}",
            done.n_events,
            done.events_path.display()
        );
    }
    if let (Some(first), Some(last)) = (
        done.first_row.as_ref(),
        Some(&done.last_row).filter(|r| !r.is_empty()),
    ) {
        let col = |name: &str| done.columns.iter().position(|c| c == name);
        if let (Some(e), Some(h)) = (col("total_energy"), col("h_norm")) {
            let _ = writeln!(
                s,
                "energy     {:.6e} J -> {:.6e} J; |h| {:.6e} -> {:.6e} N m s",
                first[e], last[e], first[h], last[h]
            );
        }
        if let Some(b) = col("energy_budget") {
            // The budget (energy + dissipated − actuator work) is constant for exact physics:
            // its change is the integration error, the line a user checks a run by.
            let _ = writeln!(
                s,
                "budget     {:.9e} J -> {:.9e} J (change {:.2e} J)",
                first[b],
                last[b],
                last[b] - first[b]
            );
        }
    }
    let _ = writeln!(
        s,
        "wrote      {} ({} rows){}",
        done.csv_path.display(),
        done.n_rows,
        if done.plots.is_empty() {
            String::new()
        } else {
            format!(
                " and {} plots ({})",
                done.plots.len(),
                done.plots.join(", ")
            )
        }
    );
    if let Some(v) = &done.view {
        let _ = writeln!(s, "view       {}", v.display());
    }
    s
}

/// Progress in milliseconds of simulated time (indicatif counts in whole units).
fn progress_units(dt: f64) -> u64 {
    (dt.max(0.0) * 1e3) as u64
}

/// The run's progress bar on standard error: simulated time done, its rate and the time
/// left. Hidden when standard error is not a terminal (tests, pipes, log files).
fn progress_bar(t0: f64, t_end: f64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(
        Some(progress_units(t_end - t0)),
        ProgressDrawTarget::stderr(),
    );
    bar.set_style(
        ProgressStyle::with_template("[{bar:30}] {percent:>3}%  t = {msg} s  {eta} left")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("#> "),
    );
    bar.set_message(format!("{t0}"));
    bar
}

/// Why the output sink stopped the run.
#[derive(Debug)]
enum Stop {
    /// Writing the CSV failed.
    Write(std::io::Error),
    /// Ctrl-C.
    Interrupted,
    /// Recording the poses of the 3-D view failed.
    View(ViewError),
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Write(e) => write!(f, "{e}"),
            Stop::Interrupted => f.write_str("interrupted"),
            Stop::View(e) => write!(f, "{e}"),
        }
    }
}

/// Ctrl-C, through `ctrlc` (its handler runs on a thread of its own, so it may do more than
/// a signal handler could). The first SIGINT starts the clean stop (the run stops at its next
/// row, the CSV is completed, the message printed). Further SIGINTs within
/// [`interrupt::GRACE`] of it are ignored, so that a burst (a process group signalled twice, a
/// double key press) cannot lose what the first one is finishing; a SIGINT after the grace
/// period ends the process at once with status 130.
pub(crate) mod interrupt {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Mutex, OnceLock};
    use std::time::{Duration, Instant};

    /// How long after the first SIGINT further ones are ignored.
    pub const GRACE: Duration = Duration::from_secs(2);

    static REQUESTED: AtomicBool = AtomicBool::new(false);
    static FIRST: OnceLock<Mutex<Option<Instant>>> = OnceLock::new();

    /// Whether Ctrl-C was pressed since [`install`].
    pub fn requested() -> bool {
        REQUESTED.load(Ordering::Relaxed)
    }

    fn on_sigint() {
        let first = FIRST.get_or_init(|| Mutex::new(None));
        let mut first = first.lock().unwrap_or_else(|e| e.into_inner());
        match *first {
            None => {
                *first = Some(Instant::now());
                REQUESTED.store(true, Ordering::SeqCst);
            }
            Some(at) if at.elapsed() < GRACE => {}
            Some(_) => std::process::exit(i32::from(super::EXIT_INTERRUPTED)),
        }
    }

    /// Installs the handler (once per process; a failure to install leaves Ctrl-C's default,
    /// which still stops the run, without the clean stop).
    pub fn install() {
        REQUESTED.store(false, Ordering::Relaxed);
        static INSTALLED: OnceLock<()> = OnceLock::new();
        INSTALLED.get_or_init(|| {
            if let Err(e) = ctrlc::set_handler(on_sigint) {
                eprintln!("warning: Ctrl-C will not stop the run cleanly: {e}");
            }
        });
    }
}
