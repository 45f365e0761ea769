//! `satsim`: the command-line tool of the satsim workspace (see `cli-contract.md`).
//!
//! The command line is parsed by clap ([`commands::Cli`]): `--help` for every command,
//! `--version`, and usage errors with exit status 2. Every command computes its whole standard
//! output first and prints it only on success, so bad input never leaves a partial JSON object
//! behind. Errors print one message on standard error and exit with status 2 (`run` also has
//! 1 for a run that fails part-way and 130 for Ctrl-C); a panic (a bug) is caught and reported
//! the same way.

// The flags' doc comments are their `--help` text, written for a terminal (`out/<scene stem>`),
// not for HTML.
#![forbid(unsafe_code)]
#![allow(rustdoc::invalid_html_tags)]

mod commands;

use clap::Parser;
use commands::run::{EXIT_RUN_FAILED, Failure};
use commands::{Cli, CliError, Command, EXIT_BAD_INPUT};
use std::io::Write;
use std::panic::AssertUnwindSafe;
use std::process::ExitCode;

fn main() -> ExitCode {
    // A bug must not print a backtrace in the middle of the contract's output: report it as
    // one message instead.
    std::panic::set_hook(Box::new(|_| {}));
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // `--help` and `--version` go to standard output with status 0; usage errors to
            // standard error with status 2.
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { EXIT_BAD_INPUT } else { 0 });
        }
    };
    // A cap on the kernels' instructions that names none of them is bad input, not ignored.
    if let Err(e) = satsim_satellite::instructions::Instructions::from_env() {
        eprintln!("error: {e}");
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    // `satsim` alone runs the default scene; `satsim run` has its own exit statuses (1 for a
    // run that fails part-way, 130 for Ctrl-C, 2 for bad input).
    let is_run = matches!(cli.command, None | Some(Command::Run(_)));
    let result = std::panic::catch_unwind(AssertUnwindSafe(|| match cli.command {
        None => commands::run::run_scene(&commands::run::default_scene(), None),
        Some(Command::Run(args)) => commands::run::command(&args),
        Some(other) => commands::dispatch(other).map_err(|e| match e {
            CliError::Interrupted(m) => Failure::Interrupted(m),
            e => Failure::BadInput(e),
        }),
    }));
    match result {
        Ok(Ok(output)) => {
            let mut out = std::io::stdout().lock();
            // A closed pipe (`satsim ... | head`) is not an error worth a message; a run's
            // files are written, so only the other commands report it.
            let written = out.write_all(output.as_bytes()).and_then(|_| out.flush());
            if written.is_err() && !is_run {
                return ExitCode::from(1);
            }
            ExitCode::SUCCESS
        }
        Ok(Err(failure)) => {
            eprintln!("{failure}");
            ExitCode::from(failure.exit_code())
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_owned());
            eprintln!("error: internal error (a bug in satsim, please report it): {what}");
            ExitCode::from(if is_run {
                EXIT_RUN_FAILED
            } else {
                EXIT_BAD_INPUT
            })
        }
    }
}
