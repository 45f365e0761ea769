//! `satsim preprint --model MODEL.toml --state STATE.json` (contract section 4): the
//! preprint's closed-form S and N (errata corrected, see docs/src/preprint/errata.md) beside
//! the same matrices from the generic engine, and their largest absolute difference.

use super::{CliError, ModelAndState, ModelStateArgs, Output, rows, to_json};
use satsim_satellite::{PreprintError, compare};
use serde::Serialize;

/// The flags of `satsim preprint`.
pub type Args = ModelStateArgs;

/// The printed object, in the contract's key order.
#[derive(Serialize)]
#[allow(non_snake_case)] // the contract's keys
struct Json {
    S_closed_form: Vec<Vec<f64>>,
    N_closed_form: Vec<f64>,
    S_tree: Vec<Vec<f64>>,
    N_tree: Vec<f64>,
    max_abs_difference: f64,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let ModelAndState {
        model_path,
        state_path,
        model,
        state,
    } = ModelAndState::read(args, "preprint")?;
    // Every number printed is finite: an overflow is an error naming the quantity (and the
    // state file), a singular (massless) model one naming the model file.
    let report = compare(&model, &state.q, &state.v, &state.tau).map_err(|e| {
        let file = match e {
            PreprintError::Layout(_) | PreprintError::Dynamics(_) => &model_path,
            _ => &state_path,
        };
        CliError::Other(format!("{}: {e}", file.display()))
    })?;
    to_json(&Json {
        S_closed_form: rows(&report.s_closed_form),
        N_closed_form: report.n_closed_form.iter().copied().collect(),
        S_tree: rows(&report.s_tree),
        N_tree: report.n_tree.iter().copied().collect(),
        max_abs_difference: report.max_abs_difference,
    })
}
