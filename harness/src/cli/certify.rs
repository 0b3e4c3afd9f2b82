//! `gcl certify` (not built yet).

/// Arguments of `gcl certify`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `gcl certify`.
pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("gcl certify is not built yet")
}
