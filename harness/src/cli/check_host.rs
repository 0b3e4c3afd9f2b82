//! `gcl check-host`: a perfect simulated hand grades a host program's traffic clause by clause
//! (library code in `gcl_harness::check_host`).

use std::path::PathBuf;

use anyhow::Context;
use gcl_harness::check_host::{CheckHostOptions, check_host};
use gcl_harness::report::Verdict;

use super::fuzz_host::HostArgs;
use super::{EXIT_FAIL, EXIT_OK};

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

Exit codes: 0 every clause passes, 1 a clause fails, 2 usage or infrastructure.

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
    let progress = super::progress::Progress::new(
        "gcl check-host",
        "runs",
        "failing clause(s)",
        super::progress::Total::Units(1),
        false,
    );
    let outcome = check_host(&opts).context("running the host");
    // The run's failing clauses, as the verdict below counts them.
    let failing = outcome.as_ref().map_or(0, |o| o.report.cases.iter().filter(|c| c.verdict.fails_run()).count());
    progress.update(1, failing as u64, "");
    progress.finish();
    let outcome = outcome?;
    let mut report = outcome.report;
    use gcl_harness::fuzz::host::HostEnd;
    let end = match &outcome.run.end {
        HostEnd::Exit(c) => format!("exited with code {c}"),
        HostEnd::Signal(s) => format!("killed by signal {s}"),
        HostEnd::Hung(at) => format!("hung ({at}); killed"),
        HostEnd::OverBudget(at) => format!("over the run budget ({at}); killed"),
    };
    let mut facts = vec![("the host".to_string(), end)];
    facts.extend(super::fuzz_host::hand_facts(&opts.run));
    let hang = opts.run.timeout_hang.as_secs_f64();
    let given = if args.host.timeout_hang_given() { "--timeout-hang" } else { "the default" };
    facts.push(("hang timeout".into(), format!("{hang} s ({given})")));
    if let Some(g) = &args.golden {
        facts.push(("golden".into(), g.display().to_string()));
    }
    report.host = Some(gcl_harness::report::HostDetails {
        command: opts.run.command.clone(),
        runs: 1,
        seed: args.seed,
        facts,
        ..Default::default()
    });
    if let Some(p) = &args.save_session {
        gcl_harness::report::write_atomic(p, outcome.session.as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
        eprintln!("wrote {}", p.display());
    }
    for c in &report.cases {
        let verdict = if c.verdict == Verdict::Skip { "not exercised" } else { c.verdict.as_str() };
        println!("{verdict:<7} {:<24} {}", c.id, c.title);
        if let Some(m) = &c.message {
            println!("        {m}");
        }
    }
    let failed = report.cases.iter().filter(|c| c.verdict.fails_run()).count();
    let idle = report.cases.iter().filter(|c| c.verdict == Verdict::Skip).count();
    println!("{} clause(s), {failed} failing, {idle} not exercised", report.cases.len());
    if let Some(dir) = args.host.report_dir() {
        for p in gcl_harness::report::write_all(dir, &report)? {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(if failed == 0 { EXIT_OK } else { EXIT_FAIL })
}
