//! `gcl check-host --serve`: a graded simulated hand for whoever connects, until stopped
//! (library code in `gcl_harness::check_host_serve`). What the `gcl_hand` pytest fixture
//! runs.

use std::io::{Read, Write};
use std::os::fd::AsFd;

use anyhow::Context;
use gcl_harness::check_host::{CheckHostOptions, grade_served};
use gcl_harness::check_host_serve::{ServeOptions, Served, serve};
use gcl_harness::fuzz::host::{Weights, fresh_schedule};
use gcl_harness::sim::misbehave::Schedule;
use gcl_model::Fault;
use gcl_model::escape::printable;
use nix::sys::signal::{SigSet, SigmaskHow, Signal, pthread_sigmask};
use nix::sys::signalfd::SignalFd;

use super::fuzz_host::HostArgs;

/// The options `--serve` adds to `gcl check-host`.
#[derive(Debug, clap::Args)]
pub struct ServeArgs {
    /// Serve a graded hand to whoever connects (no COMMAND): print `port PATH` and `url URL`
    /// on stdout, serve until SIGINT/SIGTERM (or, with --stop-on-eof, until stdin closes),
    /// then grade the whole session as for a host command.
    #[arg(long)]
    pub serve: bool,
    /// With --serve: also stop when stdin reaches its end (a parent that holds a pipe to it
    /// stops the hand by closing it, or by dying).
    #[arg(long, requires = "serve")]
    stop_on_eof: bool,
    /// With --serve: a deliberate firmware bug of the hand (repeatable; see `gcl sim --help`).
    #[arg(long, value_name = "NAME", requires = "serve")]
    fault: Vec<Fault>,
    /// With --serve: misbehave by the random schedule an unguided `gcl fuzz host --seed SEED`
    /// campaign draws for its run I past its systematic pass (SEED:I, I >= 1), planned within
    /// the session's first 10 answers.
    #[arg(long, value_name = "SEED:I", requires = "serve", value_parser = seed_run)]
    misbehave: Option<(u64, u64)>,
    /// With --misbehave: only these misbehaviours, optionally weighted (as `gcl fuzz host --ops`).
    #[arg(long, value_name = "LIST", value_parser = Weights::parse, requires = "misbehave")]
    ops: Option<Weights>,
    /// With --serve: the name of the session in reports (a test's id).
    #[arg(long, value_name = "TEXT", requires = "serve")]
    name: Option<String>,
}

fn seed_run(s: &str) -> Result<(u64, u64), String> {
    let bad = || format!("`{s}`: write SEED:I, two whole numbers, I >= 1");
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let (seed, i) = (a.parse().map_err(|_| bad())?, b.parse::<u64>().map_err(|_| bad())?);
    if i == 0 {
        return Err(bad());
    }
    Ok((seed, i))
}

/// How many answers the fuzzer assumes a session has before it has seen one (the span of a
/// schedule's planned answers is this + 2).
const ASSUMED_ANSWERS: u32 = 8;

/// Most misbehaviours in a schedule: `gcl fuzz host --max-misbehaviours`'s default.
const MAX_PLANNED: usize = 3;

/// Runs `gcl check-host --serve`.
pub fn run(host: &HostArgs, args: &ServeArgs, seed: u64, save_session: Option<&std::path::Path>) -> anyhow::Result<u8> {
    let mut run = host.host_run(seed, super::check_host::CHECK_HANG_DEFAULT)?;
    let schedule = match args.misbehave {
        Some((s, i)) => fresh_schedule(s, i, &args.ops.clone().unwrap_or_default(), MAX_PLANNED, ASSUMED_ANSWERS),
        None => Schedule::default(),
    };
    let opts = ServeOptions {
        transport: run.transport,
        profile: run.profile.clone(),
        time: run.time,
        pace: run.pace,
        hand_seed: seed,
        faults: args.fault.clone(),
        schedule: schedule.clone(),
    };
    let mut mask = SigSet::empty();
    for s in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGHUP] {
        mask.add(s);
    }
    pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&mask), None).context("blocking signals")?;
    let signals = SignalFd::new(&mask).context("signalfd")?;
    let (mut eof_stop, eof_signal) = gcl_harness::sim::stop_pair()?;
    // Without --stop-on-eof the switch is held (dropping it would stop the hand) until the end.
    let _held = if args.stop_on_eof {
        std::thread::spawn(move || {
            let mut buf = [0u8; 256];
            while let Ok(n) = std::io::stdin().read(&mut buf) {
                if n == 0 {
                    break;
                }
            }
            eof_stop.stop();
        });
        None
    } else {
        Some(eof_stop)
    };
    let started = time::OffsetDateTime::now_utc();
    let t0 = std::time::Instant::now();
    let mut announce = |s: &Served| {
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "port {}\nurl {}", s.port, s.url);
        for p in &schedule.planned {
            let _ = writeln!(out, "planned {} at answer {} (variant {})", p.op, p.answer, p.arg);
        }
        let _ = writeln!(out, "ready");
        let _ = out.flush();
    };
    let result = serve(&opts, &[signals.as_fd(), eof_signal.as_fd()], &mut announce).context("serving the hand")?;
    run.command = vec![args.name.clone().unwrap_or_else(|| "(served)".into())];
    let check = CheckHostOptions { run, ok_exit_codes: vec![0], golden: None };
    let outcome = grade_served(&check, result, started, t0);
    if let Some(p) = save_session {
        gcl_harness::report::write_atomic(p, outcome.session.as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    let report = outcome.report;
    {
        let mut out = std::io::stdout().lock();
        for f in &outcome.run.fired {
            writeln!(out, "fired {} at answer {} ({}): {}", f.op, f.answer, printable(&f.state), printable(&f.what))?;
        }
    }
    // As `gcl check-host`: a clause the host never exercised (no RealTime) is not a failure,
    // and a session nobody talked in judged nothing (exit 2).
    super::check_host::print_clauses(&report);
    if let Some(dir) = host.report_dir() {
        for p in gcl_harness::report::write_all(dir, &report)? {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(super::check_host::exit_code(&report))
}
