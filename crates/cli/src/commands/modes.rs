//! `satsim modes SCENE.toml [--along HINGE=FROM:TO:N[,HINGE=FROM:TO] [--plot FILE.svg]]`
//! (contract section 9): the structural modes of a scene at its initial state, from
//! [`satsim_tools::modes`].
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

use super::linearize::scene_error;
use super::{CliError, Output, stem, to_json, usage};
use satsim_tools::modes::{Along, Mode, Modes, SweepPoint, modes, sweep, sweep_plot};
use satsim_tools::scene::Scene;
use serde::ser::{Serialize, SerializeMap, Serializer};
use std::path::{Path, PathBuf};

/// Configurations of a sweep when `--along` gives no `N`.
pub const DEFAULT_STEPS: usize = 21;

/// The flags of `satsim modes`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (TOML, cli-contract section 7)
    #[arg(value_name = "SCENE.toml")]
    pub scene: PathBuf,
    /// Sweep hinge angles (rad, ends included) in N configurations (default 21) and print the
    /// modes at each; comma-separated hinges move together, e.g. `h4=3.1:0:31,h5=-3.1:0`
    #[arg(long, value_name = "HINGE=FROM:TO[:N][,...]")]
    pub along: Option<String>,
    /// Where to draw the swept frequencies against the first hinge's angle (needs `--along`)
    /// [default: out/<scene stem>-modes.svg]
    #[arg(long, value_name = "FILE.svg", requires = "along")]
    pub plot: Option<PathBuf>,
    /// Override a scene value by its dotted path, e.g. `--set duration=60` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::run::parse_override)]
    pub set: Vec<satsim_tools::scene_keys::Override>,
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

/// Runs `satsim modes`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let path = &args.scene;
    let along = args
        .along
        .as_deref()
        .map(|a| parse_along(a).map_err(|e| usage(&["modes"], format!("`--along` {e}"))))
        .transpose()?;
    let scene = Scene::read_to_linearise(path, &args.set)?;
    super::print_warnings(&scene.warnings);
    let Some((along, steps)) = along else {
        let m = modes(&scene).map_err(|e| scene_error(path, e))?;
        // A warning, not an error: a linear model about a motion is still what a controller
        // is checked against (`docs/src/guide/modes.md`).
        super::print_warnings(m.not_equilibrium.as_slice());
        return to_json(&ModesJson(&m));
    };
    let points = sweep(&scene, &along, steps).map_err(|e| scene_error(path, e))?;
    let moving: Vec<&SweepPoint> = points
        .iter()
        .filter(|p| p.modes.not_equilibrium.is_some())
        .collect();
    if let Some(first) = moving.first() {
        super::print_warnings(&[format!(
            "{} of the {} configurations are not equilibria; at the first ({}): {}",
            moving.len(),
            points.len(),
            along
                .iter()
                .zip(&first.angles)
                .map(|(a, v)| format!("{} = {v}", a.hinge))
                .collect::<Vec<_>>()
                .join(", "),
            first.modes.not_equilibrium.as_deref().unwrap_or_default()
        )]);
    }
    let plot = args
        .plot
        .clone()
        .unwrap_or_else(|| Path::new("out").join(format!("{}-modes.svg", stem(path))));
    let title = format!(
        "frequencies of {} over the sweep",
        path.file_name()
            .map(|s| s.to_string_lossy())
            .unwrap_or_default()
    );
    write_plot(&plot, &sweep_plot(&points, &along, &title))?;
    to_json(&SweepJson {
        along: along.iter().map(|a| a.hinge.as_str()).collect(),
        points: points
            .iter()
            .map(|p| PointJson {
                angles: &p.angles,
                frequencies_hz: &p.modes.frequencies_hz,
                damping_ratios: &p.modes.damping_ratios,
                rigid_modes: p.modes.rigid_modes,
                locked: &p.modes.locked,
            })
            .collect(),
        plot: plot.to_string_lossy().into_owned(),
    })
}

fn write_plot(path: &PathBuf, svg: &str) -> Result<(), CliError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::Other(format!("cannot create {}: {e}", dir.display())))?;
    }
    std::fs::write(path, svg)
        .map_err(|e| CliError::Other(format!("cannot write {}: {e}", path.display())))
}

/// `--along`'s output.
#[derive(serde::Serialize)]
struct SweepJson<'a> {
    along: Vec<&'a str>,
    points: Vec<PointJson<'a>>,
    plot: String,
}

/// One configuration of a sweep.
#[derive(serde::Serialize)]
struct PointJson<'a> {
    angles: &'a [f64],
    frequencies_hz: &'a [f64],
    damping_ratios: &'a [f64],
    rigid_modes: usize,
    locked: &'a [String],
}

/// A mode shape: an object from state name to value, in the linear model's state order.
struct Shape<'a>(&'a [(String, f64)]);

impl Serialize for Shape<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// One mode of the contract's object.
struct ModeJson<'a>(&'a Mode);

impl Serialize for ModeJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let m = self.0;
        let mut map = s.serialize_map(Some(5))?;
        map.serialize_entry("frequency_hz", &m.frequency_hz)?;
        map.serialize_entry("damping_ratio", &m.damping_ratio)?;
        map.serialize_entry("eigenvalue", &[m.eigenvalue.0, m.eigenvalue.1])?;
        map.serialize_entry("shape", &Shape(&m.shape))?;
        map.serialize_entry("shape_imag", &Shape(&m.shape_imag))?;
        map.end()
    }
}

/// The modes as the contract's JSON object.
struct ModesJson<'a>(&'a Modes);

impl Serialize for ModesJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let m = self.0;
        let modes: Vec<ModeJson> = m.modes.iter().map(ModeJson).collect();
        let mut map = s.serialize_map(Some(7))?;
        map.serialize_entry("frequencies_hz", &m.frequencies_hz)?;
        map.serialize_entry("damping_ratios", &m.damping_ratios)?;
        map.serialize_entry("rigid_modes", &m.rigid_modes)?;
        map.serialize_entry("modes", &modes)?;
        map.serialize_entry("real_eigenvalues", &m.real_eigenvalues)?;
        map.serialize_entry("locked", &m.locked)?;
        map.serialize_entry("released", &m.released)?;
        map.end()
    }
}
