//! `satsim preprint --model MODEL.toml --state STATE.json` (contract section 4): the
//! preprint's closed-form S and N (errata corrected, see docs/src/preprint/errata.md) beside
//! the same matrices from the generic engine, and their largest absolute difference.

use super::{CliError, ModelAndState, Options, Output, json_array, json_number, usage_line};
use satsim_satellite::preprint::{PreprintError, compare};

const NAME: &str = "preprint";

/// Runs the command.
pub fn run(args: &[std::ffi::OsString]) -> Result<Output, CliError> {
    let opts = Options::parse(NAME, args, &["model", "state"], 0)?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let ModelAndState {
        model_path,
        state_path,
        model,
        state,
    } = ModelAndState::read(NAME, &opts)?;
    // Every number printed is finite: an overflow is an error naming the quantity (and the
    // state file), a singular (massless) model one naming the model file.
    let report = compare(&model, &state.q, &state.v, &state.tau).map_err(|e| {
        let file = match e {
            PreprintError::Layout(_) | PreprintError::Dynamics(_) => &model_path,
            _ => &state_path,
        };
        CliError::Other(format!("{}: {e}", file.display()))
    })?;
    let matrix = |m: &nalgebra::DMatrix<f64>| {
        let rows: Vec<String> = (0..m.nrows())
            .map(|i| format!("    {}", json_array((0..m.ncols()).map(|j| m[(i, j)]))))
            .collect();
        format!("[\n{}\n  ]", rows.join(",\n"))
    };
    Ok(format!(
        "{{\n  \"S_closed_form\": {},\n  \"N_closed_form\": {},\n  \"S_tree\": {},\n  \"N_tree\": {},\n  \"max_abs_difference\": {}\n}}\n",
        matrix(&report.s_closed_form),
        json_array(report.n_closed_form.iter().copied()),
        matrix(&report.s_tree),
        json_array(report.n_tree.iter().copied()),
        json_number(report.max_abs_difference)
    ))
}
