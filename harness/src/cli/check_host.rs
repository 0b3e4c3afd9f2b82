//! `gcl check-host`: a perfect simulated hand grades a host program's traffic clause by clause
//! (library code in `gcl_harness::host_check`); with `--serve`, a graded simulated hand for
//! whoever connects, until stopped (library code in `gcl_harness::host_check_serve`), which
//! the `gcl_hand` pytest fixture runs.

use super::stdio::{errln, outln};
use std::path::PathBuf;

use anyhow::Context;
use gcl_harness::fuzz::host::{RunError, unreached};
use gcl_harness::host_check::{CheckHostOptions, SESSION_CASE, check_host_until, grade_served, stopped_report};
use gcl_harness::report::Verdict;

use super::fuzz_host::HostArgs;
use super::{EXIT_ERROR, EXIT_FAIL, EXIT_OK};
use gcl_harness::fuzz::host::{Weights, fresh_schedule};
use gcl_harness::host_check_serve::{ServeOptions, Served, serve};
use gcl_harness::sim::misbehave::Schedule;
use gcl_model::Fault;
use gcl_model::escape::printable;
use nix::sys::signal::{SigSet, SigmaskHow, Signal, pthread_sigmask};
use nix::sys::signalfd::SignalFd;
use std::io::{Read, Write};
use std::os::fd::AsFd;

/// `gcl check-host`'s hang timeout when `--timeout-hang` is not given: a perfect hand never
/// goes silent, so a host silent this long waits for nothing it will get; above the 5 to 15 s
/// timeouts real host libraries use, so a host that waits out its own timeout is no hang.
pub(super) const CHECK_HANG_DEFAULT: std::time::Duration = std::time::Duration::from_secs(20);

/// Arguments of `gcl check-host`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = "\
Clauses: host-line-ending (lines, the last one too, end in a single CR, never LF), host-valid-commands (command
words, prefixes and values valid for the profile), host-waits-for-answer (nothing sent while an
answer is still coming, except ^C), host-realtime-blocks (control blocks of the layout's size
with a valid header), host-leaves-cleanly (the RealTime loop left before the host
goes), host-exits-cleanly (no crash, no hang, an accepted exit code); with --golden,
host-golden (the host sends exactly the golden transcript's `send` bytes).

Exit codes: 0 every clause the host exercised passes (a clause it never exercised, such as
RealTime's for a host that never enters it, is \"not exercised\", never PASS); 1 a clause
fails; 2 nothing judged, or a usage or infrastructure error: the host never opened the port,
or opened it and sent nothing (an ERROR naming the command, how it ended and the last lines
of its stderr; with --serve: nobody opened the port, or nobody sent a byte, before the stop),
or a signal (SIGINT, SIGTERM, SIGHUP) stopped the check (the host's process group is
stopped, its run folder removed, and the reports say so).

Example:
  gcl check-host --profile seed --report reports/host -- python3 my_host.py {port}
  gcl check-host --serve --profile seed --report reports/host   # grades whoever connects")]
#[command(mut_arg("command", |a| a.required(false).required_unless_present("serve")))]
pub struct Args {
    #[command(flatten)]
    serve: ServeArgs,
    #[command(flatten)]
    host: HostArgs,
    /// Compare the bytes the host sends with the `send` steps of this transcript.
    #[arg(long, value_name = "FILE")]
    golden: Option<PathBuf>,
    /// Write the session (what the host sent and the hand answered) to FILE as a transcript;
    /// a later run can take it as its --golden.
    #[arg(long, value_name = "FILE")]
    save_session: Option<PathBuf>,
    /// Seed of the hand's noise.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// Runs `gcl check-host`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    if args.serve.serve {
        return run_serve(&args.host, &args.serve, args.seed, args.save_session.as_deref());
    }
    let golden = match &args.golden {
        Some(p) => {
            let text = gcl_host::files::read_input_text(p).with_context(|| format!("golden {}", p.display()))?;
            Some(gcl_transcript::parse(&text).with_context(|| format!("golden {}", p.display()))?)
        }
        None => None,
    };
    let opts = CheckHostOptions {
        run: args.host.host_run(args.seed, CHECK_HANG_DEFAULT)?,
        ok_exit_codes: args.host.ok_exit_codes(),
        golden,
    };
    // Ctrl-C or SIGTERM stops the host's process group and removes its run folder, and the
    // reports say the check was stopped. Before any thread starts.
    let stop = super::stop_on_signals("check-host")?;
    let progress = super::progress::Progress::new(
        "gcl check-host",
        "runs",
        "failing clause(s)",
        super::progress::Total::Units(1),
        false,
    );
    let started = time::OffsetDateTime::now_utc();
    let t0 = std::time::Instant::now();
    let outcome = check_host_until(&opts, &stop);
    // The run's failing clauses, as the verdict below counts them.
    let failing = outcome.as_ref().map_or(0, |o| o.report.cases.iter().filter(|c| c.verdict.fails_run()).count());
    progress.update(1, failing as u64, "");
    progress.finish();
    let (mut report, run) = match outcome {
        Ok(o) => {
            if let Some(p) = &args.save_session {
                gcl_harness::report::write_atomic(p, o.session.as_bytes())
                    .with_context(|| format!("writing {}", p.display()))?;
                errln!("wrote {}", p.display());
            }
            (o.report, Some(o.run))
        }
        Err(RunError::Cancelled) => {
            let by = super::stopped_by().unwrap_or_else(|| "a signal".into());
            (stopped_report(&opts, &format!("stopped by {by}"), started, t0), None)
        }
        Err(e) => return Err(anyhow::Error::new(e).context("running the host")),
    };
    let mut facts = Vec::new();
    if let Some(r) = &run {
        facts.push(("the host".to_string(), r.end.to_string()));
    }
    facts.extend(super::fuzz_host::hand_facts(&opts.run));
    let hang = opts.run.timeout_hang.as_secs_f64();
    let given = if args.host.timeout_hang_given() { "--timeout-hang" } else { "the default" };
    facts.push(("hang timeout".into(), format!("{hang} s ({given})")));
    if let Some(g) = &args.golden {
        facts.push(("golden".into(), g.display().to_string()));
    }
    let reached = run.as_ref().is_some_and(|r| unreached(r, &opts.run.command).is_none());
    report.host = Some(gcl_harness::report::HostDetails {
        command: opts.run.command.clone(),
        runs: u64::from(run.is_some()),
        reached: Some(u64::from(reached)),
        seed: args.seed,
        facts,
        ..Default::default()
    });
    print_clauses(&report);
    if let Some(dir) = args.host.report_dir() {
        for p in gcl_harness::report::write_all(dir, &report)? {
            errln!("wrote {}", p.display());
        }
    }
    Ok(exit_code(&report))
}

/// The console's table: one row per clause (and the session's ERROR when nothing was
/// judged), then the count and how much was judged.
pub(super) fn print_clauses(report: &gcl_harness::report::RunReport) {
    for c in &report.cases {
        let verdict = if c.verdict == Verdict::Skip { "not exercised" } else { c.verdict.as_str() };
        outln!("{verdict:<7} {:<24} {}", c.id, c.title);
        if let Some(m) = &c.message {
            outln!("        {}", gcl_model::escape::printable(m));
        }
    }
    let session = report.cases.iter().any(|c| c.id == SESSION_CASE);
    let failed = report.cases.iter().filter(|c| c.verdict.fails_run() && c.id != SESSION_CASE).count();
    let idle = report.cases.iter().filter(|c| c.verdict == Verdict::Skip).count();
    let judged = report.judged().unwrap_or_default();
    if session {
        outln!("nothing judged: {idle} clause(s) not exercised ({judged})");
    } else {
        outln!("{} clause(s), {failed} failing, {idle} not exercised ({judged})", report.cases.len());
    }
    outln!("result: {}", report.verdict_line());
}

/// 0 every clause exercised passes, 1 a clause fails, 2 nothing judged (the host never
/// talked to the hand, or the check was stopped).
pub(super) fn exit_code(report: &gcl_harness::report::RunReport) -> u8 {
    let session = report.cases.iter().any(|c| c.id == SESSION_CASE && c.verdict == Verdict::Error);
    let failed = report.cases.iter().any(|c| c.verdict.fails_run() && c.id != SESSION_CASE);
    match (session, failed) {
        (true, _) => EXIT_ERROR,
        (false, true) => EXIT_FAIL,
        (false, false) => EXIT_OK,
    }
}

// `gcl check-host --serve`.

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
pub fn run_serve(
    host: &HostArgs,
    args: &ServeArgs,
    seed: u64,
    save_session: Option<&std::path::Path>,
) -> anyhow::Result<u8> {
    let mut run = host.host_run(seed, CHECK_HANG_DEFAULT)?;
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
        let mut out = super::stdio::out();
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
        let mut out = super::stdio::out();
        for f in &outcome.run.fired {
            writeln!(out, "fired {} at answer {} ({}): {}", f.op, f.answer, printable(&f.state), printable(&f.what))?;
        }
    }
    // As `gcl check-host`: a clause the host never exercised (no RealTime) is not a failure,
    // and a session nobody talked in judged nothing (exit 2).
    print_clauses(&report);
    if let Some(dir) = host.report_dir() {
        for p in gcl_harness::report::write_all(dir, &report)? {
            errln!("wrote {}", p.display());
        }
    }
    Ok(exit_code(&report))
}
