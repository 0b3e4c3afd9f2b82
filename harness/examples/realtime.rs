//! The seed's "RealTime Mode Example Program", ported: `RTSetFlags("123",1,1,0,0,1,0,1,0,1)`,
//! `123LOOP`; F1 closes at velocity 55, F2 starts when F1 passes 5000, F3 when F2 passes 5000;
//! stops after 6 s and prints the final positions.
//!
//! ```text
//! cargo run --example realtime -- --target sim:seed
//! gcl sim --pty --profile seed --time fast   # the hand's clock is wire time
//! cargo run --example realtime -- --target serial:/dev/pts/N --profile seed --clock wire
//! gcl sim --tcp 127.0.0.1:5000 --profile seed --time real
//! cargo run --example realtime -- --target tcp://127.0.0.1:5000 --profile seed --clock link
//! ```

use std::process::ExitCode;
use std::time::Duration;

use clap::{Parser, ValueEnum};
use gcl_host::client::Hand;
use gcl_host::client::programs::{self, Clock};
use gcl_host::target::{OpenOptions, Target};

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ClockArg {
    /// The link's clock: simulated time for sim targets, the wall clock elsewhere.
    Link,
    /// Wire time (bytes x 10 / baud): matches `gcl sim --time fast` across a pty, TCP or stdio.
    Wire,
}

/// Run the seed's RealTime example: three fingers closing one after the other.
#[derive(Debug, Parser)]
struct Args {
    /// The hand: sim[:PROFILE], serial:PATH[?baud=N], tcp://HOST:PORT or exec:COMMAND ARGS.
    #[arg(long, default_value = "sim:seed")]
    target: Target,
    /// The hand's profile, for targets outside this process (default bh8-262).
    #[arg(long)]
    profile: Option<String>,
    /// Which clock ends the run.
    #[arg(long, value_enum, default_value = "link")]
    clock: ClockArg,
    /// Line rate the wire clock counts (default: the target's ?baud=, else 9600).
    #[arg(long)]
    baud: Option<u32>,
    /// How long to run, seconds.
    #[arg(long, default_value_t = 6.0)]
    seconds: f64,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let baud = args.baud.unwrap_or(match &args.target {
        Target::Serial { baud, .. } => *baud,
        _ => 9600,
    });
    let clock = match args.clock {
        ClockArg::Link => Clock::Link,
        ClockArg::Wire => Clock::Wire { baud },
    };
    let run_for = Duration::try_from_secs_f64(args.seconds).unwrap_or(Duration::from_secs(6));
    let opts = OpenOptions { profile: args.profile, ..Default::default() };
    let mut out = std::io::stdout();
    let result =
        Hand::open(&args.target, &opts).and_then(|mut hand| programs::realtime(&mut hand, clock, run_for, &mut out));
    match result {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("\nERROR: {e}");
            ExitCode::from(1)
        }
    }
}
