//! `gcl sim`: the simulated grasper on a pty, TCP or stdio (the transports live in
//! [`crate::sim`]). This module parses arguments, turns start-up problems into one line on
//! stderr and exit code 2, and stops cleanly on SIGINT, SIGTERM and SIGHUP.

use std::io::Write;
use std::os::fd::AsFd;
use std::path::PathBuf;

use anyhow::Context;
use gcl_model::Fault;
use nix::sys::signal::{SigSet, SigmaskHow, Signal, pthread_sigmask};
use nix::sys::signalfd::SignalFd;

use super::{EXIT_OK, load_profile};
use crate::sim::{Engine, SCENARIO_EXAMPLE, SimOptions, TimeMode, parse_scenario, pty::Pty, stdio, tcp::TcpServer};

fn after_help() -> String {
    let faults: Vec<String> = Fault::ALL.iter().map(|f| format!("  {:<20} {}", f.name(), f.description())).collect();
    let scenario: Vec<String> = SCENARIO_EXAMPLE.lines().map(|l| format!("  {l}")).collect();
    format!(
        "\
Transports (exactly one):
  --pty        prints the slave path (e.g. /dev/pts/7) alone on the first line of stdout.
               Open it like a serial port: serial.Serial('/dev/pts/7') in pyserial, or
               --target serial:/dev/pts/7. The line is raw (no echo by the tty, no CR
               translation). Closing and reopening the port keeps the hand's state; a client
               should discard stale input when it opens.
  --tcp ADDR   prints the bound address (e.g. 127.0.0.1:40123) alone on the first line of stdout.
               ADDR is HOST:PORT or PORT (127.0.0.1); port 0 picks a free one. One client at a
               time, like a cable: a second connection while one is active is closed at once with
               nothing written. State persists across clients; output produced while no client is
               connected is dropped. pyserial: serial.serial_for_url('socket://127.0.0.1:40123').
  --stdio      speaks on stdin/stdout (for exec: targets); exits 0 at end of input.

Time:
  fast   every byte takes its wire time at the hand's BAUD parameter (9600 at the factory;
         --baud only paces the output) in simulated time, and motion completes at once in
         simulated time. A host that counts wire time (bytes x 10 / baud) sees the hand's clock:
         cargo run --example realtime -- --target serial:/dev/pts/7 --profile seed --clock wire
  real   simulated time is the wall clock; motion takes as long as on a hand; ^C stops it.

Faults (--fault NAME, repeatable):
{}

Scenario file (--scenario FILE, TOML):
{}

EEPROM (--eeprom FILE): JSON of the hand's non-volatile memory. Loaded at start if present;
rewritten atomically whenever a command changes it (FSAVE, PSAVE...), wear counters at most every
5 s and at exit.

Trace (--trace FILE): one line per chunk in each direction: wall seconds, simulated seconds, '>'
(host to hand) or '<' (hand to host) or '#' (event), and the bytes escaped (\\n \\r \\xHH).

Start-up errors (bad profile, scenario or EEPROM file, port in use) print one line on stderr and
exit 2. Nothing a client sends stops the simulator; SIGINT/SIGTERM stop it with exit 0.

Examples:
  gcl sim --pty --link /tmp/hand --profile seed
  gcl sim --tcp 127.0.0.1:5000 --time real --baud 9600 --trace hand.trace
  gcl sim --stdio --eeprom hand.json --fault no-echo",
        faults.join("\n"),
        scenario.join("\n")
    )
}

/// Arguments of `gcl sim`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = after_help())]
#[command(group(clap::ArgGroup::new("transport").required(true).args(["pty", "tcp", "stdio"])))]
pub struct Args {
    /// Serve on a new pseudo-terminal; prints its path on the first line of stdout.
    #[arg(long)]
    pty: bool,
    /// With --pty: also make a symbolic link to the pty at PATH (removed at exit).
    #[arg(long, value_name = "PATH", requires = "pty")]
    link: Option<PathBuf>,
    /// Serve on TCP at HOST:PORT or PORT (loopback); prints the bound address on stdout's first line.
    #[arg(long, value_name = "ADDR")]
    tcp: Option<String>,
    /// With --tcp: allow a non-loopback address.
    #[arg(long, requires = "tcp")]
    allow_remote: bool,
    /// Serve on stdin/stdout.
    #[arg(long)]
    stdio: bool,
    /// Profile: seed, bh8-262-4.3, bh8-262-4.4 (alias bh8-262), or a spec TOML file.
    #[arg(long, default_value = "bh8-262")]
    profile: String,
    /// Pace output at the byte time of this rate (8N1: 10 bits a byte); unpaced without it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(50..=4_000_000))]
    baud: Option<u32>,
    /// fast: simulated time follows the bytes on the wire, motion completes at once; real: the wall clock.
    #[arg(long, value_enum, default_value = "fast")]
    time: TimeMode,
    /// Keep the EEPROM in this JSON file across runs.
    #[arg(long, value_name = "FILE")]
    eeprom: Option<PathBuf>,
    /// Seed of the simulated noise.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Objects, temperature and other conditions, from a TOML file (see --help).
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Log every byte in both directions, timestamped and escaped, to FILE.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Give the hand a firmware bug (repeatable; names in --help).
    #[arg(long = "fault", value_name = "NAME")]
    faults: Vec<Fault>,
}

/// Runs `gcl sim`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let profile = load_profile(&args.profile)?;
    let scenario = match &args.scenario {
        Some(p) => {
            let text = crate::files::read_input_text(p).with_context(|| format!("scenario file {}", p.display()))?;
            parse_scenario(&text).with_context(|| format!("scenario file {}", p.display()))?
        }
        None => Default::default(),
    };
    let opts = SimOptions {
        profile,
        seed: args.seed,
        scenario,
        faults: args.faults.clone(),
        time: args.time,
        baud: args.baud,
        eeprom: args.eeprom.clone(),
        trace: args.trace.clone(),
    };

    // Signals become a readable descriptor, so the loop stops cleanly (symlink removed,
    // EEPROM saved) without a handler.
    let mut mask = SigSet::empty();
    for s in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGHUP] {
        mask.add(s);
    }
    pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&mask), None).context("blocking signals")?;
    let signals = SignalFd::new(&mask).context("signalfd")?;
    let stops = [signals.as_fd()];

    if args.pty {
        let mut pty = Pty::open(args.link.as_deref())?;
        let mut engine = Engine::new(&opts)?;
        announce(&pty.path().display().to_string())?;
        eprintln!(
            "gcl sim: profile {} on {}{} (time {}); stop with ^C",
            opts.profile.id,
            pty.path().display(),
            pty.link().map(|l| format!(" (link {})", l.display())).unwrap_or_default(),
            opts.time.name()
        );
        pty.serve(&mut engine, &stops)?;
    } else if let Some(addr) = &args.tcp {
        let mut server = TcpServer::bind(addr, args.allow_remote)?;
        let mut engine = Engine::new(&opts)?;
        announce(&server.local_addr().to_string())?;
        eprintln!(
            "gcl sim: profile {} on tcp {} (time {}); stop with ^C",
            opts.profile.id,
            server.local_addr(),
            opts.time.name()
        );
        server.serve(&mut engine, &stops)?;
    } else {
        let mut engine = Engine::new(&opts)?;
        stdio::serve_stdio(&mut engine, &stops)?;
    }
    Ok(EXIT_OK)
}

/// The first line of stdout: what clients connect to.
fn announce(what: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{what}")?;
    out.flush()?;
    Ok(())
}
