//! `gcl suite` (not built yet).

/// Arguments of `gcl suite`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `gcl suite`.
pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("gcl suite is not built yet")
}
