//! `gcl conform`: the conformance suite against a hand, with a verdict per case and per
//! clause, reports CI systems read, and exit codes that mean something.

use super::stdio::errln;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use gcl_model::Fault;
use gcl_model::escape::printable;

use super::{EXIT_ERROR, EXIT_FAIL, EXIT_OK, load_profile};
use gcl_harness::conform::{self, ConformOptions, KnownFailures, LevelFilter, RunControl, RunEvent, RunOutput};
use gcl_harness::deadline::DeadlinePolicy;
use gcl_harness::report::{CaseResult, ResultStream, RunReport, StopCause, Verdict, write_all};
use gcl_harness::suite::{self, Case};
use gcl_host::target::{OpenOptions, Target};
use gcl_transcript::{Level, Requirement};

/// Arguments shared by `gcl conform` and `gcl certify`.
#[derive(Debug, clap::Args)]
pub struct SuiteArgs {
    /// The hand: `sim[:PROFILE]`, `serial:PATH[?baud=N]`, `tcp://HOST:PORT` or `exec:COMMAND ARGS`.
    #[arg(long, value_name = "TARGET")]
    pub target: Target,
    /// The profile whose suite runs (default: the sim target's profile, else bh8-262).
    #[arg(long)]
    pub profile: Option<String>,
    /// Run only cases whose id matches (a glob; repeatable).
    #[arg(long, value_name = "GLOB")]
    pub only: Vec<String>,
    /// Skip cases whose id matches (a glob; repeatable).
    #[arg(long, value_name = "GLOB")]
    pub skip: Vec<String>,
    /// A TOML file of known failures (`[[failure]]` tables with `case = "glob"`,
    /// `reason = "..."`, optional `profile`). Listed cases that fail are XFAIL; listed cases that pass are XPASS and fail the run.
    #[arg(long, value_name = "FILE")]
    pub known_failures: Option<PathBuf>,
    /// Skip every case that rests on this decision of the profile (repeatable; `gcl spec`
    /// lists the ids; a known-failures file may hold `[[skip-decision]]` tables with `id` and
    /// `reason`): for an implementation that decided an open point differently.
    #[arg(long, value_name = "ID")]
    pub skip_decision: Vec<String>,
    /// A flat per-step deadline in milliseconds for steps that do not set their own, instead of
    /// deadlines from the model (the model's time for the step at the link's baud × 2 + the
    /// margin, at least 500 ms on serial and 200 ms on TCP targets).
    #[arg(long, value_name = "MS", value_parser = super::millis)]
    pub timeout: Option<u64>,
    /// Added to every model-derived step deadline, in milliseconds (default 50; raise it for a
    /// hand or bridge with latency the model does not know).
    #[arg(long, value_name = "MS", conflicts_with = "timeout", value_parser = super::millis)]
    pub margin: Option<u64>,
    /// Stop after N failing cases; the rest are reported as SKIP, "not run".
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub max_failures: Option<u64>,
    /// Stop at the first failing case (--max-failures 1).
    #[arg(long, conflicts_with = "max_failures")]
    pub fail_fast: bool,
    /// After N timeouts in a row, probe the hand; if it does not answer, the rest of the cases
    /// are not run and the run exits 2. The same after N failing cases in a row after which the
    /// hand would not stop sending (0: never).
    #[arg(long, value_name = "N", default_value_t = gcl_harness::conform::DEFAULT_DEAD_AFTER as u64)]
    pub dead_after: u64,
    /// Skip the framing pre-flight (a few exchanges before the suite that name gross framing
    /// faults: prompt, line ending, echo, banner, status format).
    #[arg(long)]
    pub no_preflight: bool,
    /// Run the abort-timing cases (^C landing mid-motion) even on a hand whose motions end at
    /// once. Without it, a hand outside this process is closed once first; when its motion
    /// takes under a quarter of the model's time (a simulator in fast time, such as `gcl sim
    /// --stdio`), those cases are SKIP and one line says why.
    #[arg(long)]
    pub assume_real_time: bool,
    /// Refuse cases that need this of the hand (motion, realtime, eeprom, abort-timing,
    /// object; repeatable): they are reported as SKIP.
    #[arg(long = "no", value_name = "REQUIREMENT")]
    pub refuse: Vec<String>,
    /// Declare a case's physical set-up in place (only `object`: the objects its `setup:`
    /// lines name, e.g. `setup: object 1 8500`, where that motor meets them when closing).
    /// The in-process `sim` places them itself; on any other target such cases are SKIP
    /// without this flag. An object stays in the way of every case of the run, so run those
    /// cases alone: `--only param-hold-effect --fixture object`.
    #[arg(long = "fixture", value_name = "FIXTURE", value_parser = ["object"])]
    pub fixture: Vec<String>,
    /// Run the committed golden transcripts in DIR (e.g. vectors/suite) instead of the suite
    /// the built-in model generates (they are the same when the goldens are fresh).
    #[arg(long, value_name = "DIR")]
    pub suite: Option<PathBuf>,
    /// The line rate the hand runs at, for the wire-time lower bound (serial targets give
    /// their own with ?baud=N); 50 to 4000000.
    #[arg(long, value_parser = gcl_host::target::parse_baud)]
    pub baud: Option<u32>,
    /// sim targets: seed of the model's noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// sim targets: a deliberate firmware bug (repeatable; see `gcl sim --help`).
    #[arg(long, value_name = "NAME")]
    pub fault: Vec<Fault>,
}

/// Arguments of `gcl conform`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Verdict (the `result:` line, report.json's `verdict`, JUnit's gcl.verdict, the page): PASS \
when every case of the levels run passed; PARTIAL: R of T cases when some did not run (skipped, refused, \
decided otherwise) or P of T cases passed, K known failures excused; FAIL; ERROR when the hand stopped \
answering.\n\nExit codes: 0 no case failed (PASS or PARTIAL: SKIP and XFAIL allowed); 1 a case failed, timed out, \
errored or passed while listed as a known failure; 2 usage or infrastructure error (including a hand that \
does not answer the liveness probe).\n\nExamples:\n  gcl conform --target sim\n  gcl conform --target \
sim:seed --level must --report reports/out\n  gcl conform --target serial:/dev/ttyUSB0 --profile bh8-262-4.3 \
--known-failures reports/known.toml")]
pub struct Args {
    /// The hand and the suite.
    #[command(flatten)]
    pub suite: SuiteArgs,
    /// Levels to run: must (MUST), should (MUST and SHOULD), all (also MAY and INFO).
    #[arg(long, value_enum, default_value_t = LevelArg::All)]
    pub level: LevelArg,
    /// Write report.json, junit.xml, report.html (and results.jsonl as cases end) into DIR.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Print only the summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Write every case that failed, timed out or errored (and every XFAIL) to FILE as a
    /// known-failures list, each with its message as the reason: a baseline of a hand that
    /// already differs, for `--known-failures FILE` on its next build, where only what is new
    /// fails the run (and a listed case that now passes fails it as XPASS).
    #[arg(long, value_name = "FILE")]
    pub write_known_failures: Option<PathBuf>,
}

/// `--level`: the command line's names for a [`LevelFilter`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LevelArg {
    /// MUST only.
    Must,
    /// MUST and SHOULD.
    Should,
    /// Every level: MUST, SHOULD, MAY, INFO.
    All,
}

impl From<LevelArg> for LevelFilter {
    fn from(l: LevelArg) -> LevelFilter {
        match l {
            LevelArg::Must => LevelFilter::Must,
            LevelArg::Should => LevelFilter::Should,
            LevelArg::All => LevelFilter::All,
        }
    }
}

/// The suite, options and cases a run needs, from the shared arguments.
pub fn prepare(
    a: &SuiteArgs,
    level: LevelFilter,
    keep_transcripts: bool,
) -> anyhow::Result<(ConformOptions, Vec<Case>)> {
    let profile = load_profile(a.target.model_profile(a.profile.as_deref()))?;
    let cases = match &a.suite {
        Some(dir) => {
            let c = suite::load_profile(dir, &profile.id)
                .with_context(|| format!("loading the suite from {}", dir.display()))?;
            if c.is_empty() {
                anyhow::bail!("no cases for profile {} under {}", profile.id, dir.display());
            }
            c
        }
        None => suite::generate(&profile).context("generating the suite")?,
    };
    let unmatched = conform::unmatched_globs(&cases, &a.only)?;
    if !unmatched.is_empty() {
        anyhow::bail!(
            "--only {} matches no case of profile {} (`gcl suite list --profile {}` lists them)",
            unmatched.iter().map(|g| format!("`{g}`")).collect::<Vec<_>>().join(", "),
            profile.id,
            profile.id
        );
    }
    let mut known = match &a.known_failures {
        Some(p) => KnownFailures::load(p)?,
        None => KnownFailures::default(),
    };
    for k in known.entries_for(&profile.id, &cases).iter().filter(|k| !k.matched) {
        errln!(
            "gcl: warning: known failure `{}` in {} matches no case of profile {}; it is stale or a typo",
            printable(&k.case),
            known.source().unwrap_or("the known-failures list"),
            printable(&profile.id)
        );
    }
    for id in &a.skip_decision {
        known.skip_decision(id, "--skip-decision");
    }
    let refuse = a
        .refuse
        .iter()
        .map(|r| match Requirement::from_slug(r) {
            Some(Requirement::Other(s)) => {
                anyhow::bail!("unknown requirement `{s}` (motion, realtime, eeprom, abort-timing, object)")
            }
            Some(r) => Ok(r),
            None => anyhow::bail!("bad requirement `{r}`"),
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let open = OpenOptions {
        profile: Some(profile.id.clone()),
        // A profile from a file is simulated as loaded, not looked up again by its id.
        loaded_profile: Some(profile.clone()),
        seed: a.seed,
        faults: a.fault.clone(),
        ..Default::default()
    };
    let opts = ConformOptions {
        target: a.target.clone(),
        open,
        profile,
        level,
        only: a.only.clone(),
        skip: a.skip.clone(),
        known,
        step_timeout: a.timeout.map(Duration::from_millis),
        refuse,
        fixtures: if a.fixture.is_empty() { vec![] } else { vec![Requirement::Object] },
        baud: a.baud,
        keep_transcripts,
        control: RunControl {
            max_failures: if a.fail_fast { Some(1) } else { a.max_failures.map(|n| n as usize) },
            dead_after: a.dead_after as usize,
            deadlines: a.margin.map(|ms| DeadlinePolicy {
                margin: Duration::from_millis(ms),
                ..DeadlinePolicy::for_target(&a.target)
            }),
            preflight: !a.no_preflight,
            real_time_probe: !a.assume_real_time,
        },
    };
    Ok((opts, cases))
}

/// Adds to a report what only the command line knows: the suite's source, and where the
/// profile that ran (`profile`) came from.
pub fn record_options(report: &mut RunReport, a: &SuiteArgs, profile: &gcl_model::Profile) {
    report.options.suite_dir = a.suite.as_ref().map(|d| d.display().to_string());
    let given = a.target.model_profile(a.profile.as_deref());
    report.profile_spec = Some(gcl_harness::report::ProfileSpec::of(given, profile));
}

/// Runs the suite with the shared progress (a bar with an ETA on a terminal, a line every
/// 10 s in a CI log), a line per failing case, and the pre-flight and an early end said once,
/// on stderr, as they happen (the summary on stdout does not repeat them).
pub fn run_with_progress(
    opts: &ConformOptions,
    cases: &[Case],
    report_dir: Option<&std::path::Path>,
    quiet: bool,
    what: &str,
) -> anyhow::Result<RunOutput> {
    let mut stream = match report_dir {
        Some(d) => Some(ResultStream::create(d).with_context(|| format!("creating {}", d.display()))?),
        None => None,
    };
    let progress = super::progress::Progress::new(
        what,
        "cases",
        "failing",
        super::progress::Total::Units(cases.len() as u64),
        quiet,
    );
    let mut failures = 0u64;
    let out = conform::run_with_events(cases, opts, stream.as_mut(), &mut |e| match e {
        RunEvent::Preflight(line) => progress.println(line),
        RunEvent::Case(r, done, total) => {
            if r.verdict.fails_run() {
                failures += 1;
            }
            progress.set_total(total as u64);
            progress.update(done as u64, failures, &r.id);
            let not_run = r.verdict == Verdict::Skip && r.message.as_deref().is_some_and(|m| m.starts_with("not run:"));
            if !quiet && !not_run && r.verdict.fails_run() {
                progress.println(&format!("{:<7} {}: {}", r.verdict, r.id, r.message.as_deref().unwrap_or("")));
            }
        }
        RunEvent::Stopped(st) => progress.println(&format!("{what}: {}", st.message)),
    });
    if out.is_err()
        && let Some(s) = stream.take()
    {
        // A run that could not start (a port that is not there) judged nothing: the empty
        // results.jsonl it made goes, so that a report folder it made goes with its lock.
        let path = s.path().to_path_buf();
        drop(s);
        if std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file() && m.len() == 0) {
            let _ = std::fs::remove_file(&path);
        }
    }
    let out = out?;
    progress.finish();
    Ok(out)
}

/// The summary table printed at the end of a run.
pub fn summary_text(r: &RunReport) -> String {
    let mut s = String::new();
    let profile = r.profile_spec.as_ref().map_or_else(|| r.profile.clone(), |p| p.label());
    s.push_str(&format!("gcl conform: target {}, profile {profile}, level {}\n", r.target, r.level));
    let given = r.options.pairs();
    if !given.is_empty() {
        let text: Vec<String> = given.iter().map(|(k, v)| format!("--{k} {v}")).collect();
        s.push_str(&format!("  options: {}\n", text.join("; ")));
    }
    if !r.groups.is_empty() {
        s.push_str("  root causes first (failures grouped by where they part from the golden, largest first):\n");
        for g in r.groups.iter().take(10) {
            s.push_str(&format!("    {}\n", g.summary));
            if let Some(d) = &g.diff {
                s.push_str(&format!("      {}\n", gcl_harness::report::diff::one_line(d)));
            }
        }
        if r.groups.len() > 10 {
            s.push_str(&format!("    ... and {} more groups\n", r.groups.len() - 10));
        }
    }
    let mut by_level: BTreeMap<Level, BTreeMap<Verdict, usize>> = BTreeMap::new();
    for c in &r.cases {
        let l = c.level.parse().unwrap_or(Level::Info);
        *by_level.entry(l).or_default().entry(c.verdict).or_default() += 1;
    }
    s.push_str(&format!("  {:<7}{:>6}", "level", "cases"));
    for v in Verdict::ALL {
        s.push_str(&format!("{:>8}", v.as_str()));
    }
    s.push('\n');
    let mut totals: BTreeMap<Verdict, usize> = BTreeMap::new();
    for (l, counts) in &by_level {
        let n: usize = counts.values().sum();
        s.push_str(&format!("  {:<7}{:>6}", l.as_str(), n));
        for v in Verdict::ALL {
            let k = counts.get(&v).copied().unwrap_or(0);
            *totals.entry(v).or_default() += k;
            s.push_str(&format!("{k:>8}"));
        }
        s.push('\n');
    }
    s.push_str(&format!("  {:<7}{:>6}", "total", r.cases.len()));
    for v in Verdict::ALL {
        s.push_str(&format!("{:>8}", totals.get(&v).copied().unwrap_or(0)));
    }
    s.push('\n');
    // A case at a level the run does not judge (certify's INFO) is out of its scope: a clause
    // is judged on its other cases, and one with only such cases is out of scope, not half
    // judged.
    let judged = LevelFilter::from_name(&r.level).unwrap_or(LevelFilter::All);
    let in_scope = |c: &CaseResult| c.level.parse::<Level>().map_or(true, |l| judged.admits(l));
    let (mut clean, mut failing, mut skipped, mut out_of_scope) = (0usize, 0usize, 0usize, 0usize);
    let mut levels_out: Vec<Level> = Vec::new();
    for cl in &r.clauses {
        let cases: Vec<&CaseResult> = cl.cases.iter().filter_map(|id| r.cases.iter().find(|c| &c.id == id)).collect();
        let scoped: Vec<&&CaseResult> = cases.iter().filter(|c| in_scope(c)).collect();
        if scoped.is_empty() && !cases.is_empty() {
            out_of_scope += 1;
            levels_out.extend(cases.iter().filter_map(|c| c.level.parse::<Level>().ok()));
        } else if scoped.iter().any(|c| c.verdict.fails_run()) {
            failing += 1;
        } else if scoped.iter().any(|c| matches!(c.verdict, Verdict::Skip | Verdict::Xfail)) {
            skipped += 1;
        } else {
            clean += 1;
        }
    }
    let covered = r.clauses.len();
    let blocked_clauses = r.clauses.iter().filter(|c| c.blocked).count();
    s.push_str(&format!(
        "  clauses: {covered} covered: {clean} with every case passing, {} failing, {blocked_clauses} blocked (failing only through another clause's bug), {skipped} not fully judged (a case skipped or a known failure)",
        failing.saturating_sub(blocked_clauses)
    ));
    if out_of_scope > 0 {
        levels_out.sort();
        levels_out.dedup();
        let names: Vec<&str> = levels_out.iter().map(|l| l.as_str()).collect();
        s.push_str(&format!(
            ", {out_of_scope} out of this run's scope (only {} cases, a level it does not judge)",
            names.join("/")
        ));
    }
    s.push('\n');
    let blocked = r.blocked();
    let failing: Vec<&CaseResult> =
        r.cases.iter().filter(|c| c.verdict.fails_run() && !blocked.contains(c.id.as_str())).collect();
    if !failing.is_empty() {
        s.push_str("  failing cases:\n");
        for c in failing.iter().take(50) {
            s.push_str(&format!("    {:<7} {} ({})\n", c.verdict.as_str(), c.id, c.message.as_deref().unwrap_or("")));
        }
        if failing.len() > 50 {
            s.push_str(&format!("    ... and {} more\n", failing.len() - 50));
        }
    }
    if !blocked.is_empty() {
        s.push_str(&format!(
            "  blocked cases ({}; each fails on another clause's bug, named by its group):\n",
            blocked.len()
        ));
        for g in r.groups.iter().filter(|g| !g.blocked.is_empty()) {
            let ids: Vec<&str> = g.blocked.iter().take(8).map(String::as_str).collect();
            let more = if g.blocked.len() > 8 { format!(" and {} more", g.blocked.len() - 8) } else { String::new() };
            s.push_str(&format!("    by `{}`: {}{more}\n", g.clause, ids.join(", ")));
        }
    }
    if let Some(st) = &r.stopped {
        // The reason was said on stderr as it happened; the summary says where.
        s.push_str(&format!("  ended early at case {} (the cases after it were not run)\n", st.case));
    }
    if !r.liveness.after {
        s.push_str("  the hand did not answer the liveness probe after the suite\n");
    }
    s.push_str(&format!("  time: {:.3} s\n", r.duration_ms / 1000.0));
    if let Some(w) = r.wire.as_ref().filter(|w| w.refuted()) {
        s.push_str(&format!("  {}\n", w.refuted_text()));
    } else if let Some(w) = &r.wire {
        s.push_str(&format!(
            "  wire-time lower bound: {:.3} s over the {} PASS/FAIL cases (step after step, the larger of the bytes \
received at {} baud, full duplex, and the model's motion time; {} bytes sent, {} received, {:.3} s of motion and \
pauses) and the pre-flight and motion-time probe before them ({:.3} s by the same rule); the whole run, probes \
included, took {:.3} s; ratio {:.3}\n",
            w.lower_bound_ms / 1000.0,
            w.counted_cases,
            w.baud,
            w.bytes_sent,
            w.bytes_received,
            w.motion_ms / 1000.0,
            w.probes_ms / 1000.0,
            w.actual_ms / 1000.0,
            w.ratio
        ));
    }
    if r.ran() == 0 {
        s.push_str("  no case ran\n");
    }
    // The one verdict line every output of the run shows (PARTIAL when cases did not run or
    // known failures were excused; ERROR when the hand stopped answering or vanished).
    s.push_str(&format!("  result: {}\n", r.outcome().verdict));
    s
}

/// A known-failures file (the `--known-failures` format) listing every case of `report` that
/// failed, timed out, errored or was a known failure, by exact id and profile, with its
/// message as the reason; and how many it lists.
fn known_failures_text(report: &RunReport) -> (String, usize) {
    let q = |s: &str| toml::Value::String(s.to_string()).to_string();
    let mut text = format!(
        "# Known failures of {} (profile {}), written by `gcl conform --write-known-failures` on {}.\n\
         # Pass it as --known-failures: these cases are XFAIL, and one that passes again is XPASS.\n",
        report.target, report.profile, report.started
    );
    let mut n = 0;
    for c in &report.cases {
        if !matches!(c.verdict, Verdict::Fail | Verdict::Timeout | Verdict::Error | Verdict::Xfail) {
            continue;
        }
        let why = c.message.as_deref().and_then(|m| m.lines().next()).unwrap_or("failed");
        let why = why.strip_prefix("known failure: ").unwrap_or(why);
        text.push_str(&format!(
            "\n[[failure]]\ncase = {}\nprofile = {}\nreason = {}\n",
            q(&c.id),
            q(&report.profile),
            q(&format!("{}: {why}", if c.verdict == Verdict::Xfail { "FAIL" } else { c.verdict.as_str() }))
        ));
        if let Some(how) = &c.failure {
            text.push_str(&format!("how = {}\n", q(how)));
        }
        n += 1;
    }
    (text, n)
}

/// Runs `gcl conform`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let (opts, cases) = prepare(&args.suite, args.level.into(), false)?;
    // Held until the reports are written: a second run on the same folder is refused.
    let _held =
        args.report.as_deref().map(|d| gcl_harness::outputs::OutLock::acquire(d, "conform --report")).transpose()?;
    let mut out = run_with_progress(&opts, &cases, args.report.as_deref(), args.quiet, "gcl conform")?;
    record_options(&mut out.report, &args.suite, &opts.profile);
    let mut w = super::stdio::out();
    write!(w, "{}", printable(&summary_text(&out.report)))?;
    if let Some(dir) = &args.report {
        let files = write_all(dir, &out.report)?;
        for f in files {
            writeln!(w, "  wrote {}", f.display())?;
        }
    }
    if let Some(path) = &args.write_known_failures {
        let (text, n) = known_failures_text(&out.report);
        gcl_harness::outputs::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        writeln!(w, "  wrote {} ({n} known failure{})", path.display(), if n == 1 { "" } else { "s" })?;
    }
    if let Some(st) = &out.report.stopped
        && st.cause != StopCause::MaxFailures
    {
        return Ok(EXIT_ERROR);
    }
    Ok(if out.report.passed() { EXIT_OK } else { EXIT_FAIL })
}
