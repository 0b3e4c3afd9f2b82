//! The seed's "Supervisory Mode Example Program", ported: initialise the hand, close F1-F3,
//! open them, and print what it does.
//!
//! ```text
//! cargo run --example supervisory -- --target sim:seed
//! gcl sim --pty --profile seed            # prints /dev/pts/N
//! cargo run --example supervisory -- --target serial:/dev/pts/N --profile seed
//! cargo run --example supervisory -- --target 'exec:target/debug/gcl sim --stdio --profile seed' --profile seed
//! ```

use std::process::ExitCode;

use clap::Parser;
use gcl_host::client::{Hand, programs};
use gcl_host::target::{OpenOptions, Target};

/// Initialise a BarrettHand, close F1-F3 and open them again.
#[derive(Debug, Parser)]
struct Args {
    /// The hand: sim[:PROFILE], serial:PATH[?baud=N], tcp://HOST:PORT or exec:COMMAND ARGS.
    #[arg(long, default_value = "sim:seed")]
    target: Target,
    /// The hand's profile, for targets outside this process (default bh8-262).
    #[arg(long)]
    profile: Option<String>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let opts = OpenOptions { profile: args.profile, ..Default::default() };
    let mut out = std::io::stdout();
    let result = Hand::open(&args.target, &opts).and_then(|mut hand| programs::supervisory(&mut hand, &mut out));
    match result {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("\nERROR: {e}");
            ExitCode::from(1)
        }
    }
}
