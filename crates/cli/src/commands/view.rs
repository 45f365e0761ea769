//! `satsim view DIR [--out FILE]`: re-creates a run's 3-D playback (`DIR/view.html`, contract
//! section 11) from the scene and poses the run kept (`DIR/view.json`, `DIR/poses.csv`).

use super::{CliError, Options, Output, usage_line};
use satsim_satellite::view::{VIEW_HTML, ViewData};
use std::path::PathBuf;

const NAME: &str = "view";

/// Runs the command.
pub fn run(args: &[std::ffi::OsString]) -> Result<Output, CliError> {
    let opts = Options::parse(NAME, args, &["out"], 1)?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let dir = opts
        .positional
        .first()
        .map(PathBuf::from)
        .ok_or_else(|| CliError::Usage {
            command: Some(NAME),
            message: "missing the run's output folder".into(),
        })?;
    let data = ViewData::read(&dir).map_err(|e| CliError::Other(e.to_string()))?;
    let out = opts.path("out").unwrap_or_else(|| dir.join(VIEW_HTML));
    data.write_html(&out)
        .map_err(|e| CliError::Other(e.to_string()))?;
    Ok(format!(
        "wrote      {} ({} frames, t = {} .. {} s)\n",
        out.display(),
        data.frames.len(),
        data.frames.frame(0).first().copied().unwrap_or(0.0),
        data.frames
            .frame(data.frames.len().saturating_sub(1))
            .first()
            .copied()
            .unwrap_or(0.0)
    ))
}
