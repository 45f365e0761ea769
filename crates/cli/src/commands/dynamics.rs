//! `satsim dynamics --model MODEL.toml --state STATE.json` (contract section 3): the mass
//! matrix, the bias forces, the forward-dynamics acceleration (ABA) and the kinetic energy
//! of one state, as one JSON object with every number at full `f64` precision.

use super::{CliError, ModelAndState, Options, Output, json_array, json_number, usage_line};
use satsim_satellite::api::{Dynamics, DynamicsFailure, dynamics};

const NAME: &str = "dynamics";

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
    let Dynamics {
        dof: n,
        mass_matrix: m,
        bias: b,
        acceleration: a,
        kinetic_energy: ke,
    } = dynamics(&model, &state).map_err(|e| match e {
        DynamicsFailure::Engine(e) => CliError::Other(format!(
            "{}: {e} (model {})",
            state_path.display(),
            model_path.display()
        )),
        DynamicsFailure::NonFinite => CliError::Other(format!("{}: {e}", state_path.display())),
    })?;

    let rows: Vec<String> = (0..n)
        .map(|i| format!("    {}", json_array((0..n).map(|j| m[(i, j)]))))
        .collect();
    let matrix = if n == 0 {
        "[]".to_owned()
    } else {
        format!("[\n{}\n  ]", rows.join(",\n"))
    };
    Ok(format!(
        "{{\n  \"dof\": {n},\n  \"mass_matrix\": {matrix},\n  \"bias\": {},\n  \"acceleration\": {},\n  \"kinetic_energy\": {}\n}}\n",
        json_array(b.iter().copied()),
        json_array(a.iter().copied()),
        json_number(ke)
    ))
}
