//! `fistage identify`: LuGre identification from lab CSV files.

/// Arguments of `fistage identify`.
#[derive(clap::Args)]
pub struct IdentifyArgs {}

/// Runs the identification command.
pub fn run(_args: &IdentifyArgs) -> anyhow::Result<()> {
    anyhow::bail!("identification is not available yet")
}
