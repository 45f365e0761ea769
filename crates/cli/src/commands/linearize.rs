//! `satsim linearize SCENE.toml` (contract section 9): the linear model `ż = A z + B u` of a
//! scene at its initial state, every enabled effect included, as one JSON object
//! (`states`, `inputs`, `A`, `B`, plus `error_estimate` and `locked`). The work is
//! [`satsim_satellite::linearize`]'s; this is its command-line face.

use super::{CliError, Options, Output, json_array, json_number, usage_line};
use satsim_satellite::linearize::{Linearization, linearize};
use satsim_satellite::scene::Scene;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

const NAME: &str = "linearize";

/// The scene file named by the one positional argument of `command`.
pub fn scene_path(command: &'static str, opts: &Options) -> Result<PathBuf, CliError> {
    opts.positional
        .first()
        .map(PathBuf::from)
        .ok_or_else(|| CliError::Usage {
            command: Some(command),
            message: "missing the scene file".into(),
        })
}

/// A JSON string.
pub fn json_string(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

/// A JSON array of strings on one line.
pub fn json_strings<'a>(xs: impl IntoIterator<Item = &'a String>) -> String {
    let items: Vec<String> = xs.into_iter().map(|s| json_string(s)).collect();
    format!("[{}]", items.join(", "))
}

/// Runs `satsim linearize ARGS`.
pub fn run(args: &[OsString]) -> Result<Output, CliError> {
    let opts = Options::parse(NAME, args, &[], 1)?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let path = scene_path(NAME, &opts)?;
    let scene = Scene::read(&path)?;
    let lin = linearize(&scene).map_err(|e| scene_error(&path, e))?;
    Ok(to_json(&lin))
}

/// A failure to linearise a scene that was read, naming the scene file.
pub fn scene_error(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::Other(format!("{}: {e}", path.display()))
}

fn matrix(m: &nalgebra::DMatrix<f64>) -> String {
    let rows: Vec<String> = (0..m.nrows())
        .map(|r| json_array(m.row(r).iter().copied()))
        .collect();
    format!("[\n    {}\n  ]", rows.join(",\n    "))
}

/// The linearisation as the contract's JSON object.
pub fn to_json(lin: &Linearization) -> String {
    format!(
        "{{\n  \"states\": {},\n  \"inputs\": {},\n  \"A\": {},\n  \"B\": {},\n  \"error_estimate\": {},\n  \"locked\": {},\n  \"released\": {}\n}}\n",
        json_strings(&lin.states),
        json_strings(&lin.inputs),
        matrix(&lin.a),
        matrix(&lin.b),
        json_number(lin.error_estimate),
        json_strings(&lin.locked),
        json_strings(&lin.released),
    )
}
