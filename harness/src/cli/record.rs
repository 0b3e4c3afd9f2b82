//! `gcl record` (not built yet).

/// Arguments of `gcl record`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `gcl record`.
pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("gcl record is not built yet")
}
