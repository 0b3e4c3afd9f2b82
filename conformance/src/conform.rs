//! The conformance runner behind `gcl conform` and `gcl certify`: select cases, probe the
//! hand, run every case over a [`Link`] with its own deadlines, turn replay outcomes into
//! verdicts (known failures become XFAIL, or XPASS when they pass), and account for wire
//! time.
//!
//! The runner never hangs on a hung hand: every step of every case has a deadline, and a
//! vanished hand ends its case as ERROR and is reopened for the next one.
//!
//! Selection covers levels, globs, refused requirements, skipped decisions, and set-ups neither
//! placed nor declared. The liveness probe (`probe`) says what it found: silence, bytes without a
//! prompt, a flood, a hang-up. The dead-hand rule's probe (`dead_hand`) is the liveness probe and
//! then an unknown command line, so a hand answering only ^C and a bare CR is dead too; `gcl fuzz
//! device` uses it as well.
//!
//! After the pre-flight, the motion-time probe (`motion.rs`, which `gcl fuzz device` runs too)
//! runs before abort-timing cases on a hand outside this process. A hand whose motions end at once
//! gets them SKIP with one line that says why, unless `--assume-real-time`; a hand still moving at
//! a
//! quarter of the model's time is stopped there with ^C (`MotionProbe::decided_after`) instead of
//! being left to close. The pre-flight's last probe is RESET and ends at a quiet prompt, so the
//! probe
//! leaves out its own ^C and RESET (`MotionProbe::after_reset`) and nothing before the first case
//! waits for quiet twice.
//!
//! Early ends: `--max-failures`, a hand that stops answering, a vanished target that cannot be
//! reopened (an infrastructure end: exit 2, `result: ERROR`). A vanished target is drained and
//! probed before it is reopened. `RunEvent`s tell the CLI about the pre-flight, each case and an
//! early end as they happen.
//!
//! Wire-time accounting is a lower bound from the wire's physics: steps one after the other, as GCL
//! is command-then-answer; per step the larger of its received bytes, full duplex with the echo,
//! plus
//! one byte where it sent any (no answer starts before the first byte has crossed), and the model's
//! motion time; the model carries the hand's state from one passing case to the next on a kept
//! link, and from the motion-time probe to the first case. What the run puts on the line before
//! its first case (the pre-flight's and the motion-time probe's exchanges) is counted by the same
//! rule, since the run's wall time includes it (`probes_ms`).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use gcl_model::Profile;
use globset::{Glob, GlobSet, GlobSetBuilder};
use serde::Deserialize;

use crate::deadline::DeadlinePolicy;
use crate::replay::{ReplayOptions, ReplayOutcome, actual_transcript, discard, replay};
use crate::report::{
    CONTEXT_CHARS, CaseResult, Diff, KnownFailureEntry, Liveness, MAX_SHOWN, REPORT_FORMAT, ResultStream, RunOptions,
    RunReport, StopCause, Stopped, Verdict, WireTime, truncate_note,
};
/// Which levels run (kept here, where `conform` options name it).
pub use crate::suite::LevelFilter;
use crate::suite::{self, Case};
use gcl_host::link::{Link, LinkError, SimLink, byte_time};
use gcl_host::target::{OpenOptions, Target, open};
use gcl_transcript::{Form, Requirement};

/// Why a conformance run could not run (a failing hand is a report, not an error).
#[derive(Debug, thiserror::Error)]
pub enum ConformError {
    /// An `--only` or `--skip` pattern is not a glob.
    #[error(transparent)]
    Glob(#[from] BadGlob),
    /// A skipped decision names no decision of the profile.
    #[error("skip-decision: profile {profile} has no decision `{id}` (`gcl spec --profile {profile}` lists them)")]
    UnknownSkipDecision {
        /// The profile's id.
        profile: String,
        /// The decision id as given.
        id: String,
    },
    /// The hand did not answer the liveness probe before the run.
    #[error("the hand at {target} did not answer the liveness probe (^C, CR, expecting `{prompt}`): {why}")]
    NotAlive {
        /// The target as written.
        target: String,
        /// The prompt expected, escaped.
        prompt: String,
        /// What the probe found instead (nothing within the wait, a flood, a hang-up), for a
        /// person.
        why: String,
    },
    /// The target could not be opened.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// `results.jsonl` could not be written.
    #[error("writing results.jsonl: {0}")]
    Results(std::io::Error),
}

/// A pattern that is not a glob.
#[derive(Debug, thiserror::Error)]
#[error("bad glob `{pattern}`: {error}")]
pub struct BadGlob {
    /// The pattern as given.
    pub pattern: String,
    /// What globset refused.
    pub error: globset::Error,
}

impl BadGlob {
    fn new(pattern: &str, error: globset::Error) -> BadGlob {
        BadGlob { pattern: pattern.to_string(), error }
    }
}

/// Why a known-failures file does not load.
#[derive(Debug, thiserror::Error)]
pub enum KnownFailuresError {
    /// Not the TOML the format asks for.
    #[error(transparent)]
    Toml(#[from] toml::de::Error),
    /// A `case` pattern is not a glob.
    #[error(transparent)]
    Glob(BadGlob),
    /// The file could not be read.
    #[error("{}: {error}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What failed.
        error: std::io::Error,
    },
    /// The file's text is wrong.
    #[error("{}: {error}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        error: Box<KnownFailuresError>,
    },
}

/// One entry of a known-failures file.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KnownFailure {
    /// A glob over case ids (`rt-*`).
    pub case: String,
    /// Only for this profile, when given.
    #[serde(default)]
    pub profile: Option<String>,
    /// Why it fails (a ticket, a firmware version): shown in reports.
    pub reason: String,
    /// How it fails, as the run's root-cause grouping names it (`step 6: order at FGET (P)`,
    /// the case result's `failure`): when given, the case is excused only while it fails
    /// that way, so a new bug that breaks a listed case earlier, or otherwise, is a FAIL.
    #[serde(default)]
    pub how: Option<String>,
}

/// One decision an implementer took differently: every case resting on it is SKIP, with the
/// reason, in the manner of Wycheproof's flags.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkipDecision {
    /// The decision id (`gcl spec --profile P` lists them).
    pub id: String,
    /// Only for this profile, when given.
    #[serde(default)]
    pub profile: Option<String>,
    /// Why (what the implementation does instead).
    pub reason: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KnownFile {
    #[serde(default)]
    failure: Vec<KnownFailure>,
    #[serde(default, rename = "skip-decision")]
    skip_decision: Vec<SkipDecision>,
}

/// Known failures: data with a reason, never a silent skip. A listed case that fails is
/// XFAIL; one that passes is XPASS and fails the run, so the list cannot go stale.
#[derive(Debug, Clone, Default)]
pub struct KnownFailures {
    entries: Vec<(KnownFailure, globset::GlobMatcher)>,
    source: Option<String>,
    skip_decisions: Vec<SkipDecision>,
}

impl KnownFailures {
    /// Parses a known-failures TOML file:
    ///
    /// ```toml
    /// [[failure]]
    /// case = "rt-lft-*"
    /// profile = "bh8-262-4.4"   # optional
    /// reason = "firmware 4.4.1 sends LFT unsigned"
    /// how = "step 9: value at RealTime block (LFT)"   # optional: excused only while so
    ///
    /// [[skip-decision]]
    /// id = "framing-max-line"
    /// reason = "our lines hold 128 bytes"
    /// ```
    pub fn parse(text: &str) -> Result<KnownFailures, KnownFailuresError> {
        let f: KnownFile = toml::from_str(text)?;
        let mut entries = Vec::new();
        for k in f.failure {
            let g =
                Glob::new(&k.case).map_err(|e| KnownFailuresError::Glob(BadGlob::new(&k.case, e)))?.compile_matcher();
            entries.push((k, g));
        }
        Ok(KnownFailures { entries, source: None, skip_decisions: f.skip_decision })
    }

    /// Adds a decision whose cases are skipped (`--skip-decision ID`).
    pub fn skip_decision(&mut self, id: &str, reason: &str) {
        self.skip_decisions.push(SkipDecision { id: id.to_string(), profile: None, reason: reason.to_string() });
    }

    /// The skipped decisions that apply to a profile.
    pub fn skipped_decisions<'a>(&'a self, profile: &'a str) -> impl Iterator<Item = &'a SkipDecision> + 'a {
        self.skip_decisions.iter().filter(move |s| s.profile.as_deref().is_none_or(|p| p == profile))
    }

    /// The skipped decision a case rests on, if any.
    pub fn skipped_by<'a>(&'a self, profile: &'a str, decisions: &[String]) -> Option<&'a SkipDecision> {
        self.skipped_decisions(profile).find(|s| decisions.contains(&s.id))
    }

    /// Reads and parses a file.
    pub fn load(path: &Path) -> Result<KnownFailures, KnownFailuresError> {
        let text = gcl_host::files::read_input_text(path)
            .map_err(|error| KnownFailuresError::Read { path: path.to_path_buf(), error })?;
        let mut k = KnownFailures::parse(&text)
            .map_err(|e| KnownFailuresError::InFile { path: path.to_path_buf(), error: Box::new(e) })?;
        k.source = Some(path.display().to_string());
        Ok(k)
    }

    /// The file the list came from, when it came from one.
    pub fn source(&self) -> Option<&str> {
        self.source.as_deref()
    }

    /// The entries that apply to `profile`, each with whether it matches a case of `cases`
    /// (an entry that matches none is stale, or a typo).
    pub fn entries_for(&self, profile: &str, cases: &[Case]) -> Vec<KnownFailureEntry> {
        self.entries
            .iter()
            .filter(|(k, _)| k.profile.as_deref().is_none_or(|p| p == profile))
            .map(|(k, g)| KnownFailureEntry {
                case: k.case.clone(),
                reason: k.reason.clone(),
                matched: cases.iter().any(|c| g.is_match(c.id())),
            })
            .collect()
    }

    /// The entry that covers a case, if any.
    pub fn lookup(&self, profile: &str, id: &str) -> Option<&KnownFailure> {
        self.entries
            .iter()
            .find(|(k, g)| g.is_match(id) && k.profile.as_deref().is_none_or(|p| p == profile))
            .map(|(k, _)| k)
    }
}

/// The `--only` globs that match no case of `cases`: running them would run nothing.
pub fn unmatched_globs(cases: &[Case], patterns: &[String]) -> Result<Vec<String>, BadGlob> {
    let mut out = Vec::new();
    for p in patterns {
        let g = Glob::new(p).map_err(|e| BadGlob::new(p, e))?.compile_matcher();
        if !cases.iter().any(|c| g.is_match(c.id())) {
            out.push(p.clone());
        }
    }
    Ok(out)
}

fn globs(patterns: &[String]) -> Result<Option<GlobSet>, BadGlob> {
    if patterns.is_empty() {
        return Ok(None);
    }
    let mut b = GlobSetBuilder::new();
    for p in patterns {
        b.add(Glob::new(p).map_err(|e| BadGlob::new(p, e))?);
    }
    b.build().map(Some).map_err(|e| BadGlob::new(&patterns.join(" "), e))
}

/// Everything a run needs.
#[derive(Debug, Clone)]
pub struct ConformOptions {
    /// The hand.
    pub target: Target,
    /// How to open it.
    pub open: OpenOptions,
    /// The profile whose suite runs.
    pub profile: Arc<Profile>,
    /// Levels to run.
    pub level: LevelFilter,
    /// Run only cases whose id matches one of these globs.
    pub only: Vec<String>,
    /// Skip cases whose id matches one of these globs.
    pub skip: Vec<String>,
    /// Known failures.
    pub known: KnownFailures,
    /// A flat per-step deadline for steps without their own `within`, instead of deadlines
    /// from the model ([`crate::deadline`]).
    pub step_timeout: Option<Duration>,
    /// Requirements the operator refuses (`--no motion`): such cases are SKIP.
    pub refuse: Vec<Requirement>,
    /// Fixtures the operator declares in place (`--fixture object`): a case whose `setup:` the
    /// runner cannot make on this target runs only when its fixture is declared; the in-process
    /// `sim` makes every setup itself.
    pub fixtures: Vec<Requirement>,
    /// The line rate to compute the wire-time lower bound at (serial targets give their own).
    pub baud: Option<u32>,
    /// Keep the transcript of every case in the results, not only of failures (certificates).
    pub keep_transcripts: bool,
    /// Deadlines, early ends and the pre-flight.
    pub control: RunControl,
}

impl ConformOptions {
    /// Every case at every level against the in-process simulated hand of `profile` with
    /// `faults`, with no selection, known failures or deadlines of the caller's own.
    pub fn in_process(profile: Arc<Profile>, faults: Vec<gcl_model::Fault>) -> ConformOptions {
        ConformOptions {
            target: Target::Sim { profile: Some(profile.id.clone()) },
            open: OpenOptions { faults, ..Default::default() },
            profile,
            level: LevelFilter::All,
            only: vec![],
            skip: vec![],
            known: KnownFailures::default(),
            step_timeout: None,
            refuse: vec![],
            fixtures: vec![],
            baud: None,
            keep_transcripts: false,
            control: RunControl::default(),
        }
    }
}

/// After this many TIMEOUTs in a row the hand is probed again (`--dead-after`).
pub const DEFAULT_DEAD_AFTER: usize = 5;

/// How a run is steered: its deadlines, when it ends early, and whether it starts with the
/// framing pre-flight.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunControl {
    /// End the run after this many failing cases (`--max-failures N`; `--fail-fast` is 1); the
    /// rest are SKIP, "not run".
    pub max_failures: Option<usize>,
    /// After this many consecutive TIMEOUTs, probe the hand; when it does not answer, the rest
    /// of the cases are SKIP and the run says where the hand stopped answering (0: never).
    pub dead_after: usize,
    /// How step deadlines follow the model (default: [`DeadlinePolicy::for_target`]). Unused
    /// when [`ConformOptions::step_timeout`] gives flat deadlines.
    pub deadlines: Option<DeadlinePolicy>,
    /// Run the framing pre-flight before the first case.
    pub preflight: bool,
    /// Before a run with abort-timing cases on a hand outside this process, close the hand
    /// once and compare the time with the model's ([`crate::motion::MotionProbe`], the
    /// fuzzer's probe): a hand whose motions end at once cannot take a ^C mid-motion, so those
    /// cases are SKIP with that reason (`--assume-real-time` turns the probe off).
    pub real_time_probe: bool,
}

impl Default for RunControl {
    fn default() -> RunControl {
        RunControl {
            max_failures: None,
            dead_after: DEFAULT_DEAD_AFTER,
            deadlines: None,
            preflight: true,
            real_time_probe: true,
        }
    }
}

/// What a run produced besides its report.
pub struct RunOutput {
    /// The report.
    pub report: RunReport,
    /// The actual transcript of each case that ran (id, text), when asked for.
    pub transcripts: Vec<(String, String)>,
}

/// Selects the cases of `cases` that run, and the SKIP results of those that do not.
pub fn select<'c>(cases: &'c [Case], opts: &ConformOptions) -> Result<(Vec<&'c Case>, Vec<CaseResult>), ConformError> {
    let only = globs(&opts.only)?;
    let skip = globs(&opts.skip)?;
    let profile = opts.profile.id.as_str();
    if let Some(s) =
        opts.known.skipped_decisions(profile).find(|s| !opts.profile.decisions.iter().any(|d| d.id == s.id))
    {
        return Err(ConformError::UnknownSkipDecision { profile: profile.to_string(), id: s.id.clone() });
    }
    let mut run = Vec::new();
    let mut skipped = Vec::new();
    for c in cases {
        let h = c.header();
        let reason = if !opts.level.admits(h.level) {
            Some(format!("level {} not selected", h.level))
        } else if only.as_ref().is_some_and(|g| !g.is_match(c.id())) {
            // Not selected at all: leave it out of the report entirely.
            continue;
        } else if skip.as_ref().is_some_and(|g| g.is_match(c.id())) {
            Some("skipped by --skip".to_string())
        } else if let Some(s) = opts.known.skipped_by(profile, &c.decisions()) {
            Some(format!("rests on decision {}, decided differently: {}", s.id, s.reason))
        } else if let Some(r) = opts.refuse.iter().find(|r| c.requires(r)) {
            Some(format!("requires {r}, which was refused"))
        } else {
            missing_fixture(c, opts)
        };
        match reason {
            Some(message) => skipped.push(result_of(c, Verdict::Skip, 0.0, Some(message))),
            None => run.push(c),
        }
    }
    Ok((run, skipped))
}

/// Whether `target` makes a case's `setup:` itself: the in-process model takes the case's
/// objects; any other hand needs them put in place by hand.
pub fn places_setup(target: &Target) -> bool {
    matches!(target, Target::Sim { .. })
}

/// Why a case cannot run for want of its set-up, or `None`: a case with a `setup:` runs on a
/// target that makes it ([`places_setup`]) or when the operator declares it in place.
fn missing_fixture(c: &Case, opts: &ConformOptions) -> Option<String> {
    let h = c.header();
    if h.setup.is_empty() || places_setup(&opts.target) || opts.fixtures.contains(&Requirement::Object) {
        return None;
    }
    Some(format!(
        "needs {} in place, which gcl cannot place on {}: put it there and pass `--fixture object` (with `--only {}`: \
         the object stays in the way of every other case), or run it on `sim`",
        gcl_transcript::Setup::list(&h.setup),
        opts.target,
        c.id()
    ))
}

/// The options to open the target with for `case`: on the in-process model, its objects.
fn open_options_for(opts: &ConformOptions, case: &Case) -> gcl_host::target::OpenOptions {
    let mut o = opts.open.clone();
    let objects = case.header().objects();
    if places_setup(&opts.target) && objects.iter().any(Option::is_some) {
        let mut scenario = o.scenario.take().unwrap_or_default();
        scenario.objects = objects;
        o.scenario = Some(scenario);
    }
    o
}

fn result_of(c: &Case, verdict: Verdict, duration_ms: f64, message: Option<String>) -> CaseResult {
    let h = c.header();
    CaseResult {
        id: h.id.clone(),
        title: h.title.clone(),
        clauses: h.clauses.clone(),
        decisions: c.decisions(),
        level: h.level.to_string(),
        verdict,
        duration_ms,
        message,
        diff: None,
        failure: None,
        transcript: None,
    }
}

/// After a failing case, the hand must fall quiet within this long, or the link is reopened
/// (and after `--dead-after` such cases in a row the run ends: the hand floods).
const AFTER_FAILURE_DRAIN: Duration = Duration::from_secs(2);

/// A hand that sends more than this in answer to the liveness probe floods: it is not live.
pub const LIVENESS_MAX_BYTES: usize = 1 << 20;

/// What the liveness probe found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Alive {
    /// Two prompts came back, and the hand then fell quiet.
    Yes,
    /// Nothing came back within the wait.
    Silent,
    /// Bytes came back, but no prompts (`bytes` of them).
    NoPrompt {
        /// How many bytes came.
        bytes: usize,
    },
    /// The hand kept sending: past [`LIVENESS_MAX_BYTES`], or still sending after its prompts.
    Floods,
    /// The link closed (EOF, an exited process) this long after the probe went out.
    HungUp {
        /// Time from the probe to the hang-up.
        after: Duration,
    },
}

impl Alive {
    /// Whether the hand answered.
    pub fn is_alive(self) -> bool {
        self == Alive::Yes
    }

    /// Why a hand is not alive, for a person (empty for one that is).
    pub fn why(self, waited: Duration) -> String {
        match self {
            Alive::Yes => String::new(),
            Alive::Silent => format!("nothing came back within {waited:?}"),
            Alive::NoPrompt { bytes } => format!("{bytes} bytes came back within {waited:?}, but no prompt"),
            Alive::Floods => "it floods: it kept sending instead of answering with a prompt".to_string(),
            Alive::HungUp { after } => format!("it hung up {:.2} s after the probe", after.as_secs_f64()),
        }
    }
}

/// Sends a bare CR (after ^C) and waits for a prompt: is anybody there?
pub fn liveness(link: &mut dyn Link, profile: &Profile, timeout: Duration) -> Result<bool, LinkError> {
    probe(link, profile, timeout).map(Alive::is_alive)
}

/// [`liveness`], saying what it found: silence, a flood, a hang-up, bytes without a prompt.
pub fn probe(link: &mut dyn Link, profile: &Profile, timeout: Duration) -> Result<Alive, LinkError> {
    let t = profile.framing.terminator;
    prompts_after(link, profile, &[profile.framing.abort, t], 2, timeout)
}

/// Whether the hand answers a command line (an unknown command word, which changes nothing)
/// with a prompt: a hand that answers ^C and a bare CR but no command is not alive for a
/// suite of commands.
pub fn answers_a_command(link: &mut dyn Link, profile: &Profile, timeout: Duration) -> Result<Alive, LinkError> {
    let line = [crate::preflight::UNKNOWN, &[profile.framing.terminator]].concat();
    prompts_after(link, profile, &line, 1, timeout)
}

/// The dead-hand rule's probe: `None` when the hand answers ^C and a bare CR with prompts
/// *and* a command line with a prompt; otherwise why not, for a person. A hand that answers
/// the first probe but no command would time out case after case.
pub fn dead_hand(link: &mut dyn Link, profile: &Profile, timeout: Duration) -> Option<String> {
    match probe(link, profile, timeout) {
        Ok(Alive::Yes) => {}
        Ok(a) => return Some(format!("no answer to the liveness probe: {}", a.why(timeout))),
        Err(e) => return Some(format!("the link failed: {e}")),
    }
    match answers_a_command(link, profile, timeout) {
        Ok(Alive::Yes) => None,
        Ok(a) => Some(format!(
            "it answers ^C and a bare CR, but not a command line ({}: {})",
            gcl_model::escape::escape(crate::preflight::UNKNOWN),
            a.why(timeout)
        )),
        Err(e) => Some(format!("the link failed: {e}")),
    }
}

/// Sends `bytes` and counts prompts until `want` came, then waits for quiet.
fn prompts_after(
    link: &mut dyn Link,
    profile: &Profile,
    bytes: &[u8],
    want: usize,
    timeout: Duration,
) -> Result<Alive, LinkError> {
    // Any prompt-like answer counts: a hand with a malformed prompt is alive, and its cases
    // will say what is wrong with it.
    let prompt = profile.framing.prompt.trim_end().as_bytes().to_vec();
    let hung_up = |e: LinkError, start: Duration, link: &dyn Link| match e {
        LinkError::Disconnected => Ok(Alive::HungUp { after: link.elapsed().saturating_sub(start) }),
        e => Err(e),
    };
    let start = link.elapsed();
    if let Err(e) = link.send(bytes) {
        return hung_up(e, start, link);
    }
    // Count prompts as bytes arrive, keeping only a prompt's length of tail: a hand that
    // floods instead of answering costs time, never memory.
    let (mut seen, mut tail, mut total) = (0usize, Vec::new(), 0usize);
    let mut chunk = Vec::new();
    while seen < want && total <= LIVENESS_MAX_BYTES {
        let spent = link.elapsed().saturating_sub(start);
        if spent >= timeout {
            break;
        }
        chunk.clear();
        if let Err(e) = link.recv(&mut chunk, timeout - spent) {
            return hung_up(e, start, link);
        }
        total += chunk.len();
        tail.extend_from_slice(&chunk);
        seen += tail.windows(prompt.len().max(1)).filter(|w| *w == prompt.as_slice() || prompt.is_empty()).count();
        // Keep what could be the start of a prompt split across reads.
        let cut = tail.len().saturating_sub(prompt.len().saturating_sub(1));
        tail.drain(..cut);
    }
    if total > LIVENESS_MAX_BYTES {
        return Ok(Alive::Floods);
    }
    // Let a slow second prompt land before the first case starts.
    let settled = match discard(link, Duration::from_millis(20), timeout) {
        Ok(d) => d,
        Err(e) => return hung_up(e, start, link),
    };
    Ok(match (seen >= want, settled.quiet) {
        (true, true) => Alive::Yes,
        (_, false) => Alive::Floods,
        (false, true) if total == 0 => Alive::Silent,
        (false, true) => Alive::NoPrompt { bytes: total },
    })
}

/// Asks the hand for `VERS` and returns its lines; a hand that refuses (`ERR n`) or breaks GCL
/// gives an error, never its `ERR` line as a version.
pub fn firmware_version(
    link: &mut dyn Link,
    profile: &Profile,
    timeout: Duration,
) -> Result<Vec<String>, gcl_host::client::ClientError> {
    gcl_host::client::ask(link, gcl_host::client::core::Framing::of(profile), "VERS", timeout)
}

/// Something a run reports as it goes.
#[derive(Debug, Clone, Copy)]
pub enum RunEvent<'a> {
    /// A line about the target before the first case: the framing pre-flight's, and the
    /// motion-time probe's when the hand's motions end at once.
    Preflight(&'a str),
    /// A case ended: its result, how many results so far, and how many there will be.
    Case(&'a CaseResult, usize, usize),
    /// The run ends early; the remaining cases are SKIP (not run).
    Stopped(&'a Stopped),
}

/// Runs the selected cases. `progress` is told after each case.
pub fn run(
    cases: &[Case],
    opts: &ConformOptions,
    stream: Option<&mut ResultStream>,
    progress: &mut dyn FnMut(&CaseResult, usize, usize),
) -> Result<RunOutput, ConformError> {
    run_with_events(cases, opts, stream, &mut |e| {
        if let RunEvent::Case(r, done, total) = e {
            progress(r, done, total);
        }
    })
}

/// Opens the target for a run after the link was lost: waits for whatever a restarted hand
/// prints (its power-up banner), then probes it, so that no case is blamed for a restart.
fn reopen(opts: &ConformOptions, probe_timeout: Duration) -> Result<Box<dyn Link>, String> {
    let mut l = open(&opts.target, &opts.open).map_err(|e| format!("cannot reopen the target: {e}"))?;
    match probe(l.as_mut(), &opts.profile, probe_timeout) {
        Ok(Alive::Yes) => {}
        Ok(a) => {
            return Err(format!(
                "reopened the target, but it does not answer the liveness probe: {}",
                a.why(probe_timeout)
            ));
        }
        Err(e) => return Err(format!("reopened the target, but the link failed: {e}")),
    }
    match discard(l.as_mut(), Duration::from_millis(100), Duration::from_secs(5)) {
        Ok(d) if d.quiet => Ok(l),
        Ok(_) => Err("reopened the target, but it does not stop sending".to_string()),
        Err(e) => Err(format!("reopened the target, but the link failed: {e}")),
    }
}

/// As [`run`], telling `on` about the pre-flight, every case and an early end.
///
/// A run is select → probe → pre-flight → motion-time probe → cases → triage → report; each
/// stage is a function below.
pub fn run_with_events(
    cases: &[Case],
    opts: &ConformOptions,
    stream: Option<&mut ResultStream>,
    on: &mut dyn FnMut(RunEvent<'_>),
) -> Result<RunOutput, ConformError> {
    let clock = RunClock::start();
    let mut selection = select_stage(cases, opts)?;
    let plan = RunPlan::of(opts);
    let (mut link, found) = probe_stage(opts, &plan)?;
    let pre = preflight_stage(link.as_mut(), &found, opts, &plan, on);
    let (motion, probed) = motion_time_stage(link.as_mut(), &found, &pre, opts, &plan, &mut selection, on);
    let objects = unplaced_stage(cases, opts, &selection, on);
    let shared = alive_stage(link, found, opts, &plan)?;
    let outside = Outside::of(&pre, probed);
    let mut ran = cases_stage(selection, shared, outside, opts, &plan, stream, on)?;
    let after = after_stage(&mut ran, opts, &plan);
    let times = clock.stop();
    let triaged = triage_stage(cases, ran, &pre.clauses);
    let preflight = preflight_text(pre.line, motion.into_iter().chain(objects).collect());
    Ok(report_stage(cases, opts, &plan, times, preflight, triaged, after))
}

/// When a run started: the wall-clock second for the report, and the monotonic start.
struct RunClock {
    started_at: time::OffsetDateTime,
    wall: Instant,
}

/// When a run started and how long it took.
struct RunTimes {
    started_at: time::OffsetDateTime,
    duration_ms: f64,
}

impl RunClock {
    /// Reads both clocks at the start of a run.
    fn start() -> RunClock {
        let now = time::OffsetDateTime::now_utc();
        RunClock { started_at: now.replace_nanosecond(0).unwrap_or(now), wall: Instant::now() }
    }

    /// Reads the monotonic clock at the end of a run: gives its start and duration.
    fn stop(self) -> RunTimes {
        RunTimes { started_at: self.started_at, duration_ms: self.wall.elapsed().as_secs_f64() * 1000.0 }
    }
}

/// What a run fixes from its options before the first byte.
struct RunPlan {
    /// The target is opened afresh for every case (the in-process simulator).
    fresh_per_case: bool,
    /// How long a liveness probe waits.
    probe_timeout: Duration,
    /// How deadlines are derived.
    policy: DeadlinePolicy,
    /// The line's baud, when there is one (for deadlines and the wire-time bound).
    link_baud: Option<u32>,
    /// The replay options every case starts from.
    replay: ReplayOptions,
}

impl RunPlan {
    /// Takes the options; gives the run's target kind, probe wait, deadlines, baud and replay
    /// options.
    fn of(opts: &ConformOptions) -> RunPlan {
        let fresh_per_case = matches!(opts.target, Target::Sim { .. });
        let policy = opts.control.deadlines.unwrap_or_else(|| DeadlinePolicy::for_target(&opts.target));
        let mut replay = suite::replay_options();
        if let Some(t) = opts.step_timeout {
            replay.default_timeout = t;
        } else {
            replay.silent_wait = policy.silent_wait;
        }
        if !fresh_per_case {
            // A shared link was drained by the probe; between passing cases nothing is pending.
            replay.drain_quiet = Duration::ZERO;
            replay.trailing = Duration::from_millis(2);
        }
        RunPlan {
            fresh_per_case,
            probe_timeout: opts.step_timeout.unwrap_or(Duration::from_secs(5)).max(Duration::from_secs(2)),
            policy,
            link_baud: match &opts.target {
                Target::Serial { baud, .. } => Some(*baud),
                _ => opts.baud,
            },
            replay,
        }
    }
}

/// The cases a run will run, and the results of those it already skips.
struct Selection<'c> {
    to_run: Vec<&'c Case>,
    skipped: Vec<CaseResult>,
}

/// Select: takes the cases and options; gives the cases to run and the SKIP results of the rest.
fn select_stage<'c>(cases: &'c [Case], opts: &ConformOptions) -> Result<Selection<'c>, ConformError> {
    let (to_run, skipped) = select(cases, opts)?;
    Ok(Selection { to_run, skipped })
}

/// Probe: opens the target and sends the liveness probe; gives the link and what answered.
fn probe_stage(opts: &ConformOptions, plan: &RunPlan) -> Result<(Box<dyn Link>, Alive), ConformError> {
    let mut l = open(&opts.target, &opts.open)?;
    let found = probe(l.as_mut(), &opts.profile, plan.probe_timeout).unwrap_or(Alive::Silent);
    Ok((l, found))
}

/// What the framing pre-flight found.
#[derive(Default)]
struct PreflightFound {
    /// Its line for people, when it ran.
    line: Option<String>,
    /// The framing clauses it found broken.
    clauses: Vec<String>,
    /// Whether it left the hand after RESET at a quiet prompt.
    settled: bool,
    /// Bytes sent and received, probe by probe (for the wire-time bound).
    exchanged: Vec<(u64, u64)>,
}

/// What the run put on the line before its first case, for the wire-time bound: the
/// pre-flight's and the motion-time probe's steps, and the model's hand as the probe left the
/// fingers (the first case starts from there).
struct Outside {
    /// Bytes sent and received and the model's time beyond them, step by step.
    steps: Vec<WireStep>,
    /// The model's hand after the motion-time probe, when it ran as the model's did.
    start: Option<SimLink>,
}

impl Outside {
    /// Takes the pre-flight's exchanges and the motion-time probe's run (if it ran).
    fn of(pre: &PreflightFound, probed: Option<MotionRun>) -> Outside {
        let mut steps: Vec<WireStep> =
            pre.exchanged.iter().map(|&(put, got)| WireStep { put, got, busy_ms: 0.0 }).collect();
        let mut start = None;
        if let Some(m) = probed {
            steps.extend(m.steps);
            start = m.model;
        }
        Outside { steps, start }
    }
}

/// Pre-flight: on a live hand, when asked, runs the framing pre-flight (`on` hears its line)
/// and drains what it left pending; gives its line, clauses and whether the hand settled.
fn preflight_stage(
    link: &mut dyn Link,
    found: &Alive,
    opts: &ConformOptions,
    plan: &RunPlan,
    on: &mut dyn FnMut(RunEvent<'_>),
) -> PreflightFound {
    let mut pre = PreflightFound::default();
    if !(found.is_alive() && opts.control.preflight) {
        return pre;
    }
    if let Ok(p) = crate::preflight::run(link, &opts.profile, &plan.policy) {
        let clauses = p.clauses.clone();
        // Who the hand says it is comes first: a hand of another firmware fails wherever the
        // two differ, and nothing else would tell the user why.
        if let Some(who) = &p.identity {
            on(RunEvent::Preflight(who));
        }
        let line = p.line();
        on(RunEvent::Preflight(&line));
        let line = match &p.identity {
            Some(who) => format!("{who}\n{line}"),
            None => line,
        };
        pre = PreflightFound { line: Some(line), clauses, settled: p.settled, exchanged: p.exchanged };
    }
    // Its last answer may not have ended quietly (a flood, a missing prompt): drain.
    if !pre.settled {
        let _ = discard(link, Duration::from_millis(50), AFTER_FAILURE_DRAIN);
    }
    pre
}

/// Motion-time probe: on a live hand kept across cases with abort-timing cases selected,
/// probes its motions; when they end at once, moves those cases to SKIP. Gives the line `on`
/// heard, and what the probe put on the line (when it ran).
fn motion_time_stage(
    link: &mut dyn Link,
    found: &Alive,
    pre: &PreflightFound,
    opts: &ConformOptions,
    plan: &RunPlan,
    selection: &mut Selection<'_>,
    on: &mut dyn FnMut(RunEvent<'_>),
) -> (Option<String>, Option<MotionRun>) {
    if !(found.is_alive()
        && !plan.fresh_per_case
        && opts.control.real_time_probe
        && selection.to_run.iter().any(|c| c.requires(&Requirement::AbortTiming)))
    {
        return (None, None);
    }
    let Some(mut probed) = motion_time(link, opts, &plan.policy, plan.link_baud, pre.settled) else {
        return (None, None);
    };
    let Some(fast) = probed.fast.take() else {
        return (None, Some(probed));
    };
    let line = format!(
        "motion-time probe: {fast}; ^C cannot land mid-motion on it, so the abort-timing cases are SKIP \
         (as with `--no abort-timing`; `--assume-real-time` runs them)"
    );
    on(RunEvent::Preflight(&line));
    let reason = format!("requires abort-timing, which the target lacks: {fast}");
    let skipped = &mut selection.skipped;
    selection.to_run.retain(|c| {
        let timing = c.requires(&Requirement::AbortTiming);
        if timing {
            skipped.push(result_of(c, Verdict::Skip, 0.0, Some(reason.clone())));
        }
        !timing
    });
    (Some(line), Some(probed))
}

/// Takes the selection; gives one line (also told to `on`) for the cases whose object gcl
/// cannot place here (each SKIP says so too), or `None`.
fn unplaced_stage(
    cases: &[Case],
    opts: &ConformOptions,
    selection: &Selection<'_>,
    on: &mut dyn FnMut(RunEvent<'_>),
) -> Option<String> {
    let unplaced: Vec<&str> = cases
        .iter()
        .filter(|c| missing_fixture(c, opts).is_some() && selection.skipped.iter().any(|r| r.id == c.id()))
        .map(|c| c.id())
        .collect();
    if unplaced.is_empty() {
        return None;
    }
    let line = format!(
        "objects: {} need an object in the fingers' way, which gcl cannot place on this target, so they are \
         SKIP (`--fixture object` runs them with the object in place: one at a time, with `--only`)",
        unplaced.join(", ")
    );
    on(RunEvent::Preflight(&line));
    Some(line)
}

/// Takes the probed link and what answered: ends the run when the hand is not alive, else
/// gives the link to keep across cases (none when each case opens the target afresh).
fn alive_stage(
    link: Box<dyn Link>,
    found: Alive,
    opts: &ConformOptions,
    plan: &RunPlan,
) -> Result<Option<Box<dyn Link>>, ConformError> {
    let shared = if plan.fresh_per_case { None } else { Some(link) };
    if !found.is_alive() {
        return Err(ConformError::NotAlive {
            target: opts.target.to_string(),
            prompt: gcl_model::escape::escape(opts.profile.framing.prompt.as_bytes()),
            why: found.why(plan.probe_timeout),
        });
    }
    Ok(shared)
}

/// What the cases stage gave.
struct CasesRun {
    /// Every result, skipped ones first, in the order `on` heard them.
    results: Vec<CaseResult>,
    /// The failures' signatures, for triage.
    signatures: Vec<crate::triage::Failure>,
    /// The actual transcripts kept (id, text).
    transcripts: Vec<(String, String)>,
    /// What each counted case exchanged, for the wire-time bound.
    wire_cases: Vec<WireCase>,
    /// How the run ended early, if it did.
    stopped: Option<Stopped>,
    /// The link still open after the last case, if any.
    shared: Option<Box<dyn Link>>,
    /// What the run put on the line before the first case, for the wire-time bound.
    before: Outside,
}

/// Cases: takes the selection, the probed link and what went on the line before the first
/// case; runs every case in order (SKIP after an early end), streaming and telling `on` each
/// result; gives what they gave.
fn cases_stage(
    selection: Selection<'_>,
    shared: Option<Box<dyn Link>>,
    before: Outside,
    opts: &ConformOptions,
    plan: &RunPlan,
    stream: Option<&mut ResultStream>,
    on: &mut dyn FnMut(RunEvent<'_>),
) -> Result<CasesRun, ConformError> {
    let total = selection.to_run.len() + selection.skipped.len();
    // The first case follows the probes and the pre-flight: the bound starts it from the
    // model's hand as the motion-time probe left it, or (no probe) a freshly powered-up one,
    // as after the pre-flight's RESET.
    let hand_carries = before.start.is_some();
    let mut run = CaseLoop {
        opts,
        plan,
        stream,
        total,
        run: CasesRun {
            results: Vec::with_capacity(total),
            signatures: Vec::new(),
            transcripts: Vec::new(),
            wire_cases: Vec::new(),
            stopped: None,
            shared,
            before,
        },
        failures: 0,
        timeouts_in_a_row: 0,
        first_timeout: String::new(),
        unquiet_in_a_row: 0,
        first_unquiet: String::new(),
        hand_carries,
    };
    for r in selection.skipped {
        run.emit(r, on)?;
    }
    for case in selection.to_run {
        run.case(case, on)?;
    }
    Ok(run.run)
}

/// The cases stage as it goes: what it gathered and the counters that end a run early.
struct CaseLoop<'o, 's> {
    opts: &'o ConformOptions,
    plan: &'o RunPlan,
    stream: Option<&'s mut ResultStream>,
    /// How many results there will be.
    total: usize,
    run: CasesRun,
    failures: usize,
    timeouts_in_a_row: usize,
    first_timeout: String,
    unquiet_in_a_row: usize,
    first_unquiet: String,
    /// Whether the next case finds the hand where the case before left it.
    hand_carries: bool,
}

impl CaseLoop<'_, '_> {
    /// Takes a result: streams it, tells `on`, and keeps it.
    fn emit(&mut self, r: CaseResult, on: &mut dyn FnMut(RunEvent<'_>)) -> Result<(), ConformError> {
        if let Some(s) = self.stream.as_deref_mut() {
            s.push(&r).map_err(ConformError::Results)?;
        }
        on(RunEvent::Case(&r, self.run.results.len() + 1, self.total));
        self.run.results.push(r);
        Ok(())
    }

    /// Takes one case: runs it (or SKIPs it after an early end), judges it, reports it, and
    /// decides whether the run ends there.
    fn case(&mut self, case: &Case, on: &mut dyn FnMut(RunEvent<'_>)) -> Result<(), ConformError> {
        if let Some(st) = &self.run.stopped {
            let r = result_of(case, Verdict::Skip, 0.0, Some(format!("not run: {}", st.message)));
            return self.emit(r, on);
        }
        let t0 = Instant::now();
        // Whether the hand starts this case where the case before left it (for the bound).
        let carried = self.hand_carries && self.run.shared.is_some();
        if !self.link_for(case, on)? {
            return Ok(());
        }
        let outcome = self.replay(case);
        let ms = t0.elapsed().as_secs_f64() * 1000.0;
        self.count_wire(case, &outcome, carried);
        // The next case finds the hand where this one left it only when this one passed on
        // a link that is kept (a failing case is drained, maybe reopened; a timed-out one
        // may have left the hand anywhere).
        self.hand_carries = !self.plan.fresh_per_case && outcome.is_pass();
        let (mut r, flooded) = judged(case, &outcome, ms);
        if matches!(outcome, ReplayOutcome::Disconnected(_)) {
            self.run.shared = None;
        }
        self.timeouts_in_a_row = if r.verdict == Verdict::Timeout { self.timeouts_in_a_row + 1 } else { 0 };
        if self.timeouts_in_a_row == 1 {
            self.first_timeout = case.id().to_string();
        }
        self.triage_case(case, &outcome, &mut r);
        known_verdict(&mut r, self.opts.known.lookup(&case.profile, case.id()));
        self.keep_transcript(case, &outcome, &mut r);
        self.drain_after(case, &outcome, flooded);
        if outcome.is_pass() {
            self.unquiet_in_a_row = 0;
        }
        if r.verdict.fails_run() {
            self.failures += 1;
        }
        let id = r.id.clone();
        self.emit(r, on)?;
        self.run.stopped = self.stop_after(id);
        if let Some(st) = &self.run.stopped {
            on(RunEvent::Stopped(st));
        }
        Ok(())
    }

    /// Takes the case about to run: opens the target for it (afresh per case, or reopened
    /// after a lost link). Gives `false` when the hand vanished for good: the case is ERROR
    /// and the run stops, both reported.
    fn link_for(&mut self, case: &Case, on: &mut dyn FnMut(RunEvent<'_>)) -> Result<bool, ConformError> {
        if self.plan.fresh_per_case {
            self.run.shared = Some(open(&self.opts.target, &open_options_for(self.opts, case))?);
            return Ok(true);
        }
        if self.run.shared.is_some() {
            return Ok(true);
        }
        match reopen(self.opts, self.plan.probe_timeout) {
            Ok(l) => {
                self.run.shared = Some(l);
                Ok(true)
            }
            Err(e) => {
                // The link failed and the hand does not come back: the run ends there, an
                // infrastructure error, not a verdict on any clause.
                let message = format!("the hand vanished before case {} and could not be reopened: {e}", case.id());
                self.emit(result_of(case, Verdict::Error, 0.0, Some(e)), on)?;
                let st = Stopped { cause: StopCause::DeadHand, case: case.id().to_string(), message };
                on(RunEvent::Stopped(&st));
                self.run.stopped = Some(st);
                self.failures += 1;
                Ok(false)
            }
        }
    }

    /// Takes a case whose link is open: replays it with its own deadlines; gives the outcome.
    fn replay(&mut self, case: &Case) -> ReplayOutcome {
        let mut case_opts = self.plan.replay.clone();
        // The in-process model's time is simulated: waiting costs nothing there, so it keeps
        // the goldens' deadlines and the suite's in-process speed.
        if self.opts.step_timeout.is_none()
            && !self.plan.fresh_per_case
            && let Some(pred) = crate::deadline::predict(case, &self.opts.profile)
        {
            case_opts.budgets =
                crate::deadline::budgets(&self.opts.profile, case, &pred, &self.plan.policy, self.plan.link_baud);
        }
        let link = self.run.shared.as_deref_mut().expect("link_for opened one");
        suite::run_case(case, link, &case_opts)
    }

    /// Takes a case's outcome: counts its bytes for the wire-time bound when it ran to its
    /// end or to a mismatch (a TIMEOUT's wait and an ERROR's reconnect are not line time).
    fn count_wire(&mut self, case: &Case, outcome: &ReplayOutcome, carried: bool) {
        if matches!(outcome, ReplayOutcome::Pass(_) | ReplayOutcome::Mismatch(_)) {
            self.run.wire_cases.push(WireCase {
                id: case.id().to_string(),
                steps: outcome.exchange().iter().map(|e| (e.sent.len() as u64, e.received.len() as u64)).collect(),
                passed: matches!(outcome, ReplayOutcome::Pass(_)),
                carried,
            });
        }
    }

    /// Takes a judged case: signs its failure for triage (`r.failure`, and one more signature).
    fn triage_case(&mut self, case: &Case, outcome: &ReplayOutcome, r: &mut CaseResult) {
        if let Some((signature, hint)) =
            crate::triage::signature(case, outcome, &self.opts.profile, self.plan.fresh_per_case)
        {
            let step = outcome.failed_step().unwrap_or(0);
            r.failure = Some(format!("step {}: {}", step + 1, signature.key));
            let result = self.run.results.len();
            self.run.signatures.push(crate::triage::Failure { result, step, signature, hint });
        }
    }

    /// Takes a judged case: keeps its actual transcript in the result when it failed or is a
    /// RealTime case (the report plots its blocks), and in the run's when asked.
    fn keep_transcript(&mut self, case: &Case, outcome: &ReplayOutcome, r: &mut CaseResult) {
        let realtime =
            case.transcript.steps.iter().any(|s| s.expect.segments.first().is_some_and(|g| g.form == Form::Hex));
        if r.verdict != Verdict::Pass || self.opts.keep_transcripts || realtime {
            let text = actual_transcript(&case.transcript, outcome.exchange()).to_text();
            if self.opts.keep_transcripts {
                self.run.transcripts.push((case.id().to_string(), text.clone()));
            }
            if r.verdict != Verdict::Pass || realtime {
                r.transcript = Some(truncate_note(&text, MAX_SHOWN * 4));
            }
        }
    }

    /// Takes a case that did not pass on a kept link: drains what it left pending, so it is
    /// not blamed on the next case; a hand that does not stop sending is reopened (and counted).
    fn drain_after(&mut self, case: &Case, outcome: &ReplayOutcome, flooded: bool) {
        // Drained by how the case ended, not by its verdict: a known failure (XFAIL) stopped
        // reading mid-answer as a FAIL does, and leaves the link as a FAIL would.
        if outcome.is_pass() || self.plan.fresh_per_case {
            return;
        }
        let Some(l) = self.run.shared.as_deref_mut() else {
            return;
        };
        // A timed-out step has just waited through a quiet spell; others wait for one.
        let quiet = Duration::from_millis(match outcome {
            _ if flooded => 100,
            ReplayOutcome::Timeout(_) => 20,
            _ => 50,
        });
        match discard(l, quiet, AFTER_FAILURE_DRAIN) {
            Ok(d) if d.quiet => {}
            Ok(_) => {
                self.run.shared = None;
                self.unquiet_in_a_row += 1;
                if self.unquiet_in_a_row == 1 {
                    self.first_unquiet = case.id().to_string();
                }
            }
            Err(_) => self.run.shared = None,
        }
    }

    /// Takes the id of the case just reported: gives why the run stops there (too many
    /// failures, a flood, a dead hand), or `None`.
    fn stop_after(&mut self, id: String) -> Option<Stopped> {
        let control = &self.opts.control;
        if let Some(max) = control.max_failures
            && self.failures >= max
        {
            let failures = self.failures;
            let message = format!(
                "stopped after {failures} failing case{} (--max-failures {max}) at case {id}",
                if failures == 1 { "" } else { "s" }
            );
            return Some(Stopped { cause: StopCause::MaxFailures, case: id, message });
        }
        if control.dead_after > 0 && self.unquiet_in_a_row >= control.dead_after {
            let at = std::mem::take(&mut self.first_unquiet);
            let message = format!(
                "the hand floods: it did not stop sending after {} failing cases in a row, from case {at}",
                control.dead_after
            );
            return Some(Stopped { cause: StopCause::Flooding, case: at, message });
        }
        if control.dead_after > 0 && self.timeouts_in_a_row >= control.dead_after {
            self.timeouts_in_a_row = 0;
            let why = self.dead_after_timeouts()?;
            let at = std::mem::take(&mut self.first_timeout);
            let message = format!(
                "the hand stopped answering at case {at} ({} timeouts in a row from there, then {why})",
                control.dead_after
            );
            return Some(Stopped { cause: StopCause::DeadHand, case: at, message });
        }
        None
    }

    /// After timeouts in a row: asks the hand (on the kept link, or reopened) to answer a
    /// command line; gives why it is dead, or `None` when it answers.
    fn dead_after_timeouts(&mut self) -> Option<String> {
        // The probe of ^C and a bare CR is not enough: a hand that answers those and no
        // command would time out case after case. It must answer a command line too.
        let (opts, probe_timeout) = (self.opts, self.plan.probe_timeout);
        let answers = |l: &mut dyn Link| match dead_hand(l, &opts.profile, probe_timeout) {
            Some(why) => Err(why),
            None => Ok(()),
        };
        match self.run.shared.as_deref_mut() {
            Some(l) if !self.plan.fresh_per_case => answers(l).err(),
            _ => match reopen(opts, probe_timeout) {
                Ok(mut l) => {
                    let dead = answers(l.as_mut()).err();
                    if !self.plan.fresh_per_case {
                        self.run.shared = Some(l);
                    }
                    dead
                }
                Err(e) => Some(e),
            },
        }
    }
}

/// Takes a case's replay outcome and time; gives its result as the wire judged it (verdict,
/// message, diff) and whether the hand flooded.
fn judged(case: &Case, outcome: &ReplayOutcome, ms: f64) -> (CaseResult, bool) {
    let mut r = result_of(case, Verdict::Pass, ms, None);
    let mut flooded = false;
    match outcome {
        ReplayOutcome::Pass(_) => {}
        ReplayOutcome::Mismatch(m) => {
            r.verdict = Verdict::Fail;
            r.message = Some(outcome.summary());
            let got = m.exchange.last().map(|e| e.received.as_slice()).unwrap_or_default();
            r.diff = Some(diff_of(m.step, m.offset, &m.expected, &m.actual, got, m.form, &golden_of(case, m.step)));
        }
        ReplayOutcome::Timeout(t) => {
            r.verdict = Verdict::Timeout;
            r.message = Some(outcome.summary());
            let got = t.exchange.last().map(|e| e.received.as_slice()).unwrap_or_default();
            r.diff = Some(diff_of(t.step, t.offset, &t.expected, "", got, t.form, &golden_of(case, t.step)));
        }
        ReplayOutcome::Flooded(f) => {
            r.verdict = Verdict::Fail;
            r.message = Some(outcome.summary());
            let got = f.exchange.last().map(|e| e.received.as_slice()).unwrap_or_default();
            let actual = gcl_transcript::escape_text(got);
            let golden = golden_of(case, f.step);
            r.diff = Some(diff_of(f.step, 0, &golden, &actual, &[], Form::Text, &golden));
            flooded = true;
        }
        ReplayOutcome::Disconnected(_) => {
            r.verdict = Verdict::Error;
            r.message = Some(outcome.summary());
        }
    }
    (r, flooded)
}

/// Takes a judged result and its entry in the known-failures list, if any: a listed case
/// becomes XFAIL (or XPASS when it passes), unless it fails otherwise than listed.
fn known_verdict(r: &mut CaseResult, known: Option<&KnownFailure>) {
    if let Some(k) = known.filter(|k| r.verdict != Verdict::Pass && k.how.is_some() && k.how != r.failure) {
        // Listed, but failing otherwise than listed: what is new is a failure.
        let now = r.failure.as_deref().unwrap_or(r.verdict.as_str());
        let was = r.message.take().map(|m| format!(" ({m})")).unwrap_or_default();
        r.message = Some(format!(
            "fails otherwise than its known failure: known `{}`, now `{now}`{was}",
            k.how.as_deref().unwrap_or_default()
        ));
    } else if let Some(k) = known {
        r.verdict = match r.verdict {
            Verdict::Pass => Verdict::Xpass,
            _ => Verdict::Xfail,
        };
        let was = r.message.take().map(|m| format!(" ({m})")).unwrap_or_default();
        r.message = Some(match r.verdict {
            Verdict::Xpass => {
                format!("listed as a known failure ({}), but it passes: remove it from the list", k.reason)
            }
            _ => format!("known failure: {}{was}", k.reason),
        });
    }
}

/// Takes the cases' end: gives whether the hand still answers the liveness probe (never after
/// a flood or a dead hand), on the kept link or a fresh one.
fn after_stage(ran: &mut CasesRun, opts: &ConformOptions, plan: &RunPlan) -> bool {
    match (&ran.stopped, ran.shared.as_deref_mut()) {
        (Some(s), _) if s.cause != StopCause::MaxFailures => false,
        (_, Some(l)) if !plan.fresh_per_case => liveness(l, &opts.profile, plan.probe_timeout).unwrap_or(false),
        _ => match open(&opts.target, &opts.open) {
            Ok(mut l) => liveness(l.as_mut(), &opts.profile, plan.probe_timeout).unwrap_or(false),
            Err(_) => false,
        },
    }
}

/// The cases' results with their failures grouped by likely root cause.
struct Triaged {
    ran: CasesRun,
    groups: Vec<crate::report::FailureGroup>,
}

/// Triage: takes the cases' results and the pre-flight's framing clauses; gives the failure
/// groups beside them.
fn triage_stage(cases: &[Case], ran: CasesRun, framing_clauses: &[String]) -> Triaged {
    let groups = crate::triage::group(cases, &ran.results, &ran.signatures, framing_clauses);
    Triaged { ran, groups }
}

/// Takes the pre-flight's line and the notes after it; gives the report's pre-flight text.
fn preflight_text(line: Option<String>, notes: Vec<String>) -> Option<String> {
    match (line, notes.is_empty()) {
        (Some(p), false) => Some(format!("{p}\n{}", notes.join("\n"))),
        (None, false) => Some(notes.join("\n")),
        (p, true) => p,
    }
}

/// Report: takes everything the stages gave; gives the run's output (report with its
/// wire-time bound and tally, and the kept transcripts).
fn report_stage(
    cases: &[Case],
    opts: &ConformOptions,
    plan: &RunPlan,
    times: RunTimes,
    preflight: Option<String>,
    triaged: Triaged,
    after: bool,
) -> RunOutput {
    let Triaged { mut ran, groups } = triaged;
    let before = std::mem::replace(&mut ran.before, Outside { steps: Vec::new(), start: None });
    let wire = plan
        .link_baud
        .map(|baud| wire_time(cases, &ran.wire_cases, before, opts, plan.replay.trailing, baud, times.duration_ms));
    let mut report = RunReport {
        kind: crate::report::ReportKind::Conform,
        host: None,
        verdict: String::new(),
        profile_spec: None,
        certificate: None,
        format: REPORT_FORMAT,
        tool: format!("gcl {}", env!("CARGO_PKG_VERSION")),
        target: opts.target.to_string(),
        profile: opts.profile.id.clone(),
        level: opts.level.as_str().to_string(),
        started: times.started_at.format(&time::format_description::well_known::Rfc3339).unwrap_or_default(),
        duration_ms: times.duration_ms,
        suite_hash: suite::suite_hash(cases),
        liveness: Liveness { before: true, after },
        options: run_options(cases, opts),
        preflight,
        stopped: ran.stopped,
        groups,
        wire,
        summary: Default::default(),
        clauses: Vec::new(),
        cases: ran.results,
    };
    report.tally();
    RunOutput { report, transcripts: ran.transcripts }
}

/// What the motion-time probe found and put on the line.
struct MotionRun {
    /// How the target's motion fell short of the model's, or `None` (it moves in real time,
    /// or the probe decided nothing).
    fast: Option<crate::motion::NotRealTime>,
    /// Its steps for the wire-time bound, the closing ^C's answer last: bytes both ways and
    /// the model's time beyond them (the close stopped at the judgement: the time it was
    /// watched for; bytes only on a hand that does not move in real time or failed the probe).
    steps: Vec<WireStep>,
    /// The model's hand after the same probe, stopped at the same moment, when the probe ran
    /// on the hand as on the model: where the first case finds the fingers.
    model: Option<SimLink>,
}

/// Runs the motion-time probe on `link` with the run's deadlines; says what it found and put
/// on the line (`None` when the profile has no probe). `after_reset`: the hand has just
/// answered RESET at a quiet prompt (the pre-flight's last probe), so the probe's own ^C and
/// RESET are left out.
fn motion_time(
    link: &mut dyn Link,
    opts: &ConformOptions,
    policy: &DeadlinePolicy,
    baud: Option<u32>,
    after_reset: bool,
) -> Option<MotionRun> {
    let probe = crate::motion::MotionProbe::new(&opts.profile)?;
    let probe = match after_reset {
        true => probe.after_reset(&opts.profile).unwrap_or(probe),
        false => probe,
    };
    let case = Case { profile: opts.profile.id.clone(), transcript: probe.transcript.clone() };
    let mut ro = suite::replay_options();
    let pred = crate::deadline::predict(&case, &opts.profile);
    if let Some(pred) = &pred {
        ro.budgets = crate::deadline::budgets(&opts.profile, &case, pred, policy, baud);
    }
    ro.silent_wait = policy.silent_wait;
    // The line was found quiet just before (the liveness probe's settling, the pre-flight's
    // quiet after its last prompt, or its drain): what is pending is taken, without a wait.
    ro.drain_quiet = Duration::ZERO;
    // The close is judged as soon as the judgement is made: a hand still moving at a quarter
    // of the model's time moves in real time, and is stopped there (^C) rather than left to
    // close, which the first case's homing would then undo at the same cost again.
    let decided = probe.decided_after(&opts.profile);
    if let Some((step, after)) = decided
        && let Some(b) = ro.budgets.get_mut(step)
    {
        b.deadline = after;
    }
    let abort = [opts.profile.framing.abort];
    // Stopped at the judgement: the hand is still moving and gets a ^C.
    let stopped =
        |out: &ReplayOutcome| matches!((out, decided), (ReplayOutcome::Timeout(t), Some((step, _))) if t.step == step);
    let out = replay(&probe.transcript, link, &ro);
    if stopped(&out) {
        let _ = link.send(&abort);
    }
    let drained = discard(link, Duration::from_millis(50), AFTER_FAILURE_DRAIN).map_or(0, |d| d.bytes);
    let fast = probe.judge(&opts.profile, &out);
    // The model's time counts only for a probe that ran as the model's does on a hand that
    // moves in real time (else bytes only, as for a failing case).
    let modelled = fast.is_none() && (out.is_pass() || stopped(&out));
    let mut steps: Vec<WireStep> = out
        .exchange()
        .iter()
        .map(|e| {
            let cut = decided.filter(|&(step, _)| stopped(&out) && step == e.step).map(|(_, after)| after);
            let busy = match (modelled, cut) {
                (false, _) => Duration::ZERO,
                (true, Some(after)) => after,
                (true, None) => pred.as_ref().and_then(|p| p.get(e.step)).map_or(Duration::ZERO, |p| p.busy()),
            };
            WireStep { put: e.sent.len() as u64, got: e.received.len() as u64, busy_ms: busy.as_secs_f64() * 1000.0 }
        })
        .collect();
    if stopped(&out) {
        steps.push(WireStep { put: 1, got: drained, busy_ms: 0.0 });
    }
    // The same probe on the model, stopped where the hand was: the fingers the first case
    // finds. Only when the hand's run went as the model's does (else the first case's bound
    // starts from a freshly powered-up model, which moves no more than any hand).
    let mut model = SimLink::new(opts.profile.clone(), suite::model_config(case.header()));
    let model_out = replay(&probe.transcript, &mut model, &ro);
    let same = modelled && model_out.failed_step() == out.failed_step();
    if stopped(&model_out) {
        let _ = model.send(&abort);
    }
    let model = (same && discard(&mut model, Duration::from_millis(50), AFTER_FAILURE_DRAIN).is_ok_and(|d| d.quiet))
        .then_some(model);
    Some(MotionRun { fast, steps, model })
}

/// What of `opts` changed what ran, for the report. The suite's source and `--partial` are
/// the command line's to add.
pub fn run_options(cases: &[Case], opts: &ConformOptions) -> RunOptions {
    RunOptions {
        only: opts.only.clone(),
        skip: opts.skip.clone(),
        refused: opts.refuse.iter().map(|r| r.as_str().to_string()).collect(),
        fixtures: opts.fixtures.iter().map(|r| r.as_str().to_string()).collect(),
        faults: opts.open.faults.iter().map(|f| f.to_string()).collect(),
        seed: matches!(opts.target, Target::Sim { .. }).then_some(opts.open.seed),
        suite_dir: None,
        step_timeout_ms: opts.step_timeout.map(|t| u64::try_from(t.as_millis()).unwrap_or(u64::MAX)),
        known_failures_file: opts.known.source().map(str::to_string),
        known_failures: opts.known.entries_for(&opts.profile.id, cases),
        skip_decisions: opts.known.skipped_decisions(&opts.profile.id).map(|d| d.id.clone()).collect(),
        partial: false,
    }
}

/// A step's whole golden expectation in the form of a diff's `expected` and `actual`: escaped
/// text or hex tokens, elisions in braces, no quotes.
fn golden_of(case: &Case, step: usize) -> String {
    case.transcript
        .steps
        .get(step)
        .map(|s| gcl_transcript::matcher::Matcher::new(&s.expect).expected_rest())
        .unwrap_or_default()
}

/// A report's diff: 1-based step, the agreed answer before the parting byte for context, the
/// golden, and long actuals cut with a note.
fn diff_of(step: usize, offset: usize, expected: &str, actual: &str, got: &[u8], form: Form, golden: &str) -> Diff {
    let offset_c = offset.min(got.len());
    let from = offset_c.saturating_sub(CONTEXT_CHARS);
    let before = match form {
        Form::Text => gcl_transcript::escape_text(&got[from..offset_c]),
        Form::Hex => gcl_transcript::matcher::show(&got[from..offset_c], Form::Hex),
    };
    Diff {
        step: step + 1,
        offset,
        expected: truncate_note(expected, MAX_SHOWN),
        actual: truncate_note(actual, MAX_SHOWN),
        before,
        golden: truncate_note(golden, MAX_SHOWN),
        form: Some(form.into()),
    }
}

/// One step on the line, for the wire-time bound: bytes sent and received, and the model's
/// time on it beyond its bytes (motion, a reset).
#[derive(Debug, Clone, Copy)]
struct WireStep {
    put: u64,
    got: u64,
    busy_ms: f64,
}

/// The least time `steps` take on the line, one after the other (GCL is command-then-answer),
/// the bound's one rule: per step the larger of its received bytes, plus one where it sent any
/// (no answer starts before the first byte has crossed), and the model's time beyond its bytes;
/// and over the steps at least their bytes sent.
fn steps_bound_ms(steps: &[WireStep], per_byte_ms: f64) -> f64 {
    let sent: u64 = steps.iter().map(|w| w.put).sum();
    let each: f64 = steps
        .iter()
        .map(|w| {
            let first = u64::from(w.put > 0 && w.got > 0);
            f64::max((w.got + first) as f64 * per_byte_ms, w.busy_ms)
        })
        .sum();
    f64::max(sent as f64 * per_byte_ms, each)
}

/// What one case exchanged, for the wire-time bound.
struct WireCase {
    id: String,
    /// Bytes sent and received, step by step.
    steps: Vec<(u64, u64)>,
    passed: bool,
    /// Whether the case began where the case before it, a passing one on the same link, left
    /// the hand (its fingers where that case put them).
    carried: bool,
}

/// The wire-time lower bound, by construction: a sum over the cases that ran to their end
/// or to a mismatch of what each one cannot take less than.
///
/// GCL is command-then-answer: a step's command goes out only once the answer before it is
/// complete (and after the step's pause), so steps never overlap, and a case takes at least
/// the sum of its pauses and its steps. Within a step the line is full duplex and the hand
/// echoes each character as it arrives, so the bytes one way overlap those the other way:
/// a step's answer takes at least its received bytes × 10 bits / baud (never sent +
/// received), plus one byte's time when the step sent bytes (the hand cannot answer, nor
/// echo, a byte before it has crossed), and at least the time the reference model spends on
/// it beyond its bytes
/// (motion, a reset), the larger of the two, since a hand may talk while it moves. A case
/// also takes at least its sent bytes (a step's answer may end before all of its bytes
/// crossed, as when a queue is sent behind a motion, so they are counted over the case).
///
/// The model's time is its own run of the case. On a kept link a case begins where the
/// passing case before it left the hand (a homing step after a close moves the fingers all
/// the way back), so the model runs those cases in order on one hand; the first case begins
/// where the motion-time probe left the fingers (the model ran the same probe and stopped it
/// at the same step: `outside.start`); a case after anything else (the first when no probe
/// ran, one after a failure or a reopened link, every case of a target opened afresh per
/// case) starts from a freshly powered-up model, which moves no more than any hand. A failing
/// case counts its bytes only.
///
/// The run's wall time is the whole run, its probes included, so what it puts on the line
/// outside the cases is counted too, by the same rule (`outside.steps`, reported as
/// `probes_ms`): the framing pre-flight's exchanges (bytes only: the model's time on RESET is
/// left out) and the motion-time probe's steps, its close for as long as it is watched before
/// the judgement and the ^C that stops it. The liveness probes, the waits for quiet and the
/// trailing waits after cases are not line time and are not counted.
fn wire_time(
    cases: &[Case],
    counted: &[WireCase],
    outside: Outside,
    opts: &ConformOptions,
    between: Duration,
    baud: u32,
    actual_ms: f64,
) -> WireTime {
    let per_byte_ms = 10.0 / f64::from(baud.max(1)) * 1000.0;
    // What the run put on the line before its first case, by the same rule as a case's steps.
    let probes_ms = steps_bound_ms(&outside.steps, per_byte_ms);
    let (mut motion_ms, mut lower_bound_ms) = (0.0, probes_ms);
    let (mut sent, mut received) = (0u64, 0u64);
    let fresh = |c: &Case| SimLink::new(opts.profile.clone(), suite::model_config(c.header()));
    // The model's hand as the last passing case (or, before the first, the motion-time probe)
    // left it.
    let mut model: Option<SimLink> = outside.start;
    // No quiet-time drain: it is the runner's; the trailing wait between cases passes on the
    // model's clock as on the line.
    let quiet = ReplayOptions { trailing: between, drain_quiet: Duration::ZERO, ..suite::replay_options() };
    for w in counted {
        let (s, r) = w.steps.iter().fold((0u64, 0u64), |(s, r), &(a, b)| (s + a, r + b));
        sent += s;
        received += r;
        let bytes_ms = s.max(r) as f64 * per_byte_ms;
        let carried = model.take().filter(|_| w.carried);
        let case = cases.iter().find(|c| c.id() == w.id).filter(|_| w.passed);
        let Some(case) = case else {
            lower_bound_ms += bytes_ms;
            continue;
        };
        // A case with a setup starts from a fresh model with its objects (the one before had
        // none).
        let carried = carried.filter(|_| case.header().setup.is_empty());
        let mut link = carried.unwrap_or_else(|| fresh(case));
        let mut rate = link.device().baud();
        let mut outcome = suite::run_case(case, &mut link, &quiet);
        if !outcome.is_pass() {
            // Not from the state the case before left: the suite's cases pass from power-up.
            link = fresh(case);
            rate = link.device().baud();
            outcome = suite::run_case(case, &mut link, &quiet);
        }
        let steps = outcome.exchange();
        if !outcome.is_pass() || steps.len() != w.steps.len() {
            lower_bound_ms += bytes_ms;
            continue;
        }
        // The model's bytes at its own BAUD; where a case changes it, the slower rate's
        // longer byte time is taken, so that motion is never overcounted.
        let model_byte = byte_time(rate.min(link.device().baud()));
        let mut pauses_ms = 0.0;
        let mut on_line = Vec::with_capacity(steps.len());
        for (e, &(put, got)) in steps.iter().zip(&w.steps) {
            pauses_ms +=
                case.transcript.steps.get(e.step).and_then(|st| st.pause).unwrap_or_default().as_secs_f64() * 1000.0;
            let wire_at_model = model_byte * u32::try_from(e.sent.len() + e.received.len()).unwrap_or(u32::MAX);
            let busy_ms = e.took.saturating_sub(wire_at_model).as_secs_f64() * 1000.0;
            on_line.push(WireStep { put, got, busy_ms });
        }
        motion_ms += pauses_ms + on_line.iter().map(|w| w.busy_ms).sum::<f64>();
        lower_bound_ms += pauses_ms + steps_bound_ms(&on_line, per_byte_ms);
        model = Some(link);
    }
    WireTime {
        bytes_sent: sent,
        bytes_received: received,
        baud,
        motion_ms,
        lower_bound_ms,
        counted_cases: counted.len(),
        probes_ms,
        actual_ms,
        ratio: if lower_bound_ms > 0.0 { actual_ms / lower_bound_ms } else { 0.0 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_failures_match_globs_and_profiles() {
        let k = KnownFailures::parse(
            "[[failure]]\ncase = \"rt-*\"\nprofile = \"seed\"\nreason = \"ticket 7\"\n\n[[failure]]\ncase = \"echo\"\nreason = \"x\"\n",
        )
        .unwrap();
        assert_eq!(k.lookup("seed", "rt-lfap").map(|f| f.reason.as_str()), Some("ticket 7"));
        assert!(k.lookup("bh8-262-4.4", "rt-lfap").is_none());
        assert!(k.lookup("bh8-262-4.4", "echo").is_some());
        assert!(KnownFailures::parse("[[failure]]\ncase = \"x\"\n").is_err(), "a reason is required");
        assert!(KnownFailures::parse("[[failure]]\ncase = \"[\"\nreason = \"r\"\n").is_err());
    }

    /// The wire-time bound of cases run one after the other on the in-process model, each
    /// marked as carried over from the one before or not.
    fn bound_of(ids: &[(&str, bool)]) -> WireTime {
        bound_after(ids, Outside { steps: Vec::new(), start: None })
    }

    /// [`bound_of`], after what the run put on the line before its first case.
    fn bound_after(ids: &[(&str, bool)], outside: Outside) -> WireTime {
        let p = Profile::builtin("seed").unwrap();
        let cases = suite::generate(&p).unwrap();
        let counted: Vec<WireCase> = ids
            .iter()
            .map(|&(id, carried)| {
                let c = cases.iter().find(|c| c.id() == id).unwrap();
                let out =
                    suite::run_case(c, &mut SimLink::new(p.clone(), Default::default()), &suite::replay_options());
                assert!(out.is_pass(), "{id}: {}", out.render());
                WireCase {
                    id: id.to_string(),
                    steps: out.exchange().iter().map(|e| (e.sent.len() as u64, e.received.len() as u64)).collect(),
                    passed: true,
                    carried,
                }
            })
            .collect();
        let opts = ConformOptions::in_process(p, vec![]);
        wire_time(&cases, &counted, outside, &opts, Duration::from_millis(2), 9600, 1.0)
    }

    #[test]
    fn the_wire_bound_counts_the_echo_once_and_where_the_case_before_left_the_fingers() {
        // No motion: full duplex, the hand echoing as it reads, so a case takes less than its
        // bytes both ways one after the other, and at least its received bytes.
        let w = bound_of(&[("cmd-fget", false)]);
        let byte_ms = 10.0 / 9600.0 * 1000.0;
        assert!(w.lower_bound_ms < (w.bytes_sent + w.bytes_received) as f64 * byte_ms, "{w:?}");
        // ... and for each step that sent bytes, the first of them before any answer.
        let p = Profile::builtin("seed").unwrap();
        let cases = suite::generate(&p).unwrap();
        let fget = cases.iter().find(|c| c.id() == "cmd-fget").unwrap();
        let out = suite::run_case(fget, &mut SimLink::new(p.clone(), Default::default()), &suite::replay_options());
        let answered = out.exchange().iter().filter(|e| !e.sent.is_empty() && !e.received.is_empty()).count() as u64;
        assert!(answered > 1, "{}", out.render());
        assert!(w.lower_bound_ms + 1e-6 >= (w.bytes_received + answered) as f64 * byte_ms, "{w:?}");
        // C closes the hand; on a kept link the next case's HI moves the fingers all the way
        // back, which a freshly powered-up hand need not do.
        let fresh = bound_of(&[("cmd-c", false), ("cmd-hi", false)]);
        let kept = bound_of(&[("cmd-c", false), ("cmd-hi", true)]);
        assert!(kept.lower_bound_ms > fresh.lower_bound_ms + 1000.0, "{fresh:?} {kept:?}");
        assert!(kept.motion_ms > fresh.motion_ms + 1000.0, "{fresh:?} {kept:?}");
    }

    #[test]
    fn the_wire_bound_counts_the_probes_before_the_first_case_which_starts_where_the_probe_left_the_fingers() {
        let p = Profile::builtin("seed").unwrap();
        let opts = ConformOptions::in_process(p.clone(), vec![]);
        let policy = DeadlinePolicy::for_target(&opts.target);
        // The probe on the in-process hand (simulated time: it moves in real time), after a
        // pre-flight's RESET.
        let mut hand = SimLink::new(p.clone(), gcl_model::DeviceConfig::default());
        discard(&mut hand, Duration::from_millis(50), Duration::from_secs(1)).unwrap();
        let probed = motion_time(&mut hand, &opts, &policy, Some(9600), true).expect("seed has a close command");
        assert!(probed.fast.is_none(), "the model's hand moves in real time");
        let (close, after) = crate::motion::MotionProbe::new(&p)
            .and_then(|m| m.after_reset(&p))
            .and_then(|m| m.decided_after(&p))
            .unwrap();
        // Its close is counted for as long as it was watched, then its ^C.
        assert_eq!(probed.steps.len(), close + 2, "{:?}", probed.steps);
        assert_eq!(probed.steps[close].busy_ms, after.as_secs_f64() * 1000.0);
        assert_eq!(probed.steps[close + 1].put, 1);
        let byte_ms = 10.0 / 9600.0 * 1000.0;
        let probes = steps_bound_ms(&probed.steps, byte_ms);
        assert!(probes > after.as_secs_f64() * 1000.0, "{probes}");
        assert!(probed.model.is_some(), "the probe ran on the hand as on the model");
        // The bound counts it, and the first case's HI moves the fingers back from where the
        // probe's ^C stopped them, which a freshly powered-up hand need not do.
        let pre = PreflightFound { exchanged: vec![(1, 5), (1, 5)], ..Default::default() };
        let outside = Outside::of(&pre, Some(probed));
        assert_eq!(outside.steps.len(), close + 4);
        let probes = steps_bound_ms(&outside.steps, byte_ms);
        let fresh = bound_of(&[("cmd-hi", true)]);
        let after_probe = bound_after(&[("cmd-hi", true)], outside);
        assert_eq!(after_probe.probes_ms, probes);
        assert!(after_probe.motion_ms > fresh.motion_ms + 100.0, "{fresh:?} {after_probe:?}");
        assert!(after_probe.lower_bound_ms > fresh.lower_bound_ms + probes + 100.0, "{fresh:?} {after_probe:?}");
        assert_eq!(fresh.probes_ms, 0.0);
    }
}
