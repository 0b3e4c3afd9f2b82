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
//! cargo run --example realtime -- --target sim:seed --plot realtime.html
//! ```
//!
//! `--plot FILE` writes a page of the run: each finger's position per block over the band the
//! reference model gives for the same program (its own run in-process, ± 100 counts), and the
//! velocities sent.

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
    /// Write an HTML page of the run: positions per block against the reference model's band.
    #[arg(long, value_name = "FILE")]
    plot: Option<std::path::PathBuf>,
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
    let result = Hand::open(&args.target, &opts).and_then(|mut hand| {
        let profile = hand.profile().id.clone();
        programs::realtime(&mut hand, clock, run_for, &mut out).map(|r| (r, profile))
    });
    let (run, profile) = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("\nERROR: {e}");
            return ExitCode::from(1);
        }
    };
    let Some(path) = &args.plot else { return ExitCode::SUCCESS };
    // The reference: the model runs the same program for the same time on its own clock.
    let model = format!("sim:{profile}")
        .parse::<Target>()
        .map_err(|e| e.to_string())
        .and_then(|t| Hand::open(&t, &OpenOptions::default()).map_err(|e| e.to_string()))
        .and_then(|mut h| {
            programs::realtime(&mut h, Clock::Link, run_for, &mut std::io::sink()).map_err(|e| e.to_string())
        });
    let model = match model {
        Ok(m) => m,
        Err(e) => {
            eprintln!("ERROR: the reference model's run: {e}");
            return ExitCode::from(1);
        }
    };
    let options = vec![
        ("clock".to_string(), format!("{:?}", args.clock).to_lowercase()),
        ("seconds".to_string(), args.seconds.to_string()),
    ];
    let page =
        gcl_harness::report::program::realtime_program_page(&args.target.to_string(), &profile, &options, &run, &model);
    match gcl_harness::report::write_atomic(path, page.as_bytes()) {
        Ok(()) => {
            println!("wrote {}", path.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("ERROR: {}: {e}", path.display());
            ExitCode::from(1)
        }
    }
}
