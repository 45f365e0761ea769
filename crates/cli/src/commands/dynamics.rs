//! `satsim dynamics --model MODEL.toml --state STATE.json` (contract section 3): the mass
//! matrix, the bias forces, the forward-dynamics acceleration (ABA) and the kinetic energy
//! of one state, as one JSON object with every number at full `f64` precision.

use super::{CliError, ModelAndState, ModelStateArgs, Output, rows, to_json};
use satsim_tools::api::{Dynamics, DynamicsFailure, dynamics};
use serde::Serialize;

/// The flags of `satsim dynamics`.
pub type Args = ModelStateArgs;

/// The printed object, in the contract's key order.
#[derive(Serialize)]
struct Json {
    dof: usize,
    mass_matrix: Vec<Vec<f64>>,
    bias: Vec<f64>,
    acceleration: Vec<f64>,
    kinetic_energy: f64,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let ModelAndState {
        model_path,
        state_path,
        model,
        state,
    } = ModelAndState::read(args, "dynamics")?;
    let Dynamics {
        dof,
        mass_matrix,
        bias,
        acceleration,
        kinetic_energy,
    } = dynamics(&model, &state).map_err(|e| match e {
        DynamicsFailure::Engine(e) => CliError::Other(format!(
            "{}: {e} (model {})",
            state_path.display(),
            model_path.display()
        )),
        DynamicsFailure::NonFinite => CliError::Other(format!("{}: {e}", state_path.display())),
    })?;
    to_json(&Json {
        dof,
        mass_matrix: rows(&mass_matrix),
        bias: bias.iter().copied().collect(),
        acceleration: acceleration.iter().copied().collect(),
        kinetic_energy,
    })
}
