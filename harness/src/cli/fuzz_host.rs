//! `gcl fuzz host`: the adversarial hand for host libraries (library code in
//! `gcl_harness::fuzz::host`). Also owns the arguments `gcl check-host` shares.

use super::stdio::errln;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::Context;
use gcl_harness::fuzz::host::bundle::{self, BundleInfo};
use gcl_harness::fuzz::host::corpus;
use gcl_harness::fuzz::host::coverage::CoverageUse;
use gcl_harness::fuzz::host::{
    CALIBRATION_SHARE, Calibration, Campaign, DEFAULT_DURATION, Event, Finding, FindingKind, FuzzOptions, HostRun,
    Transport, Weights, judge, run_once,
};
use gcl_harness::report::{CaseResult, HostDetails, HostFinding, RunReport, StopCause, Stopped, Verdict};
use gcl_harness::sim::misbehave::Operator;
use gcl_harness::sim::{Pace, TimeMode};
use gcl_model::escape::printable;

use super::{EXIT_ERROR, EXIT_FAIL, EXIT_OK, load_profile};

fn duration(s: &str) -> Result<Duration, String> {
    super::duration(s)
}

/// What `gcl fuzz host` and `gcl check-host` share: the line, the hand, the host.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("line").args(["pty", "tcp"])))]
pub struct HostArgs {
    /// The host opens a pseudo-terminal (the default); `{port}` is its path.
    #[arg(long)]
    pty: bool,
    /// The host connects to a loopback TCP port; `{port}` is 127.0.0.1:N, `{url}` socket://127.0.0.1:N.
    #[arg(long)]
    tcp: bool,
    /// Profile of the simulated hand: seed, bh8-262-4.3, bh8-262-4.4 (alias bh8-262), or a spec TOML file.
    #[arg(long, default_value = "bh8-262")]
    profile: String,
    /// fast: simulated time follows the bytes, motion completes at once (default); real: the wall clock.
    #[arg(long, value_enum, default_value = "fast")]
    time: super::sim::TimeArg,
    /// Pace both directions at this rate; default: unpaced in fast time, the hand's BAUD in real time.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(50..=4_000_000))]
    baud: Option<u32>,
    /// A hang: the host neither sends nor exits for this long after the hand's last answer.
    /// Default for `fuzz host`: measured (the host's longest give-up time when the hand goes
    /// silent at each kind of answer, twice as long plus 2 s, at least 3 s), and confirmed by a
    /// second run that waits up to --run-budget; for `check-host`, whose hand never goes
    /// silent: 20 s (above the 5 to 15 s timeouts of real host libraries).
    #[arg(long, value_name = "D", value_parser = duration)]
    timeout_hang: Option<Duration>,
    /// A hang too: one run taking longer than this.
    #[arg(long, value_name = "D", default_value = "60s", value_parser = duration)]
    run_budget: Duration,
    /// Exit codes of the host that are no finding (a host that reports a broken hand and
    /// exits 1 is doing its job).
    #[arg(long, value_name = "LIST", default_value = "0,1", value_delimiter = ',', allow_hyphen_values = true,
          value_parser = clap::value_parser!(i32).range(0..=255))]
    ok_exit_codes: Vec<i32>,
    /// Write report.json, junit.xml and report.html into DIR (fuzz host adds fuzz.json: schema
    /// reports/fuzz-host.schema.json).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// The host program and its arguments (after --); `{port}`/`{url}` in them, or GCL_PORT
    /// and GCL_PORT_URL in its environment, name the port.
    #[arg(last = true, required = true, value_name = "COMMAND")]
    command: Vec<String>,
}

impl HostArgs {
    /// The run these arguments describe, with the hand's noise seed; `default_hang` when
    /// `--timeout-hang` is not given.
    pub fn host_run(&self, hand_seed: u64, default_hang: Duration) -> anyhow::Result<HostRun> {
        let profile = load_profile(&self.profile)?;
        let time = TimeMode::from(self.time);
        Ok(HostRun {
            command: self.command.clone(),
            transport: if self.tcp { Transport::Tcp } else { Transport::Pty },
            profile,
            time,
            pace: self.pace(time),
            hand_seed,
            timeout_hang: self.timeout_hang.unwrap_or(default_hang),
            budget: self.run_budget,
            link: None,
            coverage: Default::default(),
            env: Vec::new(),
        })
    }

    /// `--baud`, else unpaced in fast time and the hand's BAUD in real time.
    fn pace(&self, time: TimeMode) -> Pace {
        match (self.baud, time) {
            (Some(b), _) => Pace::Fixed(b),
            (None, TimeMode::Fast) => Pace::Unpaced,
            (None, TimeMode::Real) => Pace::Hand,
        }
    }

    /// Exit codes that pass.
    pub fn ok_exit_codes(&self) -> Vec<i32> {
        self.ok_exit_codes.clone()
    }

    /// Where reports go.
    pub fn report_dir(&self) -> Option<&std::path::Path> {
        self.report.as_deref()
    }

    /// Whether `--timeout-hang` was given.
    pub fn timeout_hang_given(&self) -> bool {
        self.timeout_hang.is_some()
    }
}

/// The hand a host run meets, as a report's facts: the line, the time mode and the pace (the
/// pace is what `--time` and `--baud` made of it, so a reader sees an unpaced line as one).
pub(super) fn hand_facts(run: &HostRun) -> Vec<(String, String)> {
    vec![
        ("line".into(), if run.transport == Transport::Tcp { "tcp" } else { "pty" }.into()),
        ("time".into(), run.time.name().to_string()),
        ("pace".into(), run.pace.to_string()),
    ]
}

/// The least hang timeout of `gcl fuzz host` (calibration raises it to the host's own).
pub const FUZZ_HANG_FLOOR: Duration = Duration::from_secs(3);

fn after_help() -> String {
    let ops: Vec<String> = Operator::ALL
        .iter()
        .map(|o| format!("  {:<16} {:>2}  {}", o.name(), o.default_weight(), o.description()))
        .collect();
    format!(
        "\
Each run starts a fresh simulated hand on a fresh pty (or TCP port), runs COMMAND to its end,
and judges it: a crash (death by signal; an AddressSanitizer report, Rust panic or Python
traceback on stderr), a hang (--timeout-hang of silence after the hand's last answer, or
--run-budget: a host still sending then never exited either), an exit code outside --ok-exit-codes, a process left behind holding the port
or stderr, or a protocol violation (the clauses of `gcl check-host`).

Before the campaign (unless --timeout-hang is given) the host's own give-up time is
measured at every kind of answer: the hand goes silent at the first answer of each kind (the
prompt after ^C, an answer with values, the banner after RESET, a RealTime block...), and the
time the host takes to send or exit there is its timeout; this takes at most a quarter of
--duration. A hang is then silence for twice the longest plus 2 s (at least 3 s, at most
--run-budget), and it is confirmed before it is reported: its schedule runs again, waiting as
long as --run-budget allows, and a host that acts late is an INFO note (late, not hung), not a
finding; a host that waits past the hang timeout while calibration measures has its hang found
there. A hang's signature is the innermost frame of the host's own code where it waits
(faulthandler for Python hosts, eu-stack or gdb for native ones when installed; the frames of
libc, libstdc++, Boost... it waits in go in the message), else its protocol state. How the host reacts to the hand's own misbehaviour is a finding only when it
is unsafe (a crash, a hang, an exit code, sending before an answer the hand sent whole);
otherwise it is an INFO note in the report. A host may say what it believes with
`gcl-observe: NAME MOTOR VALUE [WHERE]` lines on stderr or on the descriptor GCL_OBSERVE_FD
names (WHERE: the host's code that formed the belief; `gcl-observe: error TEXT` when it saw
the hand misbehave): a value the hand never sent, before such an error, is a
silent-wrong-value finding, named by WHERE or else by the answer it came from. Run 0 has no
misbehaviour. Then a systematic pass puts every misbehaviour at every kind of answer run 0
showed (echo and values, prompt only, banner, feedback block...), one per run, the first
round trying each misbehaviour once; an unpaced campaign opens it with one run at the hand's
line rate (line-rate). Later runs follow a schedule drawn from --seed, or a mutation of a
schedule that made the host take a new path, or (--coverage) reach code of the host no run
before it reached: a host built with afl-cc/afl-clang-fast, python-afl or cargo-afl, or a Python
host run as `python -m gcl.afl_cov host.py ARGS`, writes its edges to the AFL map each run is
given (__AFL_SHM_ID). Each distinct finding is minimized (keeping the edges its run reached
first, with coverage) and written
to --out as a bundle; --replay BUNDLE runs it again. Without --runs or --duration a campaign
lasts 5 minutes.

Misbehaviours (--ops NAME[,NAME=WEIGHT...]; default weight shown):
{}

Exit codes: 0 no finding, in runs that reached the host (the reports say how many: runs in
which it opened the port and sent the hand a byte); 1 findings; 2 nothing tested or no verdict:
the host never opened the port, or opened it and sent nothing, in the run without misbehaviour
(the campaign ends there, naming the command, how it ended and the last lines of its stderr),
the budget ran out before the first run, or a signal (SIGINT, SIGTERM, SIGHUP) stopped the
campaign without a finding (every report says `stopped by SIGTERM after N of M runs`); also a
usage or infrastructure error. --runs 0 is refused.

Examples:
  gcl fuzz host --duration 5m --report reports/host -- python3 my_host.py {{port}}
  gcl fuzz host --ops delay-above,truncate --runs 200 -- ./host_c --port {{port}}
  gcl fuzz host --replay fuzz-host-findings/hang-1a2b3c4d -- python3 my_host.py {{port}}",
        ops.join("\n")
    )
}

/// Arguments of `gcl fuzz host`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = after_help())]
pub struct Args {
    #[command(flatten)]
    host: HostArgs,
    /// Seed of the schedules (and of the hand's noise).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Stop after N runs, at least 1 (without --runs or --duration: a 5-minute campaign).
    #[arg(long, value_name = "N", conflicts_with = "duration", value_parser = clap::value_parser!(u64).range(1..))]
    runs: Option<u64>,
    /// Stop after this long (30s, 5m; default 5m unless --runs is given).
    #[arg(long, value_name = "D", value_parser = duration)]
    duration: Option<Duration>,
    /// Where bundles go.
    #[arg(long, value_name = "DIR", default_value = "fuzz-host-findings")]
    out: PathBuf,
    /// Run a bundle's schedule once and say whether its finding comes back.
    #[arg(long, value_name = "BUNDLE", conflicts_with_all = ["runs", "duration"])]
    replay: Option<PathBuf>,
    /// At most N hosts alive at once, each with its own hand on its own line: the runs,
    /// calibration, minimization and hangs' confirmations all take one of N slots. The
    /// schedules are the same for
    /// the same --seed and --jobs: run i's guidance sees run 0 and runs 0..=i-N in order (a
    /// worker waits for a slow one; the systematic pass, made of run 0, starts at run 1), so with a host that answers the same bytes the same way, the findings,
    /// their first run and minimized schedules come back run for run. Wall times do not, nor
    /// how many runs a --duration makes.
    ///
    /// Default 4: hosts mostly wait (for answers, for their timeouts), so four at once use the
    /// cores a one-job campaign leaves idle (a pyserial host with 1 s timeouts: 80 runs in
    /// 42 s at --jobs 1, 17 s at 4; a C host with 15 s timeouts: 31 runs in 2 min at 1, 57 and
    /// the whole systematic pass at 4).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=64))]
    jobs: u64,
    /// Give each slot's host a symbolic link to its pty as {port}, made at PATTERN with {slot}
    /// (1 to --jobs) replaced, before its run and removed after it: for a host that opens only a
    /// fixed device path (--link '/dev/ttyUSB{slot}'). A link never serves two live hosts; a run
    /// whose port a process of another run opened is void, made again, never a finding.
    #[arg(long, value_name = "PATTERN")]
    link: Option<String>,
    /// Only these misbehaviours, optionally weighted: delay-above,truncate=5.
    #[arg(long, value_name = "LIST", value_parser = Weights::parse)]
    ops: Option<Weights>,
    /// Most misbehaviours in a fresh schedule.
    #[arg(long, value_name = "N", default_value_t = 3)]
    max_misbehaviours: usize,
    /// Keep each finding's schedule as found.
    #[arg(long)]
    no_minimize: bool,
    /// Every schedule fresh from the seed: no mutation of the runs that took a new path.
    #[arg(long)]
    no_guidance: bool,
    /// The host's code coverage: guide (the default), measure or off. Each run gives the host
    /// an AFL map (__AFL_SHM_ID): a host built with afl-cc/afl-clang-fast, python-afl
    /// (afl.init()), `python -m gcl.afl_cov host.py` or cargo-afl writes the edges it reaches
    /// there. With guide, a schedule whose
    /// run reached a new edge is kept beside those that took a new wire path, and mutated (a
    /// power schedule favours those reaching rare edges); measure reports the edges reached but
    /// guides by wire paths only (the runs of off, to compare). A host that writes no edge gets
    /// a note, and wire paths alone guide it. Shards (--shard) run unguided: they read it only
    /// with --corpus (as measure), to keep the schedules that reached new edges.
    #[arg(long, value_name = "MODE", default_value = "guide", conflicts_with = "no_coverage")]
    coverage: CoverageUse,
    /// --coverage off.
    #[arg(long)]
    no_coverage: bool,
    /// A corpus folder kept across campaigns: its schedules (JSON, named by a hash of their
    /// content) run right after the systematic pass, and the schedules this campaign keeps (for
    /// a new wire path or a new edge) are added to it, with the edges their runs reached. A
    /// shard runs its share of the folder's schedules as read at its start and writes what it
    /// kept to DIR/incoming; `gcl fuzz merge-corpus DIR` folds those in, keeping only
    /// schedules that add edges.
    #[arg(long, value_name = "DIR")]
    corpus: Option<PathBuf>,
    /// Run only shard K of N of the campaign (run indices K-1, K-1+N, ...; unguided), for a
    /// CI matrix; `gcl fuzz merge` folds the shards' --report and --out folders into one
    /// (fuzz.json records the shard, the seed and every option that changed what ran).
    #[arg(long, value_name = "K/N")]
    shard: Option<gcl_harness::fuzz::shard::Shard>,
}

/// Runs `gcl fuzz host`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let mut run = args.host.host_run(args.seed, FUZZ_HANG_FLOOR)?;
    run.link = link_pattern(&args, &run)?;
    // A shard runs unguided: coverage would guide nothing there, but with a corpus it tells
    // which schedules reached new edges (read as `measure`: the same runs).
    run.coverage = match (args.no_coverage, args.shard.is_some(), args.corpus.is_some()) {
        (true, _, _) => CoverageUse::Off,
        (false, false, _) => args.coverage,
        (false, true, true) if args.coverage != CoverageUse::Off => CoverageUse::Measure,
        (false, true, _) => CoverageUse::Off,
    };
    if let Some(b) = &args.replay {
        return replay(&args, run, b);
    }
    refuse_empty_shard(args.runs, args.shard)?;
    let opts = host_options(&args, run);
    print_header(&args, &opts);
    let _held = hold_folders(&args)?;
    let stop = stop_on_signals()?;
    let campaign = run_campaign(&args, &opts, &stop)?;
    let unwritten = rewrite_bundles(&args.out, &opts, &campaign);
    print_campaign_summary(&campaign);
    write_campaign_report(&args, &opts, &campaign)?;
    if let Some(e) = unwritten {
        return Err(e.into());
    }
    let code = host_exit(&opts, &campaign);
    // The verdict in the words every report of it uses.
    errln!("result: {}", campaign_report(&opts, &campaign, &args.out, args.ops.is_some()).verdict_line());
    Ok(code)
}

/// `--link PATTERN` as the runs' link: over a pty only; without `{slot}` only at `--jobs 1`
/// (two slots would share one link); its folder must exist. A replay, one run, takes slot 1.
fn link_pattern(args: &Args, run: &HostRun) -> anyhow::Result<Option<PathBuf>> {
    let Some(p) = &args.link else { return Ok(None) };
    if run.transport != Transport::Pty {
        anyhow::bail!("--link makes a link to a pty: it cannot go with --tcp");
    }
    if !p.contains("{slot}") && args.jobs > 1 {
        anyhow::bail!(
            "--link {p}: without {{slot}} the {} slots of --jobs {} would share one link; put {{slot}} in it (/dev/ttyUSB{{slot}})",
            args.jobs,
            args.jobs
        );
    }
    let first = PathBuf::from(p.replace("{slot}", "1"));
    let dir = first.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    if !dir.is_dir() {
        anyhow::bail!("--link {p}: no folder {} to make the link in", dir.display());
    }
    Ok(Some(PathBuf::from(p)))
}

/// The campaign's options from the arguments, around the host's run.
fn host_options(args: &Args, run: HostRun) -> FuzzOptions {
    FuzzOptions {
        run,
        seed: args.seed,
        runs: args.runs,
        duration: args.duration,
        ok_exit_codes: args.host.ok_exit_codes(),
        jobs: args.jobs as usize,
        weights: args.ops.clone().unwrap_or_default(),
        max_planned: args.max_misbehaviours.max(1),
        minimize: !args.no_minimize,
        guided: !args.no_guidance,
        calibrate: !args.host.timeout_hang_given(),
        shard: args.shard,
    }
}

/// The campaign's first line: seed, profile, line, time, pace, jobs, where bundles go.
fn print_header(args: &Args, opts: &FuzzOptions) {
    errln!(
        "gcl fuzz host: seed {}, profile {}, {} line, time {}, {}, {} job(s), bundles in {}",
        opts.seed,
        printable(&opts.run.profile.id),
        if opts.run.transport == Transport::Tcp { "tcp" } else { "pty" },
        opts.run.time.name(),
        opts.run.pace.phrase(),
        opts.jobs,
        args.out.display()
    );
}

/// The `--out` and `--report` folders, held for the campaign: a second campaign on the same
/// folders is refused (issue 20).
fn hold_folders(args: &Args) -> anyhow::Result<Vec<gcl_harness::outputs::OutLock>> {
    let mut held = vec![gcl_harness::outputs::OutLock::acquire(&args.out, "fuzz host --out")?];
    if let Some(d) = args.host.report_dir().filter(|d| *d != args.out.as_path()) {
        held.push(gcl_harness::outputs::OutLock::acquire(d, "fuzz host --report")?);
    }
    // Let go last held first: a parent the first lock made for both goes once both are empty.
    held.reverse();
    Ok(held)
}

/// Runs the campaign with its progress line (calibration and findings said as they come,
/// each finding's bundle written): the campaign, with its provenance and how a signal
/// stopped it.
fn run_campaign(args: &Args, opts: &FuzzOptions, stop: &AtomicBool) -> anyhow::Result<Campaign> {
    let out = args.out.clone();
    let info_of = |f: &Finding| info(opts, f);
    if opts.runs.is_none() && opts.duration.is_none() {
        errln!("{}", default_budget_line());
    }
    let total = match (opts.runs, opts.duration) {
        (Some(n), _) => super::progress::Total::Units(n),
        (None, Some(d)) => super::progress::Total::Time(d),
        (None, None) => super::progress::Total::Time(DEFAULT_DURATION),
    };
    let progress = super::progress::Progress::new("gcl fuzz host", "runs", "findings", total, false);
    let done = std::sync::atomic::AtomicU64::new(0);
    let found = std::sync::atomic::AtomicU64::new(0);
    let on_event = |e: Event| {
        match e {
        // Said as soon as measured: the hang timeout the runs use, and what was left unmeasured.
        // (A run that did not reach the host is said once, as what ended the campaign.)
        Event::Calibrated(c) if c.untested.is_some() => {}
        Event::Calibrated(c) => {
            for line in calibration_lines(&c) {
                progress.println(&line);
            }
        }
        // A confirmation may wait a whole run budget: said before it waits.
        Event::Confirming { signature, state, wait } => progress.println(&format!(
            "  confirming {signature} ({state}): its schedule runs again, waiting up to {} for the host to act (--run-budget)",
            secs(wait.as_millis() as u64)
        )),
        Event::Run { .. } => {
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.update(n, found.load(Ordering::Relaxed), "");
        }
        Event::Found(f) => {
            // Counted at once: a finding is told after its run, and the last line must count it.
            let n = found.fetch_add(1, Ordering::Relaxed) + 1;
            progress.update(done.load(Ordering::Relaxed), n, "");
            let dir = bundle::write(&out, &info_of(&f), &f);
            let where_ = match &dir {
                Ok(d) => d.display().to_string(),
                Err(e) => format!("bundle not written: {e}"),
            };
            // The signature begins with the kind (`crash: ...`), so it is not repeated.
            progress.println(&format!(
                "  finding: {} ({}, {:.1} s, {} misbehaviour(s)) -> {}",
                f.verdict.signature,
                if f.by_calibration { "calibration".to_string() } else { format!("run {}", f.run) },
                f.found_after_ms as f64 / 1000.0,
                f.schedule.planned.len(),
                where_
            ));
        }
    }
    };
    let seeds = match &args.corpus {
        Some(dir) => {
            let (seeds, bad) = corpus::load(dir).with_context(|| format!("reading the corpus {}", dir.display()))?;
            for (p, why) in &bad {
                errln!("gcl fuzz host: warning: {}", printable(&format!("corpus file {} skipped: {why}", p.display())));
            }
            errln!(
                "gcl fuzz host: {} schedule(s) from the corpus {}, run after the systematic pass",
                seeds.len(),
                dir.display()
            );
            seeds
        }
        None => Vec::new(),
    };
    // What a shard's provenance records of the base it ran: shards of two bases do not merge.
    let base = (!seeds.is_empty()).then(|| format!("{} schedule(s), {}", seeds.len(), corpus::digest(&seeds)));
    let mut campaign = gcl_harness::fuzz::host::fuzz_seeded(opts, seeds, stop, &on_event).context("fuzzing")?;
    if let Some(dir) = &args.corpus {
        // A shard writes beside the base, which every shard of the campaign reads at its start.
        let to = if opts.shard.is_some() { dir.join(corpus::INCOMING) } else { dir.clone() };
        let new = corpus::save(&to, &campaign.kept).with_context(|| format!("writing the corpus {}", to.display()))?;
        errln!("gcl fuzz host: corpus {}: {new} new schedule(s) of the {} kept", to.display(), campaign.kept.len());
    }
    campaign.provenance = Some(provenance(args, opts, base));
    progress.finish();
    campaign.stopped = super::stopped_by().map(|by| stopped_after(&by, opts, &campaign));
    if let Some(st) = &campaign.stopped {
        errln!("gcl fuzz host: {st}; the report covers the runs made");
    }
    Ok(campaign)
}

/// Once more with the final hit counts. A bundle that cannot be written (a full disk) is an
/// infrastructure error: said here, and the first one given back (the run exits 2 naming it).
fn rewrite_bundles(out: &std::path::Path, opts: &FuzzOptions, campaign: &Campaign) -> Option<bundle::BundleError> {
    // A bundle not written is marked incomplete.
    let mut unwritten = None;
    for f in &campaign.findings {
        if let Err(e) = bundle::write(out, &info(opts, f), f) {
            errln!("gcl fuzz host: bundle not written: {e}");
            unwritten.get_or_insert(e);
        }
    }
    unwritten
}

/// The campaign's figures, its systematic pass, notes and misbehaviours fired, on stderr.
fn print_campaign_summary(campaign: &Campaign) {
    let secs = campaign.elapsed_ms as f64 / 1000.0;
    errln!(
        "gcl fuzz host: {} runs ({} reached the host; +{} to minimize) in {:.1} s ({:.1} runs/s), {} distinct finding(s), {} paths, {} schedules kept",
        campaign.runs,
        campaign.reached,
        campaign.minimize_runs,
        secs,
        campaign.runs as f64 / secs.max(1e-3),
        campaign.findings.len(),
        campaign.paths,
        campaign.corpus
    );
    if let Some(line) = campaign.pass_line() {
        errln!("{}", printable(&line));
    }
    if let Some(c) = &campaign.coverage {
        errln!("{}", printable(&c.line()));
    }
    if campaign.void_runs > 0 {
        errln!(
            "warning: {} run(s) void, made again and never judged: processes of two runs held one port ({}); \
             one host at a time from the first; a host that opens a fixed device path needs --link with {{slot}}",
            campaign.void_runs,
            printable(&campaign.void.join("; "))
        );
    }
    if !campaign.notes.is_empty() {
        errln!("notes (the host's reaction to the hand's misbehaviour, no finding):");
        for (n, runs) in &campaign.notes {
            errln!("  {} (x{runs})", printable(n));
        }
    }
    if !campaign.fired_at.is_empty() {
        errln!("misbehaviours fired, by protocol state:");
        for (op, states) in &campaign.fired_at {
            let list: Vec<String> = states.iter().map(|(s, n)| format!("{} x{n}", printable(s))).collect();
            errln!("  {op:<16} {}", list.join(", "));
        }
    }
}

/// With `--report`: the report pages and fuzz.json.
fn write_campaign_report(args: &Args, opts: &FuzzOptions, campaign: &Campaign) -> anyhow::Result<()> {
    if let Some(dir) = args.host.report_dir() {
        let report = campaign_report(opts, campaign, &args.out, args.ops.is_some());
        for p in gcl_harness::report::write_all(dir, &report)? {
            errln!("wrote {}", p.display());
        }
        // Sealed, so that a merge takes this folder only as written.
        let mut campaign = campaign.clone();
        gcl_harness::fuzz::merge::seal_host(&mut campaign, dir, &args.out)?;
        let p = dir.join("fuzz.json");
        gcl_harness::report::write_atomic(&p, &serde_json::to_vec_pretty(&campaign)?)?;
        errln!("wrote {}", p.display());
    }
    Ok(())
}

/// The exit code: untested is an error; a finding fails; stopped early without one, no
/// verdict (with the default budget's line again when it ran out).
fn host_exit(opts: &FuzzOptions, campaign: &Campaign) -> u8 {
    if let Some(why) = &campaign.untested {
        errln!("gcl fuzz host: nothing tested: {why}");
        return EXIT_ERROR;
    }
    if opts.runs.is_none() && opts.duration.is_none() && campaign.stopped.is_none() {
        errln!("{}", default_budget_line());
    }
    match (campaign.findings.is_empty(), &campaign.stopped) {
        (false, _) => EXIT_FAIL,
        // Stopped before its budget with no finding: no verdict on the host.
        (true, Some(_)) => EXIT_ERROR,
        (true, None) => EXIT_OK,
    }
}

/// `stopped by SIGTERM after 3 of 1000 runs` (or `after 3 runs, 4.2 s of 5m`).
fn stopped_after(by: &str, opts: &FuzzOptions, c: &Campaign) -> String {
    let of = match (opts.runs, opts.duration) {
        (Some(n), _) => format!(" of {}", opts.shard.map_or(n, |s| s.share(n))),
        (None, Some(d)) => {
            format!(" runs, {:.1} s of {}", c.elapsed_ms as f64 / 1000.0, humantime::format_duration(d))
        }
        (None, None) => {
            format!(" runs, {:.1} s of {}", c.elapsed_ms as f64 / 1000.0, humantime::format_duration(DEFAULT_DURATION))
        }
    };
    let runs = if of.starts_with(" runs") { "" } else { " runs" };
    format!("stopped by {by} after {}{of}{runs}", c.runs)
}

/// What makes this campaign's folder a shard of its campaign (see
/// [`gcl_harness::fuzz::shard::Provenance`]): its `--shard`, seed, and every option that
/// changed what ran or how it was judged, as its effective value.
fn provenance(args: &Args, opts: &FuzzOptions, base: Option<String>) -> gcl_harness::fuzz::shard::Provenance {
    let ms = |d: Duration| humantime::format_duration(d).to_string();
    let profile = gcl_harness::report::ProfileSpec::of(&args.host.profile, &opts.run.profile);
    let mut options: std::collections::BTreeMap<String, String> = [
        ("profile", profile.label()),
        ("command", serde_json::to_string(&opts.run.command).unwrap_or_default()),
        ("line", if opts.run.transport == Transport::Tcp { "tcp" } else { "pty" }.to_string()),
        ("time", opts.run.time.name().to_string()),
        ("pace", opts.run.pace.to_string()),
        (
            "ops",
            if args.ops.is_some() {
                opts.weights.0.iter().map(|(o, w)| format!("{}={w}", o.name())).collect::<Vec<_>>().join(",")
            } else {
                "every operator".to_string()
            },
        ),
        ("max-misbehaviours", opts.max_planned.to_string()),
        ("minimize", if opts.minimize { "yes" } else { "no (--no-minimize)" }.to_string()),
        // A sharded campaign is unguided whatever the flag says.
        ("guidance", if opts.guided && opts.shard.is_none() { "on" } else { "off" }.to_string()),
        (
            "timeout-hang",
            if args.host.timeout_hang_given() { ms(opts.run.timeout_hang) } else { "measured".to_string() },
        ),
        ("run-budget", ms(opts.run.budget)),
        ("ok-exit-codes", opts.ok_exit_codes.iter().map(i32::to_string).collect::<Vec<_>>().join(",")),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    if let Some(b) = base {
        options.insert("corpus".into(), b);
    }
    match (opts.runs, opts.campaign_duration()) {
        (_, Some(d)) => options.insert("duration".into(), ms(d)),
        (n, None) => options.insert("runs".into(), n.unwrap_or_default().to_string()),
    };
    gcl_harness::fuzz::shard::Provenance::new(opts.shard, opts.seed, options)
}

/// What a campaign without `--runs` or `--duration` says, at its start and its end.
fn default_budget_line() -> String {
    format!(
        "gcl fuzz host: no --runs or --duration: a {}-minute campaign; run longer with --duration (--duration 1h) or --runs N",
        DEFAULT_DURATION.as_secs() / 60
    )
}

/// Seconds for people, from milliseconds.
fn secs(ms: u64) -> String {
    format!("{:.1} s", ms as f64 / 1000.0)
}

/// A give-up time under this (milliseconds) is no wait for the answer (see
/// [`calibration_lines`]).
const NO_WAIT_MS: u64 = 100;

/// The host's timeouts as calibration measured them, for the console and the report: one
/// line per kind of answer, the hang timeout, and what was left unmeasured.
fn calibration_lines(c: &Calibration) -> Vec<String> {
    let mut lines = Vec::new();
    // A host that left within NO_WAIT_MS wherever the hand fell silent waited for no answer
    // (it sends and goes, or was gone before the answer was due): nothing of a timeout.
    let left_at_once = !c.by_kind.is_empty()
        && c.unmeasured.is_empty()
        && c.by_kind.iter().all(|k| k.gave_up_ms.is_some_and(|ms| ms < NO_WAIT_MS));
    if (c.by_kind.is_empty() && c.unmeasured.is_empty()) || left_at_once {
        // No silence fired, or none was waited for: the host took no answer at all, even
        // from a perfect hand.
        lines.push(format!(
            "warning: host timeouts not measured: the host took no answer from the hand in its run without \
             misbehaviour ({}), so this campaign tried little or nothing; hang timeout {}",
            if left_at_once {
                "wherever the hand fell silent it left or sent again within 0.1 s, as a host that does not wait for answers does"
            } else {
                "did it open the port it was given as {port} or {url}?"
            },
            secs(c.timeout_hang_ms)
        ));
        return lines;
    }
    // The longest give-up time is the host's timeout only where it gave up: where it never
    // did, the line says so beside it (it said `1.1 s` when 3 of 4 kinds never gave up).
    let gave_up = c.by_kind.iter().filter(|k| k.gave_up_ms.is_some()).count();
    let never = c.by_kind.len() - gave_up;
    let timeouts = match (c.host_timeout_ms, never) {
        (None, 0) => "none seen".to_string(),
        (None, n) => format!("none seen: at all {n} kinds it neither sent nor exited"),
        (Some(ms), 0) => secs(ms),
        (Some(ms), n) => format!(
            "{} at most where it gave up ({gave_up} of {} kinds; at {n} it neither sent nor exited)",
            secs(ms),
            c.by_kind.len()
        ),
    };
    lines.push(format!(
        "host timeouts (the hand silent at each kind of answer): {timeouts}; hang timeout {} ({} calibration runs, {})",
        secs(c.timeout_hang_ms),
        c.runs,
        secs(c.elapsed_ms)
    ));
    for k in &c.by_kind {
        let waited = match k.gave_up_ms {
            // No wait at all is no give-up time (it said `gave up after 0.0 s`).
            Some(ms) if ms < NO_WAIT_MS => "did not wait: sent or left within 0.1 s".to_string(),
            Some(ms) => format!("gave up after {}", secs(ms)),
            None if k.cut_by_share => {
                format!("waited past {} (calibration's share ran out): neither sent nor exited", secs(k.waited_past_ms))
            }
            None => format!("waited past {}: neither sent nor exited", secs(k.waited_past_ms)),
        };
        lines.push(format!("  {} (answer {}, {}): {waited}", k.kind, k.answer, k.state));
    }
    let cut: Vec<&str> = c.by_kind.iter().filter(|k| k.cut_by_share).map(|k| k.kind.as_str()).collect();
    if !c.unmeasured.is_empty() || !cut.is_empty() {
        let mut what = Vec::new();
        if !cut.is_empty() {
            what.push(format!("waits cut short at: {}", cut.join("; ")));
        }
        if !c.unmeasured.is_empty() {
            what.push(format!("not measured: {}", c.unmeasured.join("; ")));
        }
        lines.push(format!(
            "  calibration cut short at its share of the campaign (1/{CALIBRATION_SHARE} of --duration, {}): {}; \
             the campaign goes on with what it measured",
            c.share_ms.map_or("-".to_string(), secs),
            what.join("; ")
        ));
    }
    lines
}

/// SIGINT, SIGTERM and SIGHUP (a CI job's time limit) end the campaign: the runs in flight
/// are called off (their hosts killed) and bundles and reports are still written; a second
/// signal exits at once.
fn stop_on_signals() -> anyhow::Result<Arc<AtomicBool>> {
    super::stop_on_signals("fuzz host")
}

fn info(opts: &FuzzOptions, f: &Finding) -> BundleInfo {
    BundleInfo {
        kind: f.verdict.kind,
        signature: f.verdict.signature.clone(),
        message: f.verdict.message.clone(),
        seed: opts.seed,
        run: f.run,
        found_after_ms: f.found_after_ms,
        hits: f.hits,
        hand_seed: opts.run.hand_seed,
        profile: opts.run.profile.id.clone(),
        transport: opts.run.transport,
        time: opts.run.time.name().to_string(),
        command: opts.run.command.clone(),
        end: f.end.clone(),
        fired: f.fired.clone(),
        timeout_hang_ms: Some(f.timeout_hang_ms),
    }
}

/// A report with one case per distinct finding (or one passing case when there is none).
pub(super) fn campaign_report(opts: &FuzzOptions, c: &Campaign, out: &std::path::Path, ops_given: bool) -> RunReport {
    // Checked: a shard's fuzz.json is data from anywhere, and its elapsed_ms may be anything.
    let now = time::OffsetDateTime::now_utc();
    let started =
        now.checked_sub(time::Duration::milliseconds(i64::try_from(c.elapsed_ms).unwrap_or(i64::MAX))).unwrap_or(now);
    let mut cases: Vec<CaseResult> = c
        .findings
        .iter()
        .map(|f| CaseResult {
            id: format!("fuzz-host-{}", bundle::dir_name(f.verdict.kind, &f.verdict.signature)),
            title: f.verdict.signature.clone(),
            clauses: vec![format!("host: {}", f.verdict.kind.name())],
            decisions: Vec::new(),
            level: "MUST".into(),
            verdict: if f.verdict.kind == FindingKind::Hang { Verdict::Timeout } else { Verdict::Fail },
            // The campaign's time until the run that found it ended: what finding it took.
            duration_ms: f.found_after_ms as f64,
            message: Some(format!(
                "{} (run {}, {} hit(s), {})",
                f.verdict.message,
                f.run,
                f.hits,
                if f.schedule.planned.is_empty() {
                    "no misbehaviour: the hand behaved".to_string()
                } else {
                    let planned: Vec<String> =
                        f.schedule.planned.iter().map(|p| format!("{}@{}", p.op, p.answer)).collect();
                    format!("schedule: {}", planned.join(", "))
                }
            )),
            diff: None,
            failure: None,
            transcript: Some(gcl_harness::report::truncate_note(
                &bundle::transcript(&info(opts, f), &f.exchanges),
                gcl_harness::report::MAX_SHOWN,
            )),
        })
        .collect();
    for (n, runs) in &c.notes {
        cases.push(CaseResult {
            id: format!("fuzz-host-{}", bundle::dir_name(FindingKind::Violation, n).replacen("violation-", "note-", 1)),
            title: n.clone(),
            clauses: vec!["host: reaction to a misbehaving hand".into()],
            decisions: Vec::new(),
            level: "INFO".into(),
            verdict: Verdict::Pass,
            // Seen across the campaign's runs: the campaign's time.
            duration_ms: c.elapsed_ms as f64,
            message: Some(format!("a note, no finding: seen in {runs} run(s)")),
            diff: None,
            failure: None,
            transcript: None,
        });
    }
    // Without a finding, one case says what the campaign judged: a pass only when it ran to
    // its end with runs that reached the host.
    if c.findings.is_empty() {
        let (verdict, message) = match (&c.untested, &c.stopped) {
            (Some(why), _) => (Verdict::Error, Some(format!("nothing tested: {why}"))),
            (None, Some(st)) => (Verdict::Error, Some(format!("{st}, without a finding: no verdict on the host"))),
            (None, None) => (Verdict::Pass, None),
        };
        cases.push(CaseResult {
            id: "fuzz-host-campaign".into(),
            title: format!(
                "{} runs against a misbehaving hand ({} reached the host) without a finding",
                c.runs, c.reached
            ),
            clauses: vec!["host: fuzz".into()],
            decisions: Vec::new(),
            level: "MUST".into(),
            verdict,
            duration_ms: c.elapsed_ms as f64,
            message,
            diff: None,
            failure: None,
            transcript: None,
        });
    }
    let mut report = gcl_harness::host_check::host_report(
        &opts.run.command,
        &opts.run.profile.id,
        started,
        c.elapsed_ms as f64,
        opts.seed,
        true,
        cases,
    );
    report.host = Some(host_details(opts, c, out, ops_given));
    report.stopped = match (&c.untested, &c.stopped) {
        (Some(why), _) => Some(Stopped {
            cause: StopCause::CannotTest,
            case: "fuzz-host-campaign".into(),
            message: format!("nothing tested: {why}"),
        }),
        (None, Some(st)) => Some(Stopped { cause: StopCause::Signal, case: String::new(), message: st.clone() }),
        (None, None) => None,
    };
    report
}

/// The campaign as the report's pages show it: runs, seed, ops, what fired where, and each
/// finding's bundle with the command that replays it.
fn host_details(opts: &FuzzOptions, c: &Campaign, out: &std::path::Path, ops_given: bool) -> HostDetails {
    let replay = |dir: &std::path::Path| {
        let head = ["gcl", "fuzz", "host", "--replay", &dir.display().to_string(), "--"].map(String::from);
        gcl_harness::report::shell_command(&[head.as_slice(), &opts.run.command].concat())
    };
    HostDetails {
        command: opts.run.command.clone(),
        runs: c.runs,
        reached: Some(c.reached),
        minimize_runs: c.minimize_runs,
        seed: opts.seed,
        ops: if ops_given {
            opts.weights.0.iter().map(|(o, w)| format!("{}={w}", o.name())).collect()
        } else {
            Vec::new()
        },
        fired_at: c.fired_at.clone(),
        facts: hand_facts(&opts.run)
            .into_iter()
            .chain([
                ("jobs".into(), opts.jobs.to_string()),
                ("paths seen".into(), format!("{} ({} schedules kept)", c.paths, c.corpus)),
            ])
            .chain(c.provenance.as_ref().and_then(|p| p.shard).map(|s| {
                (
                    "shard".into(),
                    format!(
                        "{} of {} (--shard {s}): run indices {}, {}, ...",
                        s.index,
                        s.count,
                        s.global(0),
                        s.global(1)
                    ),
                )
            }))
            .chain(c.provenance.as_ref().and_then(|p| p.merged.as_ref()).map(|m| ("merged from".into(), m.describe())))
            .chain(c.pass_line().map(|l| ("systematic pass".into(), l.replacen("systematic pass: ", "", 1))))
            .chain(c.coverage.as_ref().map(|cov| ("code coverage".into(), cov.line().replacen("coverage: ", "", 1))))
            .chain(timeout_facts(opts, c))
            .collect(),
        merged: c.provenance.as_ref().and_then(|p| p.merged.clone()),
        edges_over_time: c
            .coverage
            .as_ref()
            .map(|cov| cov.over_time.iter().map(|p| (p.ms, p.runs, p.edges)).collect())
            .unwrap_or_default(),
        added_coverage: c
            .coverage
            .as_ref()
            .map(|cov| cov.added_by.iter().map(|a| (a.run, a.new_edges, a.schedule.clone())).collect())
            .unwrap_or_default(),
        findings: c
            .findings
            .iter()
            .map(|f| {
                let dir = out.join(bundle::dir_name(f.verdict.kind, &f.verdict.signature));
                HostFinding {
                    case: format!("fuzz-host-{}", bundle::dir_name(f.verdict.kind, &f.verdict.signature)),
                    kind: f.verdict.kind.name().to_string(),
                    signature: f.verdict.signature.clone(),
                    run: f.run,
                    bundle: Some(dir.display().to_string()),
                    replay: Some(replay(&dir)),
                    stderr: f.stderr.clone(),
                }
            })
            .collect(),
    }
}

/// The hang timeout and the host's own timeouts, as the report's facts.
fn timeout_facts(opts: &FuzzOptions, c: &Campaign) -> Vec<(String, String)> {
    let Some(cal) = &c.calibration else {
        return vec![(
            "hang timeout".into(),
            format!("{} (--timeout-hang)", secs(opts.run.timeout_hang.as_millis() as u64)),
        )];
    };
    let mut v = vec![(
        "hang timeout".into(),
        format!(
            "{} (measured: twice the host's longest give-up time, {}, plus 2 s)",
            secs(cal.timeout_hang_ms),
            cal.host_timeout_ms.map_or("none seen".to_string(), secs)
        ),
    )];
    for k in &cal.by_kind {
        let waited = match k.gave_up_ms {
            Some(ms) if ms < NO_WAIT_MS => "did not wait: sent or left within 0.1 s".to_string(),
            Some(ms) => format!("gave up after {}", secs(ms)),
            None => format!("waited past {}", secs(k.waited_past_ms)),
        };
        v.push((format!("host timeout: {} ({})", k.kind, k.state), waited));
    }
    if !cal.unmeasured.is_empty() {
        v.push((
            "host timeouts not measured".into(),
            format!("{} (calibration's share ran out)", cal.unmeasured.join("; ")),
        ));
    }
    v
}

fn replay(args: &Args, mut run: HostRun, dir: &std::path::Path) -> anyhow::Result<u8> {
    let (info, schedule) = bundle::read(dir)?;
    // A built-in profile or a file inside the bundle: a bundle is data from anywhere.
    run.profile = gcl_host::profiles::load_from_bundle(&info.profile, dir)?;
    run.transport = info.transport;
    run.hand_seed = info.hand_seed;
    // The bundle's time mode, so the hand answers as it did; an explicit --baud still paces.
    run.time = if info.time == TimeMode::Real.name() { TimeMode::Real } else { TimeMode::Fast };
    run.pace = args.host.pace(run.time);
    if let (false, Some(ms)) = (args.host.timeout_hang_given(), info.timeout_hang_ms) {
        run.timeout_hang = std::time::Duration::from_millis(ms);
    }
    // One run: slot 1's link.
    run.link = run.link.map(|l| l.to_string_lossy().replace("{slot}", "1").into());
    let r = run_once(&run, &schedule)?;
    // A host that never talked to the hand reproduces nothing, and refutes nothing either.
    if let Some(why) = gcl_harness::fuzz::host::unreached(&r, &run.command) {
        errln!("gcl fuzz host: nothing tested: {why}");
        return Ok(EXIT_ERROR);
    }
    let verdicts = judge(&r, &args.host.ok_exit_codes());
    for f in &r.fired {
        errln!("  fired {} at answer {} ({}): {}", f.op, f.answer, printable(&f.state), printable(&f.what));
    }
    if verdicts.iter().any(|v| v.signature == info.signature) {
        errln!("gcl fuzz host: reproduced: {}", printable(&info.signature));
        Ok(EXIT_FAIL)
    } else {
        errln!("gcl fuzz host: NOT reproduced: {}", printable(&info.signature));
        for v in &verdicts {
            errln!("  instead: {}", printable(&v.signature));
        }
        Ok(if verdicts.is_empty() { EXIT_OK } else { EXIT_FAIL })
    }
}

/// Refuses `--runs N` that leaves `--shard K/N` no run at all: such a shard would test
/// nothing and still report.
pub(super) fn refuse_empty_shard(
    runs: Option<u64>,
    shard: Option<gcl_harness::fuzz::shard::Shard>,
) -> anyhow::Result<()> {
    if let (Some(n), Some(s)) = (runs, shard)
        && s.share(n) == 0
    {
        anyhow::bail!("--runs {n} leaves shard {s} no run (it would test nothing): give at least {} runs", s.index);
    }
    Ok(())
}
