//! `satsim run SCENE.toml [--out DIR] [--set KEY=VALUE]...` (contract section 7): integrates a
//! scene (with `--set` overrides, see [`satsim_satellite::scene_keys`]), streams
//! `DIR/trajectory.csv` row by row (flushed, so a failed run leaves a valid file up to its
//! last row), writes every event to `DIR/events.csv`, draws SVG plots of the main quantities
//! at the end, shows a progress bar on
//! standard error when it is a terminal, and prints a short summary on standard output.
//!
//! Exit status: 0 on success, 2 for bad input (the scene, its model or state, the command
//! line), 1 for a run that fails part-way (the message says when and why), 130 for a run
//! interrupted by Ctrl-C (SIGINT): the run stops at the next output row, the CSV holds every
//! row up to it and standard error says `interrupted at t = … s; N rows written to …`. A
//! second Ctrl-C kills the process at once.
//! `satsim` with no arguments runs the default scene `examples/scenes/deploy.toml`.

use super::{CliError, Options, Output, usage_line};
use satsim_integrate::Output as Times;
use satsim_satellite::output::{CsvWriter, write_events, write_plots};
use satsim_satellite::scene::Scene;
use satsim_satellite::scene_keys::Override;
use satsim_satellite::simulation::RunError;
use std::ffi::OsString;
use std::fmt::Write as _;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

const NAME: &str = "run";

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

/// For the dispatcher: every failure as a [`CliError`] (exit status 2). The binary calls
/// [`command`] directly to tell run failures (status 1) apart.
pub fn run(args: &[OsString]) -> Result<Output, CliError> {
    command(args).map_err(|f| match f {
        Failure::BadInput(e) => e,
        Failure::Run(m) | Failure::Interrupted(m) => CliError::Other(m),
    })
}

/// Runs `satsim run ARGS`.
pub fn command(args: &[OsString]) -> Result<Output, Failure> {
    let opts = Options::parse(NAME, args, &["out", "set"], 1)?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let scene_path = opts
        .positional
        .first()
        .map(PathBuf::from)
        .ok_or_else(|| CliError::Usage {
            command: Some(NAME),
            message: "missing the scene file".into(),
        })?;
    run_scene_with(&scene_path, opts.path("out"), &opts.overrides(NAME)?)
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
    let scene = Scene::read_with(scene_path, overrides).map_err(CliError::File)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let mut sim = scene
        .simulation()
        .map_err(|e| CliError::Other(format!("{}: {e}", scene_path.display())))?;
    let stem = scene_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let dir = out.unwrap_or_else(|| Path::new("out").join(&stem));
    std::fs::create_dir_all(&dir).map_err(|e| {
        CliError::Other(format!(
            "cannot create the output folder {}: {e}",
            dir.display()
        ))
    })?;
    let csv_path = dir.join("trajectory.csv");
    let columns = sim.columns();
    let mut csv = CsvWriter::create(&csv_path, &columns)
        .map_err(|e| CliError::Other(format!("cannot write {}: {e}", csv_path.display())))?;

    let progress = std::io::stderr().is_terminal();
    let (t0, t_end) = (sim.t0(), sim.t0() + scene.duration);
    let started = Instant::now();
    let mut last_draw = started;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    interrupt::install();
    let result = sim.run(
        &scene.options,
        t_end,
        &Times::Interval(scene.every),
        |t, row| -> Result<(), Stop> {
            csv.row(row).map_err(Stop::Write)?;
            rows.push(row.to_vec());
            if progress && (last_draw.elapsed().as_millis() >= 100 || t >= t_end) {
                last_draw = Instant::now();
                draw_progress((t - t0) / (t_end - t0), t);
            }
            // Checked after the row is written, so the CSV ends with a complete row.
            if interrupt::requested() {
                return Err(Stop::Interrupted);
            }
            Ok(())
        },
    );
    if progress {
        eprint!("\r{:60}\r", "");
    }
    let elapsed = started.elapsed().as_secs_f64();
    let last_t = rows.last().map(|r| r[0]);
    // Every event, not only the ten in the summary (also for a run that failed or was interrupted).
    let events_path = dir.join("events.csv");
    let n_events = write_events(&events_path, sim.event_records())
        .map_err(|e| Failure::Run(format!("cannot write {}: {e}", events_path.display())))?;
    let stats = match result {
        Ok(stats) => stats,
        Err(RunError::Sink {
            t,
            error: Stop::Interrupted,
        }) => {
            return Err(Failure::Interrupted(format!(
                "interrupted at t = {t} s; {} rows written to {}",
                rows.len(),
                csv_path.display()
            )));
        }
        Err(e) => {
            let why = match e {
                RunError::Integrate(e) => e.to_string(),
                RunError::Sink { t, error } => {
                    format!("cannot write {} at t = {t} s: {error}", csv_path.display())
                }
            };
            let kept = match last_t {
                Some(t) => format!("{} holds the rows up to t = {t} s", csv_path.display()),
                None => format!("{} holds only the header", csv_path.display()),
            };
            return Err(Failure::Run(format!(
                "{}: the run failed: {why}; {kept}",
                scene_path.display()
            )));
        }
    };

    let plots = if scene.plots && !rows.is_empty() {
        write_plots(&dir, &columns, &rows).map_err(|e| {
            Failure::Run(format!("cannot write the plots in {}: {e}", dir.display()))
        })?
    } else {
        Vec::new()
    };

    // Summary.
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
        "ran        t = {t0} .. {} s: {} steps ({} rejected), {} rhs evaluations, {} events, {:.3} s wall",
        stats.t_final,
        stats.steps_accepted,
        stats.steps_rejected,
        stats.rhs_evals,
        stats.events.len(),
        elapsed
    );
    for (t, what) in sim.event_log().iter().take(10) {
        let _ = writeln!(s, "  event    t = {t:.4} s: {what}");
    }
    if sim.event_log().len() > 10 {
        let _ = writeln!(s, "  ...      {} more events", sim.event_log().len() - 10);
    }
    if n_events > 0 {
        let _ = writeln!(s, "events     {n_events} in {}", events_path.display());
    }
    if let (Some(first), Some(last)) = (rows.first(), rows.last()) {
        let col = |name: &str| columns.iter().position(|c| c == name);
        if let (Some(e), Some(h)) = (col("total_energy"), col("h_norm")) {
            let _ = writeln!(
                s,
                "energy     {:.6e} J -> {:.6e} J; |h| {:.6e} -> {:.6e} N m s",
                first[e], last[e], first[h], last[h]
            );
        }
    }
    let _ = writeln!(
        s,
        "wrote      {} ({} rows){}",
        csv_path.display(),
        rows.len(),
        if plots.is_empty() {
            String::new()
        } else {
            format!(" and {} plots ({})", plots.len(), plots.join(", "))
        }
    );
    Ok(s)
}

fn draw_progress(frac: f64, t: f64) {
    let frac = frac.clamp(0.0, 1.0);
    let width = 30;
    let done = (frac * width as f64).round() as usize;
    let mut err = std::io::stderr().lock();
    let _ = write!(
        err,
        "\r[{}{}] {:5.1}%  t = {t:.1} s",
        "#".repeat(done),
        " ".repeat(width - done),
        100.0 * frac
    );
    let _ = err.flush();
}

/// Why the output sink stopped the run.
#[derive(Debug)]
enum Stop {
    /// Writing the CSV failed.
    Write(std::io::Error),
    /// Ctrl-C.
    Interrupted,
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Write(e) => write!(f, "{e}"),
            Stop::Interrupted => f.write_str("interrupted"),
        }
    }
}

/// Ctrl-C: a SIGINT handler that only sets a flag (async-signal-safe) and restores the
/// default action, so that a second Ctrl-C kills the process at once.
mod interrupt {
    use std::sync::atomic::{AtomicBool, Ordering};

    static REQUESTED: AtomicBool = AtomicBool::new(false);

    /// Whether Ctrl-C was pressed since [`install`].
    pub fn requested() -> bool {
        REQUESTED.load(Ordering::Relaxed)
    }

    #[cfg(unix)]
    extern "C" fn on_sigint(_: libc::c_int) {
        REQUESTED.store(true, Ordering::Relaxed);
        // SAFETY: `signal` is async-signal-safe; SIG_DFL is a valid disposition.
        unsafe {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
        }
    }

    /// Installs the handler (a no-op where signals are not supported).
    pub fn install() {
        REQUESTED.store(false, Ordering::Relaxed);
        #[cfg(unix)]
        // SAFETY: the handler only touches an atomic and calls `signal`, both
        // async-signal-safe.
        unsafe {
            let handler: extern "C" fn(libc::c_int) = on_sigint;
            libc::signal(libc::SIGINT, handler as libc::sighandler_t);
        }
    }
}
