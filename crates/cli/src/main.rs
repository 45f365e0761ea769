//! `satsim`: the command-line tool of the satsim workspace (see `cli-contract.md`).
//!
//! Every command computes its whole standard output first and prints it only on success, so
//! bad input never leaves a partial JSON object behind. Errors print one message on standard
//! error and exit with status 2; a panic (a bug) is caught and reported the same way.

mod commands;

use std::ffi::OsString;
use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    // A bug must not print a backtrace in the middle of the contract's output: report it as
    // one message instead.
    std::panic::set_hook(Box::new(|_| {}));
    // `satsim` alone runs the default scene; `satsim run` has its own exit statuses (1 for a
    // run that fails part-way, 2 for bad input).
    let is_run = args.first().is_none_or(|a| a == "run");
    if is_run {
        let result = std::panic::catch_unwind(|| match args.first() {
            None => commands::run::run_scene(&commands::run::default_scene(), None),
            Some(_) => commands::run::command(&args[1..]),
        });
        return match result {
            Ok(Ok(summary)) => {
                let mut out = std::io::stdout().lock();
                let _ = out.write_all(summary.as_bytes()).and_then(|_| out.flush());
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
                ExitCode::from(commands::run::EXIT_RUN_FAILED)
            }
        };
    }
    let result = std::panic::catch_unwind(|| commands::dispatch(&args));
    match result {
        Ok(Ok(output)) => {
            let mut out = std::io::stdout().lock();
            // A closed pipe (`satsim ... | head`) is not an error worth a message.
            if out
                .write_all(output.as_bytes())
                .and_then(|_| out.flush())
                .is_err()
            {
                return ExitCode::from(1);
            }
            ExitCode::SUCCESS
        }
        Ok(Err(error)) => {
            eprintln!("{error}");
            ExitCode::from(commands::EXIT_BAD_INPUT)
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_owned());
            eprintln!("error: internal error (a bug in satsim, please report it): {what}");
            ExitCode::from(commands::EXIT_BAD_INPUT)
        }
    }
}
