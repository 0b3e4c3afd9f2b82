//! `gcl conform`: the conformance suite against a hand, with a verdict per case and per
//! clause, reports CI systems read, and exit codes that mean something.

use std::collections::BTreeMap;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use gcl_model::Fault;

use super::{EXIT_FAIL, EXIT_OK, load_profile};
use crate::conform::{self, ConformOptions, KnownFailures, LevelFilter, RunOutput};
use crate::report::{CaseResult, ResultStream, RunReport, Verdict, write_all};
use crate::suite::{self, Case};
use crate::target::{OpenOptions, Target};
use crate::transcript::{Level, Requirement};

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
    /// Per-step deadline in milliseconds for steps that do not set their own.
    #[arg(long, value_name = "MS")]
    pub timeout: Option<u64>,
    /// Refuse cases that need this of the hand (motion, realtime, eeprom, abort-timing;
    /// repeatable): they are reported as SKIP.
    #[arg(long = "no", value_name = "REQUIREMENT")]
    pub refuse: Vec<String>,
    /// Run the committed golden transcripts in DIR (e.g. vectors/suite) instead of the suite
    /// the built-in model generates (they are the same when the goldens are fresh).
    #[arg(long, value_name = "DIR")]
    pub suite: Option<PathBuf>,
    /// The line rate the hand runs at, for the wire-time lower bound (serial targets give
    /// their own with ?baud=N).
    #[arg(long)]
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
#[command(after_help = "Exit codes: 0 every case passed (SKIP and XFAIL allowed); 1 a case failed, timed out, \
errored or passed while listed as a known failure; 2 usage or infrastructure error (including a hand that \
does not answer the liveness probe).\n\nExamples:\n  gcl conform --target sim\n  gcl conform --target \
sim:seed --level must --report reports/out\n  gcl conform --target serial:/dev/ttyUSB0?baud=9600 --profile \
bh8-262-4.3 --known-failures known.toml")]
pub struct Args {
    /// The hand and the suite.
    #[command(flatten)]
    pub suite: SuiteArgs,
    /// Levels to run: must (MUST), should (MUST and SHOULD), all (also MAY and INFO).
    #[arg(long, value_enum, default_value_t = LevelFilter::All)]
    pub level: LevelFilter,
    /// Write report.json, junit.xml, report.html (and results.jsonl as cases end) into DIR.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Print only the summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The suite, options and cases a run needs, from the shared arguments.
pub fn prepare(
    a: &SuiteArgs,
    level: LevelFilter,
    keep_transcripts: bool,
) -> anyhow::Result<(ConformOptions, Vec<Case>)> {
    let profile_name = a
        .profile
        .clone()
        .or_else(|| a.target.sim_profile(None).map(str::to_string))
        .unwrap_or_else(|| crate::target::DEFAULT_SIM_PROFILE.to_string());
    let profile = load_profile(&profile_name)?;
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
    let mut known = match &a.known_failures {
        Some(p) => KnownFailures::load(p)?,
        None => KnownFailures::default(),
    };
    for id in &a.skip_decision {
        known.skip_decision(id, "--skip-decision");
    }
    let refuse = a
        .refuse
        .iter()
        .map(|r| match Requirement::from_slug(r) {
            Some(Requirement::Other(s)) => {
                anyhow::bail!("unknown requirement `{s}` (motion, realtime, eeprom, abort-timing)")
            }
            Some(r) => Ok(r),
            None => anyhow::bail!("bad requirement `{r}`"),
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let open =
        OpenOptions { profile: Some(profile.id.clone()), seed: a.seed, faults: a.fault.clone(), ..Default::default() };
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
        baud: a.baud,
        keep_transcripts,
    };
    Ok((opts, cases))
}

/// Runs the suite with a progress bar on a terminal, or a line per problem otherwise.
pub fn run_with_progress(
    opts: &ConformOptions,
    cases: &[Case],
    report_dir: Option<&std::path::Path>,
    quiet: bool,
) -> anyhow::Result<RunOutput> {
    let mut stream = match report_dir {
        Some(d) => Some(ResultStream::create(d).with_context(|| format!("creating {}", d.display()))?),
        None => None,
    };
    let tty = std::io::stderr().is_terminal();
    let bar = if tty && !quiet {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template("{spinner} [{bar:30}] {pos}/{len} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        Some(b)
    } else {
        None
    };
    let mut progress = |r: &CaseResult, done: usize, total: usize| {
        if let Some(b) = &bar {
            b.set_length(total as u64);
            b.set_position(done as u64);
            b.set_message(r.id.clone());
            if r.verdict.fails_run() {
                b.println(format!("{:<7} {}: {}", r.verdict, r.id, r.message.as_deref().unwrap_or("")));
            }
        } else if !quiet && r.verdict.fails_run() {
            eprintln!("{:<7} {}: {}", r.verdict, r.id, r.message.as_deref().unwrap_or(""));
        }
    };
    let out = conform::run(cases, opts, stream.as_mut(), &mut progress)?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    Ok(out)
}

/// The summary table printed at the end of a run.
pub fn summary_text(r: &RunReport) -> String {
    let mut s = String::new();
    s.push_str(&format!("gcl conform: target {}, profile {}, level {}\n", r.target, r.profile, r.level));
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
    let covered = r.clauses.len();
    let clean = r.clauses.iter().filter(|c| matches!(c.verdict, Verdict::Pass)).count();
    s.push_str(&format!("  clauses: {covered} covered, {clean} with every case passing\n"));
    let failing: Vec<&CaseResult> = r.cases.iter().filter(|c| c.verdict.fails_run()).collect();
    if !failing.is_empty() {
        s.push_str("  failing cases:\n");
        for c in failing.iter().take(50) {
            s.push_str(&format!("    {:<7} {} ({})\n", c.verdict.as_str(), c.id, c.message.as_deref().unwrap_or("")));
        }
        if failing.len() > 50 {
            s.push_str(&format!("    ... and {} more\n", failing.len() - 50));
        }
    }
    if !r.liveness.after {
        s.push_str("  the hand did not answer the liveness probe after the suite\n");
    }
    s.push_str(&format!("  time: {:.3} s\n", r.duration_ms / 1000.0));
    if let Some(w) = &r.wire {
        s.push_str(&format!(
            "  wire-time lower bound: {:.3} s ({} bytes sent, {} received at {} baud, {:.3} s of motion); took {:.3} s; ratio {:.3}\n",
            w.lower_bound_ms / 1000.0,
            w.bytes_sent,
            w.bytes_received,
            w.baud,
            w.motion_ms / 1000.0,
            w.actual_ms / 1000.0,
            w.ratio
        ));
    }
    s.push_str(&format!("  result: {}\n", if r.passed() { "PASS" } else { "FAIL" }));
    s
}

/// Runs `gcl conform`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let (opts, cases) = prepare(&args.suite, args.level, false)?;
    let out = run_with_progress(&opts, &cases, args.report.as_deref(), args.quiet)?;
    let mut w = std::io::stdout().lock();
    write!(w, "{}", summary_text(&out.report))?;
    if let Some(dir) = &args.report {
        let files = write_all(dir, &out.report)?;
        for f in files {
            writeln!(w, "  wrote {}", f.display())?;
        }
    }
    Ok(if out.report.passed() { EXIT_OK } else { EXIT_FAIL })
}
