//! Command dispatch, argument parsing and errors. One file per command.

pub mod accuracy;
pub mod bench;
pub mod campaign;
pub mod dynamics;
pub mod linearize;
pub mod modes;
pub mod preprint;
pub mod run;
pub mod view;

use satsim_tree::io::FileError;
use std::ffi::{OsStr, OsString};
use std::fmt;
use std::path::PathBuf;

/// The exit status of every error (bad input, usage, unavailable command).
pub const EXIT_BAD_INPUT: u8 = 2;

/// The whole standard output of a successful command.
pub type Output = String;

/// The usage summary printed by `satsim help`.
pub const USAGE: &str = "\
satsim: attitude dynamics of hinged spacecraft

usage: satsim <command> [options]

commands:
  dynamics --model MODEL.toml --state STATE.json
                      mass matrix, bias, forward dynamics and kinetic energy (one JSON object)
  bench --model MODEL.toml [--state STATE.json] [--calls N]
                      time crba, rnea, aba and crba_cholesky (ns per call, JSON)
  preprint --model MODEL.toml --state STATE.json
                      the preprint's closed-form S and N against the generic engine
  run SCENE.toml [--out DIR]
                      integrate a scene, write DIR/trajectory.csv
  accuracy SCENE.toml [--out DIR] [--repeats N] [--methods LIST] [--quick]
                      work-precision sweep of the integrators: DIR/accuracy.{csv,svg,md}
  campaign SCENE.toml [--out DIR] [--threads T] [--shard I/N] [--shards N] [--resume]
                      Monte Carlo campaign of a scene's [campaign] table: DIR/runs.csv,
                      summary.json, plots
  campaign merge DIR... --out DIR
                      merge the shards of a campaign into one folder
  linearize SCENE.toml
                      the linear model (A, B) at the scene's initial state (JSON)
  modes SCENE.toml [--along HINGE=FROM:TO:N[,HINGE=FROM:TO]] [--plot FILE.svg]
                      structural frequencies, damping ratios and shapes (JSON); --along
                      sweeps hinge angles and plots the frequencies
  view DIR [--out FILE]
                      re-create a run's 3-D playback DIR/view.html from its kept poses
  help [COMMAND]      this help, or a command's
  --version           the version

Bad input exits with status 2 and one message on standard error.
";

/// Why a command failed. Every variant exits with status 2.
#[derive(Debug)]
pub enum CliError {
    /// Bad command line: the message, then the command's usage.
    Usage {
        /// The command (`None` for the top level).
        command: Option<&'static str>,
        /// What is wrong.
        message: String,
    },
    /// A model or state file could not be read.
    File(FileError),
    /// Anything else (a singular configuration, an unavailable command…).
    Other(String),
}

impl From<FileError> for CliError {
    fn from(e: FileError) -> Self {
        CliError::File(e)
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Usage { command, message } => {
                let name = command
                    .map(|c| format!("satsim {c}"))
                    .unwrap_or("satsim".into());
                write!(f, "{name}: {message}\nusage: {}", usage_line(*command))?;
                write!(f, "\n(`satsim help` lists the commands)")
            }
            CliError::File(e) => write!(f, "error: {e}"),
            CliError::Other(m) => write!(f, "error: {m}"),
        }
    }
}

/// One command's usage line.
pub fn usage_line(command: Option<&str>) -> &'static str {
    match command {
        Some("dynamics") => "satsim dynamics --model MODEL.toml --state STATE.json",
        Some("bench") => "satsim bench --model MODEL.toml [--state STATE.json] [--calls N]",
        Some("preprint") => "satsim preprint --model MODEL.toml --state STATE.json",
        Some("run") => "satsim run SCENE.toml [--out DIR] [--set KEY=VALUE]...",
        Some("campaign") => {
            "satsim campaign SCENE.toml [--out DIR] [--threads T] [--shard I/N] [--shards N] [--resume] [--set KEY=VALUE]...\n       satsim campaign merge DIR... --out DIR"
        }
        Some("linearize") => "satsim linearize SCENE.toml",
        Some("modes") => {
            "satsim modes SCENE.toml [--along HINGE=FROM:TO:N[,HINGE=FROM:TO]] [--plot FILE.svg]"
        }
        Some("view") => "satsim view DIR [--out FILE]",
        Some("accuracy") => {
            "satsim accuracy SCENE.toml [--out DIR] [--repeats N] [--methods rk4,dp54,dop853,radau5] [--quick]"
        }
        _ => {
            "satsim <command> [options]   (commands: dynamics, bench, preprint, run, accuracy, campaign, linearize, modes, view, help)"
        }
    }
}

/// Runs the command line (without the program name) and returns its standard output.
pub fn dispatch(args: &[OsString]) -> Result<Output, CliError> {
    let Some(first) = args.first() else {
        // The lead will make a bare `satsim` run the default scene.
        return Err(CliError::Usage {
            command: None,
            message: "no command given".into(),
        });
    };
    let rest = &args[1..];
    let name = first.to_string_lossy();
    match name.as_ref() {
        "-h" | "--help" | "help" => help(rest),
        "-V" | "--version" | "version" => Ok(format!("satsim {}\n", env!("CARGO_PKG_VERSION"))),
        "dynamics" => dynamics::run(rest),
        "bench" => bench::run(rest),
        "preprint" => preprint::run(rest),
        "run" => run::run(rest),
        "accuracy" => accuracy::run(rest),
        "campaign" => campaign::run(rest),
        "linearize" => linearize::run(rest),
        "modes" => modes::run(rest),
        "view" => view::run(rest),
        other => Err(CliError::Usage {
            command: None,
            message: format!("unknown command `{other}`"),
        }),
    }
}

fn help(rest: &[OsString]) -> Result<Output, CliError> {
    match rest.first().map(|a| a.to_string_lossy()) {
        None => Ok(USAGE.to_owned()),
        Some(c) => match c.as_ref() {
            "dynamics" | "bench" | "preprint" | "run" | "accuracy" | "campaign" | "linearize"
            | "modes" | "view" => Ok(format!("usage: {}\n", usage_line(Some(&c)))),
            other => Err(CliError::Usage {
                command: Some("help"),
                message: format!("unknown command `{other}`"),
            }),
        },
    }
}

/// Parsed options of one command: `--name VALUE` or `--name=VALUE` pairs, `--help`, and
/// positional arguments.
#[derive(Debug, Default)]
pub struct Options {
    values: Vec<(&'static str, OsString)>,
    /// Positional arguments, in order.
    pub positional: Vec<OsString>,
    /// `--help` or `-h` was given.
    pub help: bool,
}

impl Options {
    /// Parses `args` for `command`, which takes the value options `names` and at most
    /// `max_positional` positional arguments.
    pub fn parse(
        command: &'static str,
        args: &[OsString],
        names: &[&'static str],
        max_positional: usize,
    ) -> Result<Self, CliError> {
        let usage = |message: String| CliError::Usage {
            command: Some(command),
            message,
        };
        let mut out = Options::default();
        let mut it = args.iter();
        while let Some(arg) = it.next() {
            let text = arg.to_string_lossy();
            if text == "-h" || text == "--help" {
                out.help = true;
                continue;
            }
            if let Some(flag) = text.strip_prefix("--") {
                let (key, inline) = match flag.split_once('=') {
                    Some((k, _)) => (k, Some(split_value(arg))),
                    None => (flag, None),
                };
                let Some(&name) = names.iter().find(|n| **n == key) else {
                    return Err(usage(format!("unknown option `--{key}`")));
                };
                if name != "set" && out.values.iter().any(|(n, _)| *n == name) {
                    return Err(usage(format!("`--{name}` given twice")));
                }
                let value = match inline {
                    Some(v) => v,
                    None => it
                        .next()
                        .cloned()
                        .ok_or_else(|| usage(format!("`--{name}` needs a value")))?,
                };
                if value.is_empty() {
                    return Err(usage(format!("`--{name}` needs a non-empty value")));
                }
                out.values.push((name, value));
            } else if text.starts_with('-') && text.len() > 1 {
                return Err(usage(format!("unknown option `{text}`")));
            } else {
                if out.positional.len() == max_positional {
                    return Err(usage(format!("unexpected argument `{text}`")));
                }
                out.positional.push(arg.clone());
            }
        }
        Ok(out)
    }

    /// The value of `--name`, if given.
    pub fn get(&self, name: &str) -> Option<&OsStr> {
        self.values
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v.as_os_str())
    }

    /// Every value of the repeatable `--name` (only `--set` repeats), in order.
    pub fn all(&self, name: &str) -> impl Iterator<Item = &OsStr> {
        self.values
            .iter()
            .filter(move |(n, _)| *n == name)
            .map(|(_, v)| v.as_os_str())
    }

    /// The `--set KEY=VALUE` overrides, in order.
    pub fn overrides(
        &self,
        command: &'static str,
    ) -> Result<Vec<satsim_satellite::scene_keys::Override>, CliError> {
        self.all("set")
            .map(|s| {
                satsim_satellite::scene_keys::Override::parse(&s.to_string_lossy()).map_err(|e| {
                    CliError::Usage {
                        command: Some(command),
                        message: format!("--set {e}"),
                    }
                })
            })
            .collect()
    }

    /// The value of `--name` as a path, if given.
    pub fn path(&self, name: &str) -> Option<PathBuf> {
        self.get(name).map(PathBuf::from)
    }

    /// The value of the required option `--name` as a path.
    pub fn required_path(&self, command: &'static str, name: &str) -> Result<PathBuf, CliError> {
        self.path(name).ok_or_else(|| CliError::Usage {
            command: Some(command),
            message: format!("missing `--{name}`"),
        })
    }
}

/// A model and one of its states, read from `--model` and `--state` (both required).
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

impl ModelAndState {
    /// Reads both files named by the options of `command`.
    pub fn read(command: &'static str, opts: &Options) -> Result<Self, CliError> {
        let model_path = opts.required_path(command, "model")?;
        let state_path = opts.required_path(command, "state")?;
        let model = satsim_tree::io::read_model(&model_path)?;
        let state = satsim_tree::io::read_state(&state_path, &model)?;
        Ok(Self {
            model_path,
            state_path,
            model,
            state,
        })
    }
}

/// The part of `--key=value` after the first `=` (a non-UTF-8 value is read lossily).
fn split_value(arg: &OsStr) -> OsString {
    let text = arg.to_string_lossy();
    OsString::from(text.split_once('=').map_or("", |(_, v)| v))
}

/// Formats a number for JSON: shortest representation that reads back to the same `f64`.
/// Non-finite numbers have no JSON form; callers check finiteness first.
pub fn json_number(x: f64) -> String {
    debug_assert!(x.is_finite());
    serde_json::to_string(&x).unwrap_or_else(|_| "null".into())
}

/// A JSON array of numbers on one line.
pub fn json_array(xs: impl IntoIterator<Item = f64>) -> String {
    let items: Vec<String> = xs.into_iter().map(json_number).collect();
    format!("[{}]", items.join(", "))
}
