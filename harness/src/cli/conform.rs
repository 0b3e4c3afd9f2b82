//! `gcl conform` (not built yet).

/// Arguments of `gcl conform`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `gcl conform`.
pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("gcl conform is not built yet")
}
