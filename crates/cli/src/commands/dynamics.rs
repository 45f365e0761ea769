//! `satsim dynamics --model MODEL.toml --state STATE.json` (contract section 3): the mass
//! matrix, the bias forces, the forward-dynamics acceleration (ABA) and the kinetic energy
//! of one state, as one JSON object with every number at full `f64` precision. A model with
//! flexible bodies (contract section 14) evaluates the flexible algorithms: its elastic
//! coordinates follow the hinge rates, and the state file may give them (`flexible`).

use super::{CliError, ModelStateArgs, Output, rows, to_json};
use satsim_tools::api::{Dynamics, DynamicsFailure, DynamicsModel};
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
    let (model_path, state_path) = (&args.model, &args.state);
    let model = DynamicsModel::read(model_path)?;
    let (state, elastic) = model.read_state(state_path)?;
    let Dynamics {
        dof,
        mass_matrix,
        bias,
        acceleration,
        kinetic_energy,
    } = model.dynamics(&state, &elastic).map_err(|e| match e {
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
