//! `gcl fuzz`: the fuzzers that drive whole programs. Each subcommand owns its module.

use super::fuzz_host;

/// Arguments of `gcl fuzz`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: FuzzCommand,
}

/// What to fuzz.
#[derive(Debug, clap::Subcommand)]
pub enum FuzzCommand {
    /// Put a misbehaving simulated hand in front of a host program: crashes, hangs, protocol
    /// violations, with reproducers.
    Host(fuzz_host::Args),
}

/// Runs `gcl fuzz`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    match args.command {
        FuzzCommand::Host(a) => fuzz_host::run(a),
    }
}
