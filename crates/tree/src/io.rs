//! Readers for the model TOML and state JSON files of the command-line contract
//! (`cli-contract.md` sections 1 and 2).
//!
//! - [`read_model`] / [`parse_model`]: a model file into a validated
//!   [`Model`](crate::Model). The file is first deserialised into a [`ModelFile`] (strict:
//!   unknown keys are errors), which keeps the byte span of every body, hinge and key, so
//!   that every error names the line concerned.
//! - [`read_state`] / [`parse_state`]: a state file into a [`State`] in the engine's layout.
//!   The root's attitude is a quaternion, Euler angles in a stated sequence or an axis and
//!   angle ([`Attitude`]).
//!
//! - [`read_flex_model`] / [`parse_flex_model`]: a model file whose bodies may carry
//!   `[body.flexible]` (contract section 14) into a [`FlexModel`](crate::flexible::FlexModel);
//!   [`parse_modes_file`] / [`write_modes_file`]: the modes file such a body may name.
//!
//! Every [`FileError`] displays as `PATH:LINE: message` (or `PATH: field: message` where
//! only the field is known, as for JSON arrays of the wrong length).
//!
//! A fixed-length array is read through [`exact`], which refuses too many entries as serde
//! refuses too few (`invalid length 4, expected an array of length 3`, at its line).
//!
//! ```
//! use satsim_tree::io::{parse_model, parse_state};
//! use std::path::Path;
//! let text = r#"
//! [[body]]
//! name = "bus"
//! mass = 500
//! inertia = [[40, 0, 0], [0, 40, 0], [0, 0, 30]]
//!
//! [[body]]
//! name = "panel"
//! mass = 20.0
//! inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]
//!
//! [[hinge]]
//! name = "h"
//! parent = "bus"
//! child = "panel"
//! axis = [1, 0, 0]
//! at = [0, 1, 0]
//! "#;
//! let (model, _file) = parse_model(text, Path::new("sat.toml"))?;
//! assert_eq!(model.nv(), 7);
//! let state = parse_state(r#"{"hinges": {"angle": [0.1], "rate": [0.0]}}"#, Path::new("s.json"), &model)?;
//! assert_eq!(state.q, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1]);
//!
//! let bad = text.replace("parent = \"bus\"", "parent = \"bsu\"");
//! let err = parse_model(&bad, Path::new("bad.toml")).unwrap_err();
//! assert_eq!(err.to_string(), "bad.toml:14: hinge `h`: unknown parent body `bsu`");
//! # Ok::<(), satsim_tree::io::FileError>(())
//! ```

mod attitude;
mod document;
mod error;
mod exact;
mod flex_file;
mod model_file;
mod state_file;

pub use attitude::{Attitude, EULER_SEQUENCES, EulerSequence};
pub use document::Document;
pub use error::{FileError, SpannedError, line_of};
pub use exact::{Exact, exact};
pub use flex_file::{
    MAX_FILE_MODES, MODES_FILE_NODE_TOLERANCE, ModesFile, NodeFile, flex_model_of,
    parse_flex_model, parse_modes_file, read_flex_model, write_modes_file,
};
pub use model_file::{
    BaseFile, BaseKindFile, BeamFile, BodyFile, CoefficientsFile, FacetFile, FlexibleFile,
    HingeFile, ModelFile, ShapeFile, parse_model, parse_model_file, read_model, with_key,
};
pub use state_file::{
    BaseFrame, BaseStateFile, FieldError, FrameMotion, HingesStateFile, RATE_WARNING,
    STATE_ATTITUDE_TOLERANCE, State, StateFile, near_unit_quaternion, parse_state,
    parse_state_file, read_state,
};

use std::path::Path;

/// Checks a name that becomes part of output column names (`angle_<hinge>`,
/// `thrust_<thruster>`, `<sensor>_x`…): bodies, hinges, wheels, thrusters, torquers, sensors.
/// It must be ASCII letters, digits and `_`, so that no comma, quote, space or newline breaks
/// a CSV row or header. The error says what is allowed and shows the name as written.
///
/// ```
/// use satsim_tree::io::column_name;
/// assert!(column_name("panel_1").is_ok());
/// assert!(column_name("a,b").unwrap_err().contains("\"a,b\""));
/// assert!(column_name("").is_err() && column_name("x\ny").is_err());
/// ```
pub fn column_name(name: &str) -> Result<(), String> {
    if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Ok(());
    }
    Err(format!(
        "must be letters, digits and `_` (it names output columns), got {name:?}"
    ))
}

/// The text of the file at `path`; an empty file (or only white space) is an error.
pub(crate) fn read_text(path: &Path) -> Result<String, FileError> {
    let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    if text.trim().is_empty() {
        return Err(FileError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(text)
}

#[cfg(test)]
mod tests;
