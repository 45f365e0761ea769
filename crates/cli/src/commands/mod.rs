//! The command line ([`Cli`], parsed by clap) and the errors every command shares. One file
//! per command: its flags (a `clap::Args` struct, whose doc comments are its `--help`) and
//! its work.

pub mod accuracy;
pub mod bench;
pub mod campaign;
pub mod completions;
pub mod dynamics;
pub mod environment;
pub mod linearize;
pub mod modes;
pub mod plot;
pub mod preprint;
pub mod run;
pub mod view;

use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, Subcommand};
use satsim_tree::io::{FileError, line_of};
use std::fmt;
use std::path::{Path, PathBuf};

/// The exit status of every error (bad input, usage, unavailable command).
pub const EXIT_BAD_INPUT: u8 = 2;

/// The whole standard output of a successful command.
pub type Output = String;

/// `satsim`: attitude dynamics of hinged spacecraft.
#[derive(Debug, Parser)]
#[command(
    name = "satsim",
    version,
    about = "satsim: attitude dynamics of hinged spacecraft",
    long_about = "satsim: attitude dynamics of hinged spacecraft.\n\n\
        With no command, runs the default scene examples/scenes/deploy.toml \
        (as `satsim run examples/scenes/deploy.toml`).",
    after_help = "Bad input exits with status 2 and one message on standard error naming the \
        file and line (or the flag). `satsim help COMMAND` or `satsim COMMAND --help` shows a \
        command's flags."
)]
pub struct Cli {
    /// The command; none runs the default scene.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Every command.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Mass matrix, bias, forward dynamics and kinetic energy of one state (one JSON object)
    Dynamics(dynamics::Args),
    /// Time crba, rnea, aba and crba_cholesky on a model (ns per call, one JSON object)
    Bench(bench::Args),
    /// The preprint's closed-form S and N against the generic engine (one JSON object)
    Preprint(preprint::Args),
    /// Integrate a scene: DIR/trajectory.csv, events.csv, plots and the 3-D view.html
    Run(run::Args),
    /// Work-precision sweep of the integrators: DIR/accuracy.{csv,svg,md}
    Accuracy(accuracy::Args),
    /// Monte Carlo campaign of a scene's [campaign] table: DIR/runs.csv, summary.json, plots
    Campaign(campaign::Args),
    /// The linear model (A, B) at the scene's initial state (one JSON object)
    Linearize(linearize::Args),
    /// Structural frequencies, damping ratios and mode shapes (one JSON object)
    Modes(modes::Args),
    /// Orbit, Sun, shadow, density, field and every effect's loads at a time (one JSON object)
    Environment(environment::Args),
    /// Re-create a run's 3-D playback DIR/view.html from its kept poses
    View(view::Args),
    /// Re-plot columns of a run's CSV against t (an SVG), without running again
    Plot(plot::Args),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell)
    Completions(completions::Args),
}

/// Runs every command but `run` (whose failures have their own exit statuses, see
/// [`run::Failure`]) and returns its standard output.
pub fn dispatch(command: Command) -> Result<Output, CliError> {
    match command {
        Command::Dynamics(a) => dynamics::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::Preprint(a) => preprint::run(&a),
        Command::Run(a) => run::run(&a),
        Command::Accuracy(a) => accuracy::run(&a),
        Command::Campaign(a) => campaign::run(&a),
        Command::Linearize(a) => linearize::run(&a),
        Command::Modes(a) => modes::run(&a),
        Command::Environment(a) => environment::run(&a),
        Command::View(a) => view::run(&a),
        Command::Plot(a) => plot::run(&a),
        Command::Completions(a) => completions::run(&a),
    }
}

/// Why a command failed. Every variant but [`CliError::Interrupted`] (130) exits with
/// status 2.
#[derive(Debug)]
pub enum CliError {
    /// Bad command line, found after parsing (a value clap cannot check alone): clap's
    /// message with the command's usage.
    Usage(Box<clap::Error>),
    /// A model, state or scene file could not be read.
    File(FileError),
    /// Anything else (a singular configuration, an unwritable output…).
    Other(String),
    /// Stopped by Ctrl-C (exit status 130, as `run`'s); the message says what was kept.
    Interrupted(String),
}

impl From<FileError> for CliError {
    fn from(e: FileError) -> Self {
        CliError::File(e)
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Usage(e) => write!(f, "{}", e.render().to_string().trim_end()),
            CliError::File(e) => write!(f, "error: {e}"),
            CliError::Other(m) => write!(f, "error: {m}"),
            CliError::Interrupted(m) => write!(f, "{m}"),
        }
    }
}

/// A usage error of the (sub)command at `path` (such as `["campaign", "merge"]`), formatted
/// as clap formats its own: the message, the command's usage line and a `--help` hint.
pub fn usage(path: &[&str], message: impl fmt::Display) -> CliError {
    let mut here = Cli::command();
    // Building sets every subcommand's full name (`satsim campaign merge`) for its usage.
    here.build();
    for name in path {
        match here.find_subcommand(name).cloned() {
            Some(sub) => here = sub,
            None => break,
        }
    }
    CliError::Usage(Box::new(here.error(ErrorKind::ValueValidation, message)))
}

/// A value parser: a whole number >= 1.
pub fn at_least_one(s: &str) -> Result<usize, String> {
    s.parse::<usize>()
        .ok()
        .filter(|n| *n >= 1)
        .ok_or_else(|| "must be a whole number >= 1".to_owned())
}

/// The `--model` and `--state` files of `dynamics` and `preprint`.
#[derive(Debug, clap::Args)]
pub struct ModelStateArgs {
    /// The model file (TOML, cli-contract section 1)
    #[arg(long, value_name = "MODEL.toml")]
    pub model: PathBuf,
    /// The state file (JSON, cli-contract section 2)
    #[arg(long, value_name = "STATE.json")]
    pub state: PathBuf,
}

/// A model and one of its states, read from `--model` and `--state`.
pub struct ModelAndState {
    /// The model file's path.
    pub model_path: PathBuf,
    /// The state file's path.
    pub state_path: PathBuf,
    /// The model.
    pub model: satsim_tree::Model,
    /// The state.
    pub state: satsim_tree::State,
}

/// Reads the rigid model file at `path` for `satsim <command>`. A model with flexible bodies
/// (`[body.flexible]`) is refused at the body's line: `preprint` and `bench` evaluate the
/// rigid algorithms (`dynamics` reads a flexible model with
/// [`satsim_tools::api::DynamicsModel`]); a flexible model runs in a scene.
pub fn read_rigid_model(path: &Path, command: &str) -> Result<satsim_tree::Model, CliError> {
    let e = match satsim_tree::io::read_model(path) {
        Ok(m) => return Ok(m),
        Err(e) => e,
    };
    let flexible = std::fs::read_to_string(path).ok().and_then(|text| {
        let file = satsim_tree::io::parse_model_file(&text, path).ok()?;
        file.body.iter().find_map(|b| {
            let b = b.get_ref();
            b.flexible
                .as_ref()
                .map(|f| (b.name.get_ref().clone(), line_of(&text, f.span().start)))
        })
    });
    Err(match flexible {
        Some((body, line)) => FileError::Schema {
            path: path.to_path_buf(),
            line: Some(line),
            message: format!(
                "body `{body}` is flexible: `satsim {command}` takes rigid models only; \
                 run a model with flexible bodies in a scene (`satsim run`, `satsim modes`, \
                 `satsim linearize`) or with `satsim dynamics`"
            ),
        },
        None => e,
    }
    .into())
}

impl ModelAndState {
    /// Reads both files (`command` names the command in messages).
    pub fn read(args: &ModelStateArgs, command: &str) -> Result<Self, CliError> {
        let model = read_rigid_model(&args.model, command)?;
        let state = satsim_tree::io::read_state(&args.state, &model)?;
        Ok(Self {
            model_path: args.model.clone(),
            state_path: args.state.clone(),
            model,
            state,
        })
    }
}

/// A matrix as a JSON array of rows.
pub fn rows(m: &nalgebra::DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

/// The JSON text of `value` (pretty, one trailing newline): what the JSON commands print.
/// Numbers are written in their shortest round-trip form.
pub fn to_json(value: &impl serde::Serialize) -> Result<Output, CliError> {
    let mut s = serde_json::to_string_pretty(value)
        .map_err(|e| CliError::Other(format!("cannot write the JSON output: {e}")))?;
    s.push('\n');
    Ok(s)
}

/// The stem of a scene or CSV path (`"scene"` when it has none), for default output names.
/// Prints what a reader accepted but the user should hear about (a nearly unit quaternion
/// normalised, …) on standard error, one `warning:` line each: every command that reads a
/// scene says the same.
pub fn print_warnings(warnings: &[String]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

pub fn stem(path: &std::path::Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn usage_errors_name_the_subcommand() {
        let e = usage(&["campaign", "merge"], "bad thing").to_string();
        assert!(e.contains("bad thing"), "{e}");
        assert!(e.contains("Usage: satsim campaign merge"), "{e}");
    }
}
