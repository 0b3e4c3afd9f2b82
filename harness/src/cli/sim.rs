//! `gcl sim` (not built yet).

/// Arguments of `gcl sim`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `gcl sim`.
pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("gcl sim is not built yet")
}
