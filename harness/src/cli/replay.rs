//! `gcl replay` (not built yet).

/// Arguments of `gcl replay`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `gcl replay`.
pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("gcl replay is not built yet")
}
