//! `satsim view DIR [--out FILE]`: re-creates a run's 3-D playback (`DIR/view.html`, contract
//! section 11) from the scene and poses the run kept (`DIR/view.json`, `DIR/poses.csv`).

use super::{CliError, Output};
use satsim_tools::view::{VIEW_HTML, ViewData};
use std::path::PathBuf;

/// The flags of `satsim view`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The output folder of a `satsim run` (holding view.json and poses.csv)
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
    /// Where to write the page [default: DIR/view.html]
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let dir = &args.dir;
    let data = ViewData::read(dir).map_err(|e| CliError::Other(e.to_string()))?;
    let out = args.out.clone().unwrap_or_else(|| dir.join(VIEW_HTML));
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
