//! `satsim modes SCENE.toml [--along HINGE=FROM:TO:N[,HINGE=FROM:TO] [--plot FILE.svg]]`
//! (contract section 9): the structural modes of a scene at its initial state, from
//! [`satsim_satellite::modes`].
//!
//! Without `--along`: one JSON object, `frequencies_hz` (ascending), `damping_ratios`,
//! `rigid_modes`, `modes` (each with `frequency_hz`, `damping_ratio`, `eigenvalue`,
//! `shape`, `shape_imag`), `real_eigenvalues` and `locked`.
//!
//! With `--along`: the modes in `N` configurations from `FROM` to `TO` (rad, ends included)
//! of the named hinge, every other part of the initial state as in the scene; several
//! hinges, comma-separated, move together (an accordion-folded array: `h4=3.1:0:31,h5=-3.1:0`).
//! Prints one JSON object (`along`, `points`: each with `angles`, `frequencies_hz`,
//! `damping_ratios`, `rigid_modes`, `locked`; `plot`) and draws the frequencies against
//! the first hinge's angle into `--plot` (default `out/<scene stem>-modes.svg`).

use super::linearize::{json_string, json_strings, scene_error, scene_path};
use super::{CliError, Options, Output, json_array, json_number, usage_line};
use satsim_satellite::modes::{Along, Mode, Modes, modes, sweep, sweep_plot};
use satsim_satellite::scene::Scene;
use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const NAME: &str = "modes";

/// Configurations of a sweep when `--along` gives no `N`.
pub const DEFAULT_STEPS: usize = 21;

fn usage(message: impl Into<String>) -> CliError {
    CliError::Usage {
        command: Some(NAME),
        message: message.into(),
    }
}

/// Parses `HINGE=FROM:TO[:N]` items separated by commas: the hinges and the number of
/// configurations (the `N`s given must agree; default [`DEFAULT_STEPS`]).
pub fn parse_along(text: &str) -> Result<(Vec<Along>, usize), String> {
    let mut along = Vec::new();
    let mut steps: Option<usize> = None;
    for item in text.split(',') {
        let item = item.trim();
        let (spec, n) = match item.split(':').count() {
            3 => {
                let (spec, n) = item.rsplit_once(':').unwrap_or((item, ""));
                let n = n
                    .trim()
                    .parse::<usize>()
                    .ok()
                    .filter(|n| *n >= 2)
                    .ok_or_else(|| format!("`{item}`: N must be a whole number >= 2, got `{n}`"))?;
                (spec, Some(n))
            }
            2 => (item, None),
            _ => return Err(format!("`{item}`: expected HINGE=FROM:TO:N")),
        };
        if let Some(n) = n {
            if steps.is_some_and(|s| s != n) {
                return Err(format!("`{text}`: the hinges' N differ"));
            }
            steps = Some(n);
        }
        along.push(Along::parse(spec)?);
    }
    Ok((along, steps.unwrap_or(DEFAULT_STEPS)))
}

/// Runs `satsim modes ARGS`.
pub fn run(args: &[OsString]) -> Result<Output, CliError> {
    let opts = Options::parse(NAME, args, &["along", "plot"], 1)?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let path = scene_path(NAME, &opts)?;
    let along = match opts.get("along") {
        Some(a) => {
            Some(parse_along(&a.to_string_lossy()).map_err(|e| usage(format!("`--along` {e}")))?)
        }
        None => {
            if opts.get("plot").is_some() {
                return Err(usage("`--plot` needs `--along`"));
            }
            None
        }
    };
    let scene = Scene::read(&path)?;
    match along {
        None => {
            let m = modes(&scene).map_err(|e| scene_error(&path, e))?;
            Ok(modes_json(&m))
        }
        Some((along, steps)) => {
            let points = sweep(&scene, &along, steps).map_err(|e| scene_error(&path, e))?;
            let plot = opts.path("plot").unwrap_or_else(|| {
                let stem = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "scene".into());
                Path::new("out").join(format!("{stem}-modes.svg"))
            });
            let title = format!(
                "frequencies of {} over the sweep",
                path.file_name()
                    .map(|s| s.to_string_lossy())
                    .unwrap_or_default()
            );
            let svg = sweep_plot(&points, &along, &title);
            write_plot(&plot, &svg)?;
            let mut out = String::from("{\n");
            let names: Vec<String> = along.iter().map(|a| a.hinge.clone()).collect();
            let _ = writeln!(out, "  \"along\": {},", json_strings(&names));
            out.push_str("  \"points\": [\n");
            for (i, p) in points.iter().enumerate() {
                let _ = writeln!(
                    out,
                    "    {{\"angles\": {}, \"frequencies_hz\": {}, \"damping_ratios\": {}, \"rigid_modes\": {}, \"locked\": {}}}{}",
                    json_array(p.angles.iter().copied()),
                    json_array(p.modes.frequencies_hz.iter().copied()),
                    json_array(p.modes.damping_ratios.iter().copied()),
                    p.modes.rigid_modes,
                    json_strings(&p.modes.locked),
                    if i + 1 < points.len() { "," } else { "" }
                );
            }
            out.push_str("  ],\n");
            let _ = writeln!(out, "  \"plot\": {}", json_string(&plot.to_string_lossy()));
            out.push_str("}\n");
            Ok(out)
        }
    }
}

fn write_plot(path: &PathBuf, svg: &str) -> Result<(), CliError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::Other(format!("cannot create {}: {e}", dir.display())))?;
    }
    std::fs::write(path, svg)
        .map_err(|e| CliError::Other(format!("cannot write {}: {e}", path.display())))
}

fn shape_json(shape: &[(String, f64)]) -> String {
    let items: Vec<String> = shape
        .iter()
        .map(|(k, v)| format!("{}: {}", json_string(k), json_number(*v)))
        .collect();
    format!("{{{}}}", items.join(", "))
}

fn mode_json(m: &Mode) -> String {
    format!(
        "{{\"frequency_hz\": {}, \"damping_ratio\": {}, \"eigenvalue\": {},\n     \"shape\": {},\n     \"shape_imag\": {}}}",
        json_number(m.frequency_hz),
        json_number(m.damping_ratio),
        json_array([m.eigenvalue.0, m.eigenvalue.1]),
        shape_json(&m.shape),
        shape_json(&m.shape_imag),
    )
}

/// The modes as the contract's JSON object.
pub fn modes_json(m: &Modes) -> String {
    let modes: Vec<String> = m.modes.iter().map(mode_json).collect();
    format!(
        "{{\n  \"frequencies_hz\": {},\n  \"damping_ratios\": {},\n  \"rigid_modes\": {},\n  \"modes\": [\n    {}\n  ],\n  \"real_eigenvalues\": {},\n  \"locked\": {},\n  \"released\": {}\n}}\n",
        json_array(m.frequencies_hz.iter().copied()),
        json_array(m.damping_ratios.iter().copied()),
        m.rigid_modes,
        modes.join(",\n    "),
        json_array(m.real_eigenvalues.iter().copied()),
        json_strings(&m.locked),
        json_strings(&m.released),
    )
}
