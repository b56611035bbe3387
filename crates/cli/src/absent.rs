//! Commands a lean build leaves out (`--no-default-features`): they keep
//! their names, so `fistage bench` or `fistage fmu` says which feature brings
//! them instead of "unrecognized subcommand".

/// Whatever the command was given: a lean build reads none of it.
#[derive(clap::Args)]
pub struct AbsentArgs {
    /// The command's arguments (this build does not have the command).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub args: Vec<String>,
}

/// The refusal of `command`, which the cargo feature `feature` brings.
pub fn refuse(command: &str, feature: &str) -> anyhow::Result<()> {
    anyhow::bail!(
        "`fistage {command}` is not in this build (its `{feature}` feature is off); build the whole program with `cargo build --release -p fistage`"
    )
}
