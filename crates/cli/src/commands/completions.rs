//! `satsim completions SHELL`: a completion script for the shell (clap_complete), printed on
//! standard output.

use super::{Cli, CliError, Output};
use clap::CommandFactory;
use clap_complete::Shell;

/// The flags of `satsim completions`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Install, for example:\n  \
    bash: satsim completions bash > ~/.local/share/bash-completion/completions/satsim\n  \
    zsh:  satsim completions zsh > ~/.zfunc/_satsim   (with fpath+=~/.zfunc in ~/.zshrc)\n  \
    fish: satsim completions fish > ~/.config/fish/completions/satsim.fish")]
pub struct Args {
    /// The shell to complete in
    #[arg(value_name = "SHELL")]
    pub shell: Shell,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let mut script = Vec::new();
    clap_complete::generate(args.shell, &mut Cli::command(), "satsim", &mut script);
    String::from_utf8(script)
        .map_err(|e| CliError::Other(format!("the completion script is not UTF-8: {e}")))
}
