//! `gcl sim`: the simulated grasper on a pty, TCP or stdio (the transports live in
//! [`gcl_harness::sim`]). This module parses arguments, turns start-up problems into one line on
//! stderr and exit code 2, and stops cleanly on SIGINT, SIGTERM and SIGHUP.

use super::stdio::errln;
use std::io::Write;
use std::os::fd::AsFd;
use std::path::PathBuf;

use anyhow::Context;
use gcl_model::Fault;
use nix::sys::signal::{SigSet, SigmaskHow, Signal, pthread_sigmask};
use nix::sys::signalfd::SignalFd;

use super::{EXIT_OK, load_profile};
use gcl_harness::sim::{
    Engine, Pace, SCENARIO_EXAMPLE, SimOptions, TimeMode, check_scenario, parse_scenario, pty::Pty, stdio,
    tcp::TcpServer,
};

fn after_help() -> String {
    let faults: Vec<String> = Fault::ALL.iter().map(|f| format!("  {:<20} {}", f.name(), f.description())).collect();
    let scenario: Vec<String> = SCENARIO_EXAMPLE.lines().map(|l| format!("  {l}")).collect();
    format!(
        "\
Transports (exactly one):
  --pty        prints the slave path (e.g. /dev/pts/7) alone on the first line of stdout.
               Open it like a serial port: serial.Serial('/dev/pts/7') in pyserial, or
               --target serial:/dev/pts/7. The line is raw (no echo by the tty, no CR
               translation) and starts at the hand's rate. It opens and closes like a serial
               port: the hand keeps its state across a reopen, what the host had not read is
               discarded when it closes, and what the hand sends while no host has the port
               open is lost (so the power-up banner is never seen; send RESET to see one).
               While paced, the speed the host sets on the port is checked against the hand's
               rate: when they differ, bytes cross garbled both ways, as through a UART at the
               wrong rate (a host that changes the hand's BAUD must change its own too). Each
               byte is judged at the speed set when it crosses, standard or arbitrary
               (termios2); within 2 % of the hand's rate is the same rate. The simulator sets
               the port's speed once, before it prints the path, and never over the host's.
               --no-speed-check turns this off.
  --tcp ADDR   prints the bound address (e.g. 127.0.0.1:40123) alone on the first line of stdout.
               ADDR is HOST:PORT or PORT (127.0.0.1); port 0 picks a free one. One client at a
               time, like a cable: a second connection while one is active is closed at once with
               nothing written. State persists across clients; what a client had not read is
               discarded when it goes, and output produced while no client is connected is lost.
               A client that half-closes still gets its answers.
               pyserial: serial.serial_for_url('socket://127.0.0.1:40123').
  --stdio      speaks on stdin/stdout (for exec: targets); exits 0 at end of input.

Defaults match a hand: --pty and --tcp run in real time, paced at the hand's BAUD parameter
(9600 at the factory) in both directions; PSET BAUD / FSET BAUD change the pace after their
answer. --stdio defaults to fast time, unpaced (it is a pipe to a test program, not a line).
Nothing is dropped while a host is connected: when it stops reading, the simulator stops
reading it.

Time (--time):
  real   simulated time is the wall clock; motion takes as long as on a hand; ^C stops it.
  fast   an opt-in speed-up: every byte takes its wire time at the hand's BAUD in simulated
         time, and motion completes at once in simulated time. A host that counts wire time
         (bytes x 10 / baud) sees the hand's clock:
         cargo run --example realtime -- --target serial:/dev/pts/7 --profile seed --clock wire
         Unpaced unless --baud is given.
Pace:
  --baud N     pace both directions at N whatever the hand's BAUD says.
  --unpaced    an opt-in speed-up: bytes cross at once (no hand does this).

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
  gcl sim --tcp 127.0.0.1:5000 --trace hand.trace
  gcl sim --pty --time fast --unpaced
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
    /// With --pty: do not garble bytes when the host's port speed differs from the hand's.
    #[arg(long, requires = "pty")]
    no_speed_check: bool,
    /// With --tcp: allow a non-loopback address.
    #[arg(long, requires = "tcp")]
    allow_remote: bool,
    /// Serve on stdin/stdout.
    #[arg(long)]
    stdio: bool,
    /// Profile: seed, bh8-262-4.3, bh8-262-4.4 (alias bh8-262), or a spec TOML file.
    #[arg(long, default_value = "bh8-262")]
    profile: String,
    /// Pace both directions at this rate (8N1: 10 bits a byte) instead of the hand's BAUD.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(50..=4_000_000), conflicts_with = "unpaced")]
    baud: Option<u32>,
    /// Opt-in speed-up: no line timing at all.
    #[arg(long)]
    unpaced: bool,
    /// real: the wall clock (default for --pty and --tcp); fast: opt-in speed-up, simulated time
    /// follows the bytes on the wire and motion completes at once (default for --stdio).
    #[arg(long, value_enum)]
    time: Option<TimeArg>,
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

/// `--time`: the command line's names for a [`TimeMode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum TimeArg {
    /// Simulated time advances by the wire time of every byte exchanged (at the hand's BAUD)
    /// and by the duration of each motion, which completes as fast as the CPU allows. The same
    /// bytes always give the same answers, whatever the host's speed.
    Fast,
    /// Simulated time is the wall clock since start: a motion takes as long as on a hand and a
    /// ^C sent mid-motion stops it.
    Real,
}

impl From<TimeArg> for TimeMode {
    fn from(t: TimeArg) -> TimeMode {
        match t {
            TimeArg::Fast => TimeMode::Fast,
            TimeArg::Real => TimeMode::Real,
        }
    }
}

/// Runs `gcl sim`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let profile = load_profile(&args.profile)?;
    let scenario = match &args.scenario {
        Some(p) => {
            let text = gcl_host::files::read_input_text(p).with_context(|| format!("scenario file {}", p.display()))?;
            let s = parse_scenario(&text).with_context(|| format!("scenario file {}", p.display()))?;
            check_scenario(&s, &profile).with_context(|| format!("scenario file {}", p.display()))?;
            s
        }
        None => Default::default(),
    };
    let time = args.time.map(TimeMode::from).unwrap_or(if args.stdio { TimeMode::Fast } else { TimeMode::Real });
    let pace = match (args.unpaced, args.baud) {
        (true, _) => Pace::Unpaced,
        (false, Some(b)) => Pace::Fixed(b),
        (false, None) if time == TimeMode::Fast => Pace::Unpaced,
        (false, None) => Pace::Hand,
    };
    let opts = SimOptions {
        profile,
        seed: args.seed,
        scenario,
        faults: args.faults.clone(),
        time,
        pace,
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
        let mut engine = Engine::new(&opts)?;
        let mut pty = Pty::open(args.link.as_deref(), engine.line_baud())?;
        pty.set_speed_check(!args.no_speed_check);
        pty.on_speed_mismatch(|line| errln!("gcl sim: {line} (--no-speed-check to turn this off)"));
        announce(&pty.path().display().to_string())?;
        errln!(
            "gcl sim: profile {} on {}{} (time {}, {}); stop with ^C",
            gcl_model::escape::printable(&opts.profile.id),
            pty.path().display(),
            pty.link().map(|l| format!(" (link {})", l.display())).unwrap_or_default(),
            opts.time.name(),
            opts.pace.phrase()
        );
        pty.serve(&mut engine, &stops)?;
    } else if let Some(addr) = &args.tcp {
        let mut server = TcpServer::bind(addr, args.allow_remote)?;
        let mut engine = Engine::new(&opts)?;
        announce(&server.local_addr().to_string())?;
        errln!(
            "gcl sim: profile {} on tcp {} (time {}, {}); stop with ^C",
            gcl_model::escape::printable(&opts.profile.id),
            server.local_addr(),
            opts.time.name(),
            opts.pace.phrase()
        );
        server.serve(&mut engine, &stops)?;
    } else {
        let mut engine = Engine::new(&opts)?;
        stdio::serve_stdio(&mut engine, &stops)?;
    }
    Ok(EXIT_OK)
}

/// The first line of stdout: what clients connect to. A hand nobody can find is not served:
/// when that line cannot be written (stdout closed), the command ends with an error.
fn announce(what: &str) -> anyhow::Result<()> {
    let mut out = super::stdio::out();
    writeln!(out, "{what}")?;
    out.flush()?;
    if super::stdio::stdout_lost() {
        anyhow::bail!("stdout is closed: nobody can read where the hand is ({what}), so it is not served");
    }
    Ok(())
}
