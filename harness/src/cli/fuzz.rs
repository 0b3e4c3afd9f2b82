//! `gcl fuzz`: fuzzers that check someone else's hand or host library against the reference
//! model. This module only turns arguments into the library's options and
//! prints; the fuzzers live in `gcl_harness::fuzz`.

use super::stdio::errln;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;

use anyhow::Context;
use gcl_model::Fault;
use gcl_model::escape::printable;

use super::{EXIT_ERROR, EXIT_FAIL, EXIT_OK, fuzz_host, load_profile};

/// Arguments of `gcl fuzz`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to fuzz.
    #[command(subcommand)]
    pub command: FuzzCommand,
}

/// The fuzzers.
#[derive(Debug, clap::Subcommand)]
pub enum FuzzCommand {
    /// Fuzz a hand over the wire with host actions drawn from the profile; the reference model
    /// judges every answer.
    Device(DeviceArgs),
    /// Put a misbehaving simulated hand in front of a host program: crashes, hangs, protocol
    /// violations, with reproducers.
    Host(fuzz_host::Args),
    /// Fold the report, bundle, finding and corpus folders of a campaign's shards
    /// (`--shard K/N`) into one.
    Merge(super::fuzz_merge::Args),
    /// Fold `gcl fuzz host` corpus folders (`--corpus`: a base, the schedules shards wrote to
    /// its `incoming/`, other folders) into one, keeping only schedules that add edges.
    MergeCorpus(MergeCorpusArgs),
}

/// Arguments of `gcl fuzz merge-corpus`.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Each schedule file of a `gcl fuzz host --corpus` folder holds the edges of the host's code its
run reached. The merge reads DIR, DIR/incoming (what shards wrote) and each FROM folder (and
its incoming/), and keeps in DIR, for each edge, the schedule with the fewest misbehaviours
that reached it (as afl-cmin does), and every schedule without edges (its run read no map).
The others are removed from DIR, and the incoming files read are removed; FROM folders are only
read. Nothing is run: the edges are those the files hold.")]
pub struct MergeCorpusArgs {
    /// The corpus folder to merge into (made if missing).
    pub dir: PathBuf,
    /// Other corpus folders to fold in (another machine's, a cache).
    pub from: Vec<PathBuf>,
}

/// Arguments of `gcl fuzz device`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Exit codes: 0 no new finding in the cases run (the reports say how many ran and how many \
drawn cases were dropped); 1 new findings (each written as a minimized transcript \
with --out; a finding --baseline or --known-failures explains is known, not new); 2 nothing to test or no verdict: \
options that leave no case are refused at the start (--runs 0, a --skip-decision of a decision every case rests on, \
such as framing-line-ending), 5000 drawn cases dropped in a row end the campaign, a hand that stops answering ends \
it, and a signal (SIGINT, SIGTERM, SIGHUP) that stops it before a new finding leaves no verdict (every report says \
`stopped by SIGTERM after N of M runs`); also a usage or infrastructure error.\n\nserial: targets are fuzzed conservatively by default: no EEPROM \
writes (FSAVE, PSAVE) unless --write-budget N allows N of them, no change of the hand's line rate unless --allow \
rate-change, and one worker.\n\nExamples:\n  gcl fuzz device \
--target sim --fault fget-reversed --seed 1 --runs 500 --out reports/findings\n  gcl fuzz device --target 'exec:gcl sim \
--stdio' --no abort-timing --duration 30s --jobs 2\n  gcl fuzz device --target serial:/dev/ttyUSB0 \
--profile bh8-262-4.3 --no motion --duration 5m")]
pub struct DeviceArgs {
    /// The hand: `sim[:PROFILE]`, `serial:PATH[?baud=N]`, `tcp://HOST:PORT` or `exec:COMMAND ARGS`.
    #[arg(long, value_name = "TARGET")]
    pub target: gcl_host::target::Target,
    /// sim targets: a deliberate firmware bug (repeatable; see `gcl sim --help`).
    #[arg(long, value_name = "NAME")]
    pub fault: Vec<Fault>,
    /// The profile the model speaks (default: the sim target's profile, else bh8-262).
    #[arg(long)]
    pub profile: Option<String>,
    /// Seed of the generator (worker i uses SEED + i).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// How long to fuzz, e.g. `30s`, `5m` (default 60s unless --runs is given).
    #[arg(long, value_parser = super::duration, conflicts_with = "runs")]
    pub duration: Option<Duration>,
    /// How many cases to run, at least 1.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub runs: Option<u64>,
    /// Stop after N distinct findings.
    #[arg(long, value_name = "N")]
    pub max_findings: Option<usize>,
    /// A corpus directory: read at the start, and every case that reaches new model coverage
    /// is added (one file per entry, named by its content hash, so corpora merge).
    #[arg(long, value_name = "DIR")]
    pub corpus: Option<PathBuf>,
    /// Write each distinct finding's minimized transcript into DIR (`gcl replay` runs it).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Refuse what the hand may not do: motion, realtime, eeprom, abort-timing (repeatable).
    /// Needed: `--no abort-timing` against a simulator in fast time (`gcl sim --stdio`,
    /// `--time fast`), whose motions end at once; such a target is refused (exit 2) without it.
    #[arg(long = "no", value_name = "REQUIREMENT")]
    pub refuse: Vec<String>,
    /// Allow what a serial target refuses by default (repeatable): `rate-change`, cases may
    /// set the hand's line rate (BAUD); the port follows each change after the hand's answer
    /// and sets the hand back to the port's rate before it closes.
    #[arg(long = "allow", value_name = "WHAT")]
    pub allow: Vec<String>,
    /// The most EEPROM writes the run may make (restores included); serial targets: 0 unless given.
    #[arg(long, value_name = "N")]
    pub write_budget: Option<u64>,
    /// Write fuzz-device.json, junit.xml and fuzz-device.html into DIR.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Workers, each with its own connection (sim, exec: and tcp:// targets).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=64))]
    pub jobs: u64,
    /// Keep findings as found, without minimizing them.
    #[arg(long)]
    pub no_minimize: bool,
    /// A folder of earlier findings (what `--out` wrote): a finding with the signature of one
    /// of them is known, not new (repeatable). Status bits the baseline has are known only on
    /// the command it had them on. A baseline recorded under another profile is refused; the
    /// baseline is named in the report.
    #[arg(long, value_name = "DIR")]
    pub baseline: Vec<PathBuf>,
    /// Known failures, as for `gcl conform`: an entry's `case` glob matches a finding's id
    /// (`fuzz-fget-order`) or signature; its `[[skip-decision]]` entries apply as
    /// `--skip-decision` does.
    #[arg(long, value_name = "FILE")]
    pub known_failures: Option<PathBuf>,
    /// A decision the hand took differently (repeatable): no case resting on it is drawn.
    #[arg(long, value_name = "ID")]
    pub skip_decision: Vec<String>,
    /// Print only the summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Run only shard K of N (for a CI matrix): its worker w draws from the generator stream
    /// K-1+w*N (seed + that), and --runs is the whole campaign's, of which it runs its share;
    /// `gcl fuzz merge` folds the shards' folders into one. The report records the shard, the
    /// seed and every option that changed what ran, so that only one campaign's shards merge.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<gcl_harness::fuzz::shard::Shard>,
}

/// Runs `gcl fuzz`.
pub fn run(a: Args) -> anyhow::Result<u8> {
    match a.command {
        FuzzCommand::Device(d) => device(d),
        FuzzCommand::Host(h) => fuzz_host::run(h),
        FuzzCommand::Merge(m) => super::fuzz_merge::run(m),
        FuzzCommand::MergeCorpus(m) => merge_corpus(m),
    }
}

fn merge_corpus(a: MergeCorpusArgs) -> anyhow::Result<u8> {
    let m = gcl_harness::fuzz::host::corpus::merge(&a.dir, &a.from)
        .with_context(|| format!("merging into the corpus {}", a.dir.display()))?;
    for (p, why) in &m.malformed {
        errln!("gcl fuzz merge-corpus: warning: {}", printable(&format!("{} left as it is: {why}", p.display())));
    }
    errln!(
        "gcl fuzz merge-corpus: {} schedule(s) read, {} kept in {} ({} edges; {} without edges kept as they are)",
        m.read,
        m.kept,
        a.dir.display(),
        m.edges,
        m.without_edges
    );
    Ok(EXIT_OK)
}

fn device(a: DeviceArgs) -> anyhow::Result<u8> {
    let (mut o, baselines) = device_options(&a)?;
    fuzz_host::refuse_empty_shard(a.runs, a.shard)?;
    // A CI time limit (SIGTERM) ends the campaign with its reports written. Before any thread
    // starts: a thread started earlier would keep the signals unblocked.
    o.stop = super::stop_on_signals("fuzz device")?;
    let ran = device_campaign(&a, &o)?;
    let report = device_report(&a, &o, &ran.summary, ran.timeline, &baselines);
    print_device_summary(&a, &ran.summary, &report)?;
    Ok(device_exit(&ran.summary, &report))
}

/// The campaign's options from the arguments (the profile, its refusals, known failures and
/// baselines), with the baselines as the provenance names them; or why they make none.
fn device_options(a: &DeviceArgs) -> anyhow::Result<(gcl_harness::fuzz::device::FuzzOptions, Vec<String>)> {
    use gcl_harness::fuzz::device::{Budget, FuzzOptions};
    use gcl_host::target::Target;
    let profile = load_profile(a.target.model_profile(a.profile.as_deref()))?;
    if !a.fault.is_empty() && !matches!(a.target, Target::Sim { .. }) {
        anyhow::bail!("--fault applies to sim targets only");
    }
    let serial = matches!(a.target, Target::Serial { .. });
    if serial && a.jobs > 1 {
        anyhow::bail!("--jobs: a serial port can be opened once; use one worker");
    }
    let mut o = FuzzOptions::new(a.target.clone(), profile);
    o.open.faults = a.fault.clone();
    o.seed = a.seed;
    o.shard = a.shard;
    o.budget = match (a.runs, a.duration) {
        (Some(n), _) => Budget::Runs(a.shard.map_or(n, |s| s.share(n))),
        (None, Some(d)) => Budget::Time(d),
        (None, None) => Budget::Time(Duration::from_secs(60)),
    };
    o.max_findings = a.max_findings;
    o.corpus = a.corpus.clone();
    o.out = a.out.clone();
    o.jobs = a.jobs as usize;
    o.minimize = !a.no_minimize;
    if let Some(b) = a.write_budget {
        o.write_budget = Some(b);
        o.allowed.eeprom = b > 0;
    }
    for r in &a.refuse {
        match r.as_str() {
            "motion" => o.allowed.motion = false,
            "realtime" => o.allowed.realtime = false,
            "eeprom" => {
                o.allowed.eeprom = false;
                o.write_budget = Some(0);
            }
            "abort-timing" => o.allowed.abort_timing = false,
            other => anyhow::bail!("unknown requirement `{other}` (motion, realtime, eeprom, abort-timing)"),
        }
    }
    for w in &a.allow {
        match w.as_str() {
            "rate-change" if serial => {
                o.allowed.keep_rate = None;
                o.open.follow_rate = true;
            }
            "rate-change" => anyhow::bail!(
                "--allow rate-change applies to serial: targets only (the others have no line rate to keep)"
            ),
            other => anyhow::bail!("unknown --allow `{other}` (rate-change)"),
        }
    }
    if let Some(f) = &a.known_failures {
        o.baseline.known = gcl_harness::conform::KnownFailures::load(f)?;
    }
    for id in &a.skip_decision {
        if !o.profile.decisions.iter().any(|d| &d.id == id) {
            anyhow::bail!(
                "--skip-decision {id}: profile {} has no such decision (`gcl spec` lists them)",
                o.profile.id
            );
        }
        o.baseline.known.skip_decision(id, "--skip-decision");
    }
    let baselines = add_baselines(a, &mut o)?;
    Ok((o, baselines))
}

/// Adds `--baseline` folders to the options: each as the provenance names it; refused when
/// one was recorded under another profile.
fn add_baselines(a: &DeviceArgs, o: &mut gcl_harness::fuzz::device::FuzzOptions) -> anyhow::Result<Vec<String>> {
    let mut baselines = Vec::new();
    for dir in &a.baseline {
        let n = o.baseline.add_dir(dir).with_context(|| format!("--baseline {}", dir.display()))?;
        // A finding is known only under the profile it was found under.
        if let Some((file, profiles)) = o.baseline.recorded_elsewhere(&o.profile.id).first() {
            anyhow::bail!(
                "--baseline {}: {} was recorded on profile {}, and this campaign's profile is {}: a baseline says what \
                 is known of a hand under its own profile only (record a baseline with --profile {}, or fuzz with the \
                 baseline's profile)",
                dir.display(),
                file.display(),
                profiles.join(" "),
                o.profile.id,
                o.profile.id
            );
        }
        // ... and under its spec, not only its id: a file declaring the id with other contents
        // is another profile.
        let spec = gcl_harness::report::ProfileSpec::of(a.target.model_profile(a.profile.as_deref()), &o.profile);
        if let Some((file, theirs)) = o.baseline.recorded_on_another_spec(&spec).first() {
            let theirs = match theirs {
                Some(d) => format!("a spec with sha256 {}", &d[..d.len().min(16)]),
                None => format!("no spec (written by an older gcl, so taken as the built-in {})", o.profile.id),
            };
            anyhow::bail!(
                "--baseline {}: {} names {theirs}, and this campaign's profile is {}: a baseline says what is known of a hand under the spec it was recorded on only (record the baseline again with this profile)",
                dir.display(),
                file.display(),
                spec.label()
            );
        }
        baselines.push(match n {
            0 => format!("{} (no finding in it)", dir.display()),
            n => format!("{} ({n} finding(s), recorded on profile {})", dir.display(), o.profile.id),
        });
    }
    Ok(baselines)
}

/// What [`device_campaign`] gives: the summary, the coverage over time, and the folders held.
struct DeviceRun {
    summary: gcl_harness::fuzz::device::FuzzSummary,
    timeline: Vec<gcl_harness::fuzz::device::report::CoveragePoint>,
    /// Held until the reports are written.
    _held: Vec<gcl_harness::outputs::OutLock>,
}

/// Runs the campaign with its progress line (findings printed as found) and its folders held.
fn device_campaign(a: &DeviceArgs, o: &gcl_harness::fuzz::device::FuzzOptions) -> anyhow::Result<DeviceRun> {
    use gcl_harness::fuzz::device::{self as fd, Budget, Progress};
    let total = match o.budget {
        Budget::Runs(n) => super::progress::Total::Units(n),
        Budget::Time(d) => super::progress::Total::Time(d),
    };
    let progress = super::progress::Progress::new("gcl fuzz device", "runs", "findings", total, a.quiet);
    // Coverage over time, for the report's plot: a point whenever the features grow.
    let timeline: Mutex<Vec<fd::report::CoveragePoint>> = Mutex::new(Vec::new());
    let on_progress = |p: Progress<'_>| match p {
        Progress::Run { runs, findings, features, elapsed } => {
            progress.update(runs, findings as u64, &format!("{findings} findings, {features} features"));
            let mut t = timeline.lock().unwrap_or_else(|e| e.into_inner());
            if t.last().is_none_or(|l| l.features < features as u64) {
                t.push(fd::report::CoveragePoint {
                    elapsed_ms: elapsed.as_millis() as u64,
                    runs,
                    features: features as u64,
                });
            }
        }
        Progress::Finding(f) if !a.quiet => {
            let at = f.path.as_ref().map_or(String::new(), |p| format!(" -> {}", p.display()));
            let known = f.known.as_ref().map_or(String::new(), |k| format!(" [known: {k}]"));
            progress.println(&format!(
                "finding: {}{known} (run {}, {} ms, {} actions){at}",
                f.signature,
                f.run,
                f.found_after.as_millis(),
                f.actions.len()
            ));
        }
        Progress::Note(line) => progress.println(&printable(line)),
        Progress::NotReproduced(n) if !a.quiet => {
            progress.println(&format!(
                "not reproduced: {} (its minimized transcript failed so {} of {} times on a fresh connection: a note, not a finding)",
                printable(&n.signature),
                n.reproduced,
                n.replays
            ));
        }
        Progress::Joined { finding, explanation } if !a.quiet => {
            progress.println(&format!(
                "joined: {} is `{explanation}` (found since; its transcript removed)",
                finding.signature
            ));
        }
        _ => {}
    };
    // Held for the campaign: a second campaign on the same folders is refused, so neither
    // replaces the other's findings or reports.
    let mut _held = Vec::new();
    for (dir, what) in [(&a.out, "fuzz device --out"), (&a.report, "fuzz device --report")] {
        if let Some(d) = dir
            && !(what.ends_with("--report") && a.out.as_ref() == Some(d))
        {
            _held.push(gcl_harness::outputs::OutLock::acquire(d, what)?);
        }
    }
    // Let go last held first: a parent the first lock made for both goes once both are empty.
    _held.reverse();
    let s = fd::run(o, &on_progress).context("gcl fuzz device")?;
    progress.finish();
    let timeline = timeline.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok(DeviceRun { summary: s, timeline, _held })
}

/// The campaign's report: its summary, how a signal stopped it, its coverage over time and
/// provenance (warning of corpus files skipped).
fn device_report(
    a: &DeviceArgs,
    o: &gcl_harness::fuzz::device::FuzzOptions,
    s: &gcl_harness::fuzz::device::FuzzSummary,
    timeline: Vec<gcl_harness::fuzz::device::report::CoveragePoint>,
    baselines: &[String],
) -> gcl_harness::fuzz::device::report::FuzzReport {
    use gcl_harness::fuzz::device::{self as fd, Budget};
    for (p, why) in &s.malformed_corpus {
        errln!("gcl fuzz device: warning: {}", printable(&format!("corpus file {} skipped: {why}", p.display())));
    }
    let mut report = fd::report::FuzzReport::new(o, s);
    if let Some(by) = super::stopped_by().filter(|_| s.interrupted) {
        let of = match o.budget {
            Budget::Runs(n) => format!(" of {n} runs"),
            Budget::Time(d) => {
                format!(" runs, {:.1} s of {}", s.elapsed.as_secs_f64(), humantime::format_duration(d))
            }
        };
        let st = format!("stopped by {by} after {}{of}", s.runs);
        errln!("gcl fuzz device: {st}; the report covers the runs made");
        report.stopped = Some(st);
    }
    report.coverage_over_time = timeline;
    report.provenance = Some(provenance(a, o, baselines));
    // Sealed, so that a merge takes this folder only as written.
    if let Err(e) = gcl_harness::fuzz::merge::seal_device(&mut report, a.out.as_deref().unwrap_or(Path::new("."))) {
        errln!(
            "gcl fuzz device: warning: {}",
            printable(&format!("the report is not sealed, and no merge takes it: {e}"))
        );
    }
    report
}

/// Prints the campaign's figures and findings, its coverage (unless `--quiet`), and writes
/// the `--report` pages.
fn print_device_summary(
    a: &DeviceArgs,
    s: &gcl_harness::fuzz::device::FuzzSummary,
    report: &gcl_harness::fuzz::device::report::FuzzReport,
) -> anyhow::Result<()> {
    use gcl_harness::fuzz::device as fd;
    let mut out = super::stdio::out();
    writeln!(
        out,
        "{} runs ({} drawn cases dropped: the model made no case of them, they rest on a skipped decision, they would change a serial line's rate, or the EEPROM write budget was spent) in {:.1} s, {:.1} cases/s, {:.0} wire bytes/s ({:.0} sent, {:.0} received), {:.1} lines sent/s; {} distinct findings ({} new, {} known); {} corpus entries; {} EEPROM writes",
        s.runs,
        s.dropped,
        s.elapsed.as_secs_f64(),
        s.cases_per_second(),
        s.per_second(s.wire_bytes),
        s.per_second(s.bytes_sent),
        s.per_second(s.wire_bytes - s.bytes_sent),
        s.per_second(s.lines_sent),
        s.findings.len(),
        s.findings.iter().filter(|f| f.is_new()).count(),
        s.findings.iter().filter(|f| !f.is_new()).count(),
        s.corpus,
        s.eeprom_writes
    )?;
    for f in &s.findings {
        writeln!(
            out,
            "  {}{}{} ({} actions){}",
            printable(&f.signature.to_string()),
            fd::report::binding_note(f),
            printable(&f.known.as_ref().map_or(String::new(), |k| format!(" [known: {k}]"))),
            f.actions.len(),
            f.path.as_ref().map_or(String::new(), |p| format!(": {}", p.display()))
        )?;
    }
    for n in &s.not_reproduced {
        writeln!(
            out,
            "  note: not reproduced: {} (failed {} of {} replays of its minimized transcript on a fresh connection)",
            printable(&n.signature),
            n.reproduced,
            n.replays
        )?;
    }
    if let Some(who) = &s.identity {
        writeln!(out, "  {}", printable(who))?;
    }
    for said in &s.hand_after {
        writeln!(out, "  hand after: {}", printable(said))?;
    }
    if !a.quiet {
        write!(out, "{}", fd::coverage::render(&report.coverage))?;
    }
    writeln!(out, "  result: {}", report.verdict())?;
    if let Some(dir) = &a.report {
        for p in fd::report::write_all(dir, report)? {
            writeln!(out, "wrote {}", p.display())?;
        }
    }
    Ok(())
}

/// The exit code: a dead hand or nothing to test is an error; a new finding fails; stopped
/// early without one, no verdict.
fn device_exit(
    s: &gcl_harness::fuzz::device::FuzzSummary,
    report: &gcl_harness::fuzz::device::report::FuzzReport,
) -> u8 {
    if let Some(why) = &s.dead_hand {
        errln!("gcl fuzz device: {}", printable(why));
        return EXIT_ERROR;
    }
    if let Some(why) = &s.no_cases {
        errln!("gcl fuzz device: nothing left to test: {}", printable(why));
        return EXIT_ERROR;
    }
    if s.runs == 0
        && !s.interrupted
        && let Some(why) = &report.stopped
    {
        errln!("gcl fuzz device: nothing tested: {}", printable(why));
    }
    // Only new findings fail the run: what the baseline explains was known before. A
    // campaign stopped before its budget without one has no verdict.
    match (s.findings.iter().any(|f| f.is_new()), &report.stopped) {
        (true, _) => EXIT_FAIL,
        (false, Some(_)) => EXIT_ERROR,
        (false, None) => EXIT_OK,
    }
}

/// What makes this campaign's folder a shard of its campaign (see
/// [`gcl_harness::fuzz::shard::Provenance`]): its `--shard`, seed, and every option that
/// changed what ran or how it was judged (`--baseline`, `--skip-decision` among them), as its
/// effective value; `--runs` is the whole campaign's, not the shard's share.
fn provenance(
    a: &DeviceArgs,
    o: &gcl_harness::fuzz::device::FuzzOptions,
    baselines: &[String],
) -> gcl_harness::fuzz::shard::Provenance {
    let list = |v: Vec<String>| if v.is_empty() { "none".to_string() } else { v.join(", ") };
    let given = a.target.model_profile(a.profile.as_deref());
    let allowed = o.allowed;
    let refused: Vec<String> = [
        ("motion", allowed.motion),
        ("realtime", allowed.realtime),
        ("eeprom", allowed.eeprom),
        ("abort-timing", allowed.abort_timing),
    ]
    .iter()
    .filter(|(_, ok)| !ok)
    .map(|(n, _)| n.to_string())
    .collect();
    let mut options: std::collections::BTreeMap<String, String> = [
        ("target", a.target.to_string()),
        ("profile", gcl_harness::report::ProfileSpec::of(given, &o.profile).label()),
        ("fault", list(a.fault.iter().map(|f| f.name().to_string()).collect())),
        ("no", list(refused)),
        ("write-budget", o.write_budget.map_or("unlimited".to_string(), |b| b.to_string())),
        ("max-findings", o.max_findings.map_or("none".to_string(), |n| n.to_string())),
        ("jobs", o.jobs.to_string()),
        ("minimize", if o.minimize { "yes" } else { "no (--no-minimize)" }.to_string()),
        ("baseline", list(baselines.to_vec())),
        ("known-failures", a.known_failures.as_ref().map_or("none".to_string(), |f| f.display().to_string())),
        ("skip-decision", list(a.skip_decision.clone())),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    if !a.allow.is_empty() {
        options.insert("allow".into(), list(a.allow.clone()));
    }
    match (a.runs, a.duration) {
        (Some(n), _) => options.insert("runs".into(), n.to_string()),
        (None, d) => options
            .insert("duration".into(), humantime::format_duration(d.unwrap_or(Duration::from_secs(60))).to_string()),
    };
    gcl_harness::fuzz::shard::Provenance::new(o.shard, o.seed, options)
}
