//! `gcl`: the conformance kit for the Grasper Control Language.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cli;

// A fuzzing campaign allocates and frees many small values per case (matcher states, answers,
// clones of a model): with mimalloc `gcl fuzz device --target sim` takes about a quarter less
// CPU than with the system's allocator (issue 41).
#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The conformance kit for the Grasper Control Language (GCL), the serial protocol of
/// Barrett's BH8-series robot hands.
///
/// Exit codes: 0 success, 1 conformance failures or mismatches, 2 usage or
/// infrastructure errors.
#[derive(Debug, Parser)]
#[command(name = "gcl", version, propagate_version = true, max_term_width = 100)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run lines against a fresh simulated hand and show how the model reads and answers them.
    Explain(cli::explain::Args),
    /// Print a profile: framing, commands, parameters, status codes, decisions.
    Spec(cli::spec::Args),
    /// Run the simulated grasper on a pty, TCP or stdio.
    Sim(cli::sim::Args),
    /// Turn a script of host lines and blocks into a golden transcript.
    Record(cli::record::Args),
    /// Replay a transcript's host side and compare the hand's answers.
    Replay(cli::replay::Args),
    /// Run the conformance suite against a hand.
    Conform(cli::conform::Args),
    /// Run the suite at MUST and SHOULD and write a certificate bundle, or verify one.
    Certify(cli::certify::Args),
    /// Fuzz a hand (`gcl fuzz device`) with the reference model as the oracle, or a host
    /// program against a misbehaving simulated hand (`gcl fuzz host`).
    Fuzz(cli::fuzz::Args),
    /// Grade a host program's traffic against a perfect simulated hand, clause by clause.
    CheckHost(cli::check_host::Args),
    /// Regenerate or check the committed golden transcripts.
    Suite(cli::suite::Args),
    /// Regenerate or check the committed JSON test vectors (also done by `gcl suite`).
    Vectors(cli::vectors::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Explain(a) => cli::explain::run(a),
        Command::Spec(a) => cli::spec::run(a),
        Command::Sim(a) => cli::sim::run(a),
        Command::Record(a) => cli::record::run(a),
        Command::Replay(a) => cli::replay::run(a),
        Command::Conform(a) => cli::conform::run(a),
        Command::Certify(a) => cli::certify::run(a),
        Command::Fuzz(a) => cli::fuzz::run(a),
        Command::CheckHost(a) => cli::check_host::run(a),
        Command::Suite(a) => cli::suite::run(a),
        Command::Vectors(a) => cli::vectors::run(a),
    };
    let code = match result {
        Ok(code) => code,
        Err(e) => {
            // What a hand, a host or a file put in an error is shown escaped, never obeyed.
            cli::stdio::errln!("gcl: error: {}", gcl_model::escape::printable(&cli::error_line(&e)));
            cli::EXIT_ERROR
        }
    };
    // The verdict's code whatever became of stdout (a closed pipe is its reader's choice);
    // output that could not be written where it was asked for (`> /dev/full`) fails a pass.
    match cli::stdio::finish() {
        Some(e) => {
            cli::stdio::errln!("gcl: error: writing to stdout: {e}");
            ExitCode::from(if code == cli::EXIT_OK { cli::EXIT_ERROR } else { code })
        }
        None => ExitCode::from(code),
    }
}
