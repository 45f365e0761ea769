//! `satsim accuracy SCENE.toml [--out DIR] [--repeats N] [--methods LIST] [--tolerances LIST]
//! [--quick]`: the work-precision sweep of [`satsim_tools::accuracy`] on a scene. Writes
//! `DIR/accuracy.csv`, `DIR/accuracy.svg` (final error against wall time, log-log),
//! `DIR/accuracy_rhs.svg` (against right-hand-side evaluations) and `DIR/accuracy.md`, and
//! prints a short summary. `DIR` defaults to `out/<scene stem>-accuracy`.

use super::{CliError, Output, at_least_one, stem};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use satsim_integrate::Method;
use satsim_tools::accuracy::{Cost, Sweep, fmt_seconds, method_label, sweep};
use satsim_tools::scene::Scene;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The flags of `satsim accuracy`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (TOML, cli-contract section 7)
    #[arg(value_name = "SCENE.toml")]
    pub scene: PathBuf,
    /// Output folder [default: out/<scene stem>-accuracy]
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Timed repetitions of each setting (the fastest counts) [default: 3, 1 with --quick]
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub repeats: Option<usize>,
    /// The integrators to sweep, comma-separated: rk4, dp54, dop853, radau5 [default: all]
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_method)]
    pub methods: Vec<Method>,
    /// A short sweep (fewer settings): a quick look rather than the full figure
    #[arg(long)]
    pub quick: bool,
    /// The adaptive methods' tolerances, comma-separated, in place of the sweep's (`rtol`;
    /// `atol` the same), e.g. `--tolerances 1e-5,1.5e-5` to compare two settings
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_tolerance)]
    pub tolerances: Vec<f64>,
    /// Override a scene value by its dotted path, e.g. `--set duration=60` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::run::parse_override)]
    pub set: Vec<satsim_tools::scene_keys::Override>,
}

fn parse_method(s: &str) -> Result<Method, String> {
    s.parse::<Method>().map_err(|e| e.to_string())
}

/// A tolerance of `--tolerances`: finite and positive.
fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        Ok(t) => Err(format!("a tolerance must be finite and > 0, got {t}")),
        Err(e) => Err(format!("`{s}` is not a number: {e}")),
    }
}

/// Runs `satsim accuracy`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let scene_path = &args.scene;
    let scene = Scene::read_with(scene_path, &args.set)?;
    super::print_warnings(&scene.warnings);
    let mut plan = if args.quick {
        Sweep::quick(&scene)
    } else {
        Sweep::full(&scene)
    };
    if let Some(n) = args.repeats {
        plan.repeats = n;
    }
    if !args.tolerances.is_empty() {
        plan.tolerances = args.tolerances.clone();
    }
    if !args.methods.is_empty() {
        let mut methods = Vec::new();
        for &m in &args.methods {
            if !methods.contains(&m) {
                methods.push(m);
            }
        }
        plan.methods = methods;
    }
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(format!("{}-accuracy", stem(scene_path))));

    // Progress on standard error (drawn only when it is a terminal).
    let total = plan.settings().len() as u64 + 2;
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("[{bar:30}] {pos}/{len}  {elapsed} elapsed  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("#> "),
    );
    let report = sweep(&scene, &plan, |what| {
        bar.set_message(what.to_string());
        bar.inc(1);
    })
    .map_err(|e| CliError::Other(format!("{}: {e}", scene_path.display())))?;
    bar.finish_and_clear();

    std::fs::create_dir_all(&dir).map_err(|e| {
        CliError::Other(format!(
            "cannot create the output folder {}: {e}",
            dir.display()
        ))
    })?;
    let files = [
        ("accuracy.csv", report.csv()),
        ("accuracy.svg", report.svg(Cost::Seconds)),
        ("accuracy_rhs.svg", report.svg(Cost::RhsEvals)),
        ("accuracy.md", report.markdown()),
    ];
    for (name, text) in &files {
        let path = dir.join(name);
        std::fs::write(&path, text)
            .map_err(|e| CliError::Other(format!("cannot write {}: {e}", path.display())))?;
    }

    let mut s = String::new();
    let _ = writeln!(s, "scene      {}", scene_path.display());
    let _ = writeln!(
        s,
        "reference  {} at tol {:e} ({} rhs, {} s); {} for {}; floor {:.2e}",
        report.reference.method,
        report.reference.tol,
        report.reference.rhs_evals,
        fmt_seconds(report.reference.seconds),
        report.cross_reference.method,
        report.reference.method,
        report.floor.final_max
    );
    if !scene.elastic_error && plan.methods.iter().any(|&m| m != Method::Radau5) {
        let _ = writeln!(
            s,
            "elastic    radau5 leaves the elastic coordinates out of its error (`integrator.elastic_error = false`); the other methods count them, as the references do"
        );
    }
    let _ = writeln!(
        s,
        "{:<8} {:<12} {:>10} {:>10} {:>10} {:>10}",
        "method", "setting", "error", "rms", "time (s)", "rhs"
    );
    for p in &report.points {
        match &p.result {
            Ok(m) => {
                let _ = writeln!(
                    s,
                    "{:<8} {:<12} {:>10.2e} {:>10.2e} {:>10} {:>10}",
                    p.method.name(),
                    p.setting.label(),
                    m.errors.final_max,
                    m.errors.rms,
                    fmt_seconds(m.seconds),
                    m.rhs_evals
                );
            }
            Err(why) => {
                let _ = writeln!(
                    s,
                    "{:<8} {:<12} failed: {why}",
                    p.method.name(),
                    p.setting.label()
                );
            }
        }
    }
    for &m in &report.sweep.methods {
        let r = report.to_reach(m, 1e-8, Cost::Seconds);
        let _ = writeln!(
            s,
            "to 1e-8   {:<16} {}",
            method_label(m),
            match (&r.cheapest, r.interpolated) {
                (Some((setting, x)), i) => format!(
                    "{} s ({}){}",
                    fmt_seconds(x.seconds),
                    setting.label(),
                    i.map(|t| format!(", interpolated {} s", fmt_seconds(t)))
                        .unwrap_or_default()
                ),
                (None, _) => "not reached".into(),
            }
        );
    }
    let _ = writeln!(
        s,
        "wrote      {}",
        files
            .iter()
            .map(|(n, _)| dir.join(n).display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(s)
}
