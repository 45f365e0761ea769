//! `satsim accuracy SCENE.toml [--out DIR] [--repeats N] [--methods LIST] [--quick]`: the
//! work-precision sweep of [`satsim_satellite::accuracy`] on a scene. Writes
//! `DIR/accuracy.csv`, `DIR/accuracy.svg` (final error against wall time, log-log),
//! `DIR/accuracy_rhs.svg` (against right-hand-side evaluations) and `DIR/accuracy.md`, and
//! prints a short summary. `DIR` defaults to `out/<scene stem>-accuracy`.

use super::{CliError, Options, Output, usage_line};
use satsim_integrate::Method;
use satsim_satellite::accuracy::{Cost, Sweep, fmt_seconds, method_label, sweep};
use satsim_satellite::scene::Scene;
use std::ffi::OsString;
use std::fmt::Write as _;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

const NAME: &str = "accuracy";

fn usage(message: impl Into<String>) -> CliError {
    CliError::Usage {
        command: Some(NAME),
        message: message.into(),
    }
}

/// Runs `satsim accuracy ARGS`.
pub fn run(args: &[OsString]) -> Result<Output, CliError> {
    // `--quick` is a flag (no value); the shared parser only knows value options.
    let quick = args.iter().any(|a| a == "--quick");
    let rest: Vec<OsString> = args.iter().filter(|a| *a != "--quick").cloned().collect();
    let opts = Options::parse(NAME, &rest, &["out", "repeats", "methods"], 1)?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let scene_path = opts
        .positional
        .first()
        .map(PathBuf::from)
        .ok_or_else(|| usage("missing the scene file"))?;
    let scene = Scene::read(&scene_path)?;
    let mut plan = if quick {
        Sweep::quick(&scene)
    } else {
        Sweep::full(&scene)
    };
    if let Some(r) = opts.get("repeats") {
        let text = r.to_string_lossy();
        plan.repeats = match text.parse::<usize>() {
            Ok(n) if n > 0 => n,
            _ => {
                return Err(usage(format!(
                    "`--repeats` must be a whole number > 0, got `{text}`"
                )));
            }
        };
    }
    if let Some(m) = opts.get("methods") {
        let text = m.to_string_lossy();
        let mut methods = Vec::new();
        for name in text.split(',') {
            let method = name
                .parse::<Method>()
                .map_err(|e| usage(format!("`--methods`: {e}")))?;
            if !methods.contains(&method) {
                methods.push(method);
            }
        }
        plan.methods = methods;
    }
    let stem = scene_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let dir = opts
        .path("out")
        .unwrap_or_else(|| Path::new("out").join(format!("{stem}-accuracy")));

    let progress = std::io::stderr().is_terminal();
    let total = plan.settings().len() + 2;
    let mut done = 0usize;
    let report = sweep(&scene, &plan, |what| {
        if progress {
            done += 1;
            let mut err = std::io::stderr().lock();
            let _ = write!(err, "\r[{done}/{total}] {what:<40}");
            let _ = err.flush();
        }
    })
    .map_err(|e| CliError::Other(format!("{}: {e}", scene_path.display())))?;
    if progress {
        eprint!("\r{:60}\r", "");
    }

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
