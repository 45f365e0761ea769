//! `satsim linearize SCENE.toml` (contract section 9): the linear model `ż = A z + B u` of a
//! scene at its initial state, every enabled effect included, as one JSON object
//! (`states`, `inputs`, `A`, `B`, plus `error_estimate`, `locked`, `released` and `residual`). The work
//! is [`satsim_tools::linearize`]'s; this is its command-line face.

use super::{CliError, Output, rows, to_json};
use satsim_tools::linearize::{Linearization, linearize};
use satsim_tools::scene::Scene;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The flags of `satsim linearize`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (TOML, cli-contract section 7)
    #[arg(value_name = "SCENE.toml")]
    pub scene: PathBuf,
    /// Override a scene value by its dotted path, e.g. `--set duration=60` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::run::parse_override)]
    pub set: Vec<satsim_tools::scene_keys::Override>,
}

/// The printed object, in the contract's key order.
#[derive(Serialize)]
#[allow(non_snake_case)] // the contract's keys
struct Json<'a> {
    states: &'a [String],
    inputs: &'a [String],
    A: Vec<Vec<f64>>,
    B: Vec<Vec<f64>>,
    error_estimate: f64,
    locked: &'a [String],
    released: &'a [String],
    residual: &'a [f64],
}

/// Runs `satsim linearize`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let scene = Scene::read_to_linearise(&args.scene, &args.set)?;
    super::print_warnings(&scene.warnings);
    let lin = linearize(&scene).map_err(|e| scene_error(&args.scene, e))?;
    super::print_warnings(lin.not_an_equilibrium().as_slice());
    to_json(&json(&lin))
}

/// A failure to linearise a scene that was read, naming the scene file.
pub fn scene_error(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::Other(format!("{}: {e}", path.display()))
}

fn json(lin: &Linearization) -> Json<'_> {
    Json {
        states: &lin.states,
        inputs: &lin.inputs,
        A: rows(&lin.a),
        B: rows(&lin.b),
        error_estimate: lin.error_estimate,
        locked: &lin.locked,
        released: &lin.released,
        residual: &lin.residual,
    }
}
