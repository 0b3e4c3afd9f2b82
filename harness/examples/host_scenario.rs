//! A host program with a ten-command supervisory scenario and short timeouts, built on the
//! host library: the correct host that `gcl fuzz host` and `gcl check-host` are tried against
//! (tests, benchmark), and a template for a host author's own CI scenario.
//!
//! ```text
//! gcl check-host --profile seed -- target/debug/examples/host_scenario --target 'serial:{port}' --profile seed
//! gcl fuzz host --profile seed --runs 100 -- target/debug/examples/host_scenario --target 'serial:{port}' --profile seed
//! ```
//! Exit codes: 0 the scenario ran, 1 the hand misbehaved (one line on stderr says how).

use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use gcl_host::client::{ClientError, Hand, Timeouts};
use gcl_host::target::{OpenOptions, Target};

/// Ten commands against a hand, each with a short deadline.
#[derive(Debug, Parser)]
struct Args {
    /// The hand: sim[:PROFILE], serial:PATH[?baud=N], tcp://HOST:PORT or exec:COMMAND ARGS.
    #[arg(long, default_value = "sim:seed")]
    target: Target,
    /// The hand's profile, for targets outside this process (default bh8-262).
    #[arg(long)]
    profile: Option<String>,
}

const SCENARIO: [&str; 10] =
    ["FGET DP", "HI", "1M 5000", "1FGET P", "C", "FGET P", "O", "2M 1000", "123FGET P", "FGET DP"];

fn scenario(hand: &mut Hand) -> Result<(), ClientError> {
    let t = Duration::from_millis(500);
    hand.set_timeouts(Timeouts { reply: t, motion: t * 4, block: t, sync: t });
    for line in SCENARIO {
        let first = line.trim_start_matches(|c: char| c.is_ascii_digit());
        if ["HI", "M", "C", "O"].iter().any(|m| first == *m || first.starts_with(&format!("{m} "))) {
            hand.motion(line)?;
        } else {
            hand.command(line)?;
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = Args::parse();
    let opts = OpenOptions { profile: args.profile, ..Default::default() };
    match Hand::open(&args.target, &opts).and_then(|mut hand| scenario(&mut hand)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("host_scenario: {e}");
            ExitCode::from(1)
        }
    }
}
