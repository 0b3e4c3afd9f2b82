//! `gcl check-host`: a perfect simulated hand grades a host program's traffic clause by clause
//! (library code in `gcl_harness::check_host`).

use std::path::PathBuf;

use anyhow::Context;
use gcl_harness::check_host::{CheckHostOptions, SESSION_CASE, check_host_until, stopped_report};
use gcl_harness::fuzz::host::{RunError, unreached};
use gcl_harness::report::Verdict;

use super::fuzz_host::HostArgs;
use super::{EXIT_ERROR, EXIT_FAIL, EXIT_OK};

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
    serve: super::check_host_serve::ServeArgs,
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
        return super::check_host_serve::run(&args.host, &args.serve, args.seed, args.save_session.as_deref());
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
                eprintln!("wrote {}", p.display());
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
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(exit_code(&report))
}

/// The console's table: one row per clause (and the session's ERROR when nothing was
/// judged), then the count and how much was judged.
pub(super) fn print_clauses(report: &gcl_harness::report::RunReport) {
    for c in &report.cases {
        let verdict = if c.verdict == Verdict::Skip { "not exercised" } else { c.verdict.as_str() };
        println!("{verdict:<7} {:<24} {}", c.id, c.title);
        if let Some(m) = &c.message {
            println!("        {}", gcl_model::escape::printable(m));
        }
    }
    let session = report.cases.iter().any(|c| c.id == SESSION_CASE);
    let failed = report.cases.iter().filter(|c| c.verdict.fails_run() && c.id != SESSION_CASE).count();
    let idle = report.cases.iter().filter(|c| c.verdict == Verdict::Skip).count();
    let judged = report.judged().unwrap_or_default();
    if session {
        println!("nothing judged: {idle} clause(s) not exercised ({judged})");
    } else {
        println!("{} clause(s), {failed} failing, {idle} not exercised ({judged})", report.cases.len());
    }
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
