//! `tactrace completions bash|zsh|fish`: a shell completion script for
//! every subcommand and option, generated from the CLI's own definition
//! (clap_complete), so it cannot fall behind the commands.

use anyhow::Result;
use clap::{Args, ValueEnum};
use clap_complete::Shell;
use std::io::Write as _;

#[derive(Args)]
pub struct CompletionsArgs {
    /// The shell to write the script for.
    #[arg(value_enum)]
    shell: CompletionShell,
}

/// The shells a script can be written for.
#[derive(Clone, Copy, ValueEnum)]
enum CompletionShell {
    /// Bash: `source <(tactrace completions bash)`, or save it under
    /// ~/.local/share/bash-completion/completions/tactrace.
    Bash,
    /// Zsh: save it as `_tactrace` in a folder of your `fpath`.
    Zsh,
    /// Fish: save it as ~/.config/fish/completions/tactrace.fish.
    Fish,
}

impl CompletionShell {
    fn shell(self) -> Shell {
        match self {
            CompletionShell::Bash => Shell::Bash,
            CompletionShell::Zsh => Shell::Zsh,
            CompletionShell::Fish => Shell::Fish,
        }
    }
}

/// The script for `shell` completing `cli`, as text.
fn script(shell: CompletionShell, cli: &mut clap::Command) -> Vec<u8> {
    let mut buf = Vec::new();
    clap_complete::generate(shell.shell(), cli, "tactrace", &mut buf);
    buf
}

/// Writes the completion script on standard output (a closed pipe ends
/// quietly, as for every command).
pub fn completions(a: CompletionsArgs, mut cli: clap::Command) -> Result<()> {
    let text = script(a.shell, &mut cli);
    let mut out = std::io::stdout().lock();
    out.write_all(&text)?;
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Cli;
    use clap::CommandFactory;

    /// Every subcommand's name, nested ones included (`sensor render`).
    fn names(cmd: &clap::Command, out: &mut Vec<String>) {
        for sub in cmd.get_subcommands() {
            out.push(sub.get_name().to_owned());
            names(sub, out);
        }
    }

    /// Issue 20: there were no shell completions. Each shell's script
    /// names every subcommand, nested ones included, and their options.
    #[test]
    fn every_shells_script_mentions_every_subcommand() {
        let mut all = Vec::new();
        names(&Cli::command(), &mut all);
        assert!(all.len() > 20, "{all:?}");
        for shell in [
            CompletionShell::Bash,
            CompletionShell::Zsh,
            CompletionShell::Fish,
        ] {
            let text = String::from_utf8(script(shell, &mut Cli::command())).unwrap();
            let missing: Vec<&String> = all.iter().filter(|n| !text.contains(n.as_str())).collect();
            assert!(missing.is_empty(), "{:?} lacks {missing:?}", shell.shell());
            // Fish writes long options without their dashes (`-l name`).
            for option in ["replay-keep", "val-fraction", "fit-physics"] {
                assert!(text.contains(option), "{:?} lacks {option}", shell.shell());
            }
        }
    }
}
