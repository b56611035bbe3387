//! `fistage completions SHELL` prints the shell's completion script and
//! `fistage man [--out DIR]` writes man pages (`fistage.1` and one per
//! command, `fistage-run.1`, ...), both made by clap's own generators from
//! the command definitions, so they always match `--help`.

use std::path::PathBuf;

use anyhow::Context;
use clap_complete::Shell;

/// Arguments of `fistage completions`.
#[derive(clap::Args)]
pub struct CompletionsArgs {
    /// The shell (bash, zsh, fish, elvish, powershell). For bash:
    /// `fistage completions bash > ~/.local/share/bash-completion/completions/fistage`.
    pub shell: Shell,
}

/// Arguments of `fistage man`.
#[derive(clap::Args)]
pub struct ManArgs {
    /// Folder for the pages (default: out/man); `man -l out/man/fistage.1` reads one.
    #[arg(long, short)]
    pub out: Option<PathBuf>,
}

/// Prints the completion script.
pub fn completions(args: &CompletionsArgs, mut command: clap::Command) -> anyhow::Result<()> {
    clap_complete::generate(args.shell, &mut command, "fistage", &mut std::io::stdout());
    Ok(())
}

/// Writes the man pages.
pub fn man(args: &ManArgs, command: clap::Command) -> anyhow::Result<()> {
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from("out/man"));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    // The pages are made in a folder beside `out` and each moved over its
    // earlier version only when all are written: a failure leaves the
    // earlier pages as they were.
    let staging =
        fistage_model::output::staging_beside(&out, &format!("partial-{}", std::process::id()))?;
    let _ = std::fs::remove_dir_all(&staging);
    let made = std::fs::create_dir(&staging)
        .and_then(|()| clap_mangen::generate_to(command, &staging))
        .and_then(|()| move_pages(&staging, &out));
    let _ = std::fs::remove_dir_all(&staging);
    made.with_context(|| format!("cannot write the man pages into {}", out.display()))?;
    println!("wrote the man pages into {}", out.display());
    Ok(())
}

/// Moves every page of `staging` into `out`, each replacing its namesake.
fn move_pages(staging: &std::path::Path, out: &std::path::Path) -> std::io::Result<()> {
    for entry in std::fs::read_dir(staging)? {
        let entry = entry?;
        std::fs::rename(entry.path(), out.join(entry.file_name()))?;
    }
    Ok(())
}
