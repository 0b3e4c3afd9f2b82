//! The conformance runner behind `gcl conform` and `gcl certify`: select cases, probe the
//! hand, run every case over a [`Link`] with its own deadlines, turn replay outcomes into
//! verdicts (known failures become XFAIL, or XPASS when they pass), and account for wire
//! time.
//!
//! The runner never hangs on a hung hand: every step of every case has a deadline, and a
//! vanished hand ends its case as ERROR and is reopened for the next one.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use gcl_model::Profile;
use globset::{Glob, GlobSet, GlobSetBuilder};
use serde::Deserialize;

use crate::link::{Link, LinkError, SimLink, byte_time};
use crate::replay::{ReplayOptions, ReplayOutcome, actual_transcript};
use crate::report::{CaseResult, Diff, Liveness, REPORT_FORMAT, ResultStream, RunReport, Verdict, WireTime};
use crate::suite::{self, Case};
use crate::target::{OpenOptions, Target, open};
use crate::transcript::{Level, Requirement};

/// Which levels to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LevelFilter {
    /// MUST only.
    Must,
    /// MUST and SHOULD.
    Should,
    /// Every level: MUST, SHOULD, MAY, INFO.
    All,
}

impl LevelFilter {
    /// Whether a case of `level` runs.
    pub fn admits(self, level: Level) -> bool {
        match self {
            LevelFilter::Must => level == Level::Must,
            LevelFilter::Should => matches!(level, Level::Must | Level::Should),
            LevelFilter::All => true,
        }
    }

    /// The lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            LevelFilter::Must => "must",
            LevelFilter::Should => "should",
            LevelFilter::All => "all",
        }
    }
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
    ///
    /// [[skip-decision]]
    /// id = "framing-max-line"
    /// reason = "our lines hold 128 bytes"
    /// ```
    pub fn parse(text: &str) -> anyhow::Result<KnownFailures> {
        let f: KnownFile = toml::from_str(text)?;
        let mut entries = Vec::new();
        for k in f.failure {
            let g = Glob::new(&k.case).map_err(|e| anyhow::anyhow!("bad glob `{}`: {e}", k.case))?.compile_matcher();
            entries.push((k, g));
        }
        Ok(KnownFailures { entries, skip_decisions: f.skip_decision })
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
    pub fn load(path: &Path) -> anyhow::Result<KnownFailures> {
        let text = std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        KnownFailures::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e:#}", path.display()))
    }

    /// The entry that covers a case, if any.
    pub fn lookup(&self, profile: &str, id: &str) -> Option<&KnownFailure> {
        self.entries
            .iter()
            .find(|(k, g)| g.is_match(id) && k.profile.as_deref().is_none_or(|p| p == profile))
            .map(|(k, _)| k)
    }
}

fn globs(patterns: &[String]) -> anyhow::Result<Option<GlobSet>> {
    if patterns.is_empty() {
        return Ok(None);
    }
    let mut b = GlobSetBuilder::new();
    for p in patterns {
        b.add(Glob::new(p).map_err(|e| anyhow::anyhow!("bad glob `{p}`: {e}"))?);
    }
    Ok(Some(b.build()?))
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
    /// Per-step deadline for steps without their own `within`.
    pub step_timeout: Option<Duration>,
    /// Requirements the operator refuses (`--no motion`): such cases are SKIP.
    pub refuse: Vec<Requirement>,
    /// The line rate to compute the wire-time lower bound at (serial targets give their own).
    pub baud: Option<u32>,
    /// Keep the transcript of every case in the results, not only of failures (certificates).
    pub keep_transcripts: bool,
}

/// What a run produced besides its report.
pub struct RunOutput {
    /// The report.
    pub report: RunReport,
    /// The actual transcript of each case that ran (id, text), when asked for.
    pub transcripts: Vec<(String, String)>,
}

/// Selects the cases of `cases` that run, and the SKIP results of those that do not.
pub fn select<'c>(cases: &'c [Case], opts: &ConformOptions) -> anyhow::Result<(Vec<&'c Case>, Vec<CaseResult>)> {
    let only = globs(&opts.only)?;
    let skip = globs(&opts.skip)?;
    let profile = opts.profile.id.as_str();
    if let Some(s) =
        opts.known.skipped_decisions(profile).find(|s| !opts.profile.decisions.iter().any(|d| d.id == s.id))
    {
        anyhow::bail!(
            "skip-decision: profile {profile} has no decision `{}` (`gcl spec --profile {profile}` lists them)",
            s.id
        );
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
        } else {
            opts.refuse.iter().find(|r| c.requires(r)).map(|r| format!("requires {r}, which was refused"))
        };
        match reason {
            Some(message) => skipped.push(result_of(c, Verdict::Skip, 0.0, Some(message))),
            None => run.push(c),
        }
    }
    Ok((run, skipped))
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
        transcript: None,
    }
}

/// Sends a bare CR (after ^C) and waits for a prompt: is anybody there?
pub fn liveness(link: &mut dyn Link, profile: &Profile, timeout: Duration) -> Result<bool, LinkError> {
    // Any prompt-like answer counts: a hand with a malformed prompt is alive, and its cases
    // will say what is wrong with it.
    let prompt = profile.framing.prompt.trim_end().as_bytes().to_vec();
    link.send(&[profile.framing.abort])?;
    link.send(&[profile.framing.terminator])?;
    let mut buf = Vec::new();
    let ok = link.recv_until(&mut buf, timeout, &|b: &[u8]| {
        b.windows(prompt.len()).filter(|w| *w == prompt.as_slice()).count() >= 2
    })?;
    // Let a slow second prompt land before the first case starts.
    crate::transcript::record::drain(link, Duration::from_millis(20), timeout)?;
    Ok(ok)
}

/// Asks the hand for `VERS` and returns its lines (empty if it answered nothing useful).
pub fn firmware_version(link: &mut dyn Link, profile: &Profile, timeout: Duration) -> Result<Vec<String>, LinkError> {
    let mut cmd = b"VERS".to_vec();
    cmd.push(profile.framing.terminator);
    link.send(&cmd)?;
    let prompt = [profile.framing.line_ending.as_bytes(), profile.framing.prompt.as_bytes()].concat();
    let mut buf = Vec::new();
    link.recv_until(&mut buf, timeout, &|b: &[u8]| b.ends_with(&prompt))?;
    let text = String::from_utf8_lossy(&buf).into_owned();
    let eol = profile.framing.line_ending.as_str();
    let mut lines: Vec<String> = text.split(eol).skip(1).map(str::to_string).collect();
    lines.pop(); // the prompt
    Ok(lines)
}

/// Runs the selected cases. `progress` is told after each case.
pub fn run(
    cases: &[Case],
    opts: &ConformOptions,
    stream: Option<&mut ResultStream>,
    progress: &mut dyn FnMut(&CaseResult, usize, usize),
) -> anyhow::Result<RunOutput> {
    let now = time::OffsetDateTime::now_utc();
    let started_at = now.replace_nanosecond(0).unwrap_or(now);
    let wall = Instant::now();
    let (selected, skipped) = select(cases, opts)?;
    let fresh_per_case = matches!(opts.target, Target::Sim { .. });
    let probe_timeout = opts.step_timeout.unwrap_or(Duration::from_secs(5)).max(Duration::from_secs(2));
    let open_link = || open(&opts.target, &opts.open);

    let mut shared: Option<Box<dyn Link>> = None;
    let before = {
        let mut l = open_link()?;
        let ok = liveness(l.as_mut(), &opts.profile, probe_timeout).unwrap_or(false);
        if !fresh_per_case {
            shared = Some(l);
        }
        ok
    };
    if !before {
        anyhow::bail!(
            "the hand at {} did not answer the liveness probe (^C, CR, expecting `{}`) within {:?}",
            opts.target,
            gcl_model::escape::escape(opts.profile.framing.prompt.as_bytes()),
            probe_timeout
        );
    }

    let mut ropts = suite::replay_options();
    if let Some(t) = opts.step_timeout {
        ropts.default_timeout = t;
    }
    if !fresh_per_case {
        // A shared link was drained by the probe; between passing cases nothing is pending.
        ropts.drain_quiet = Duration::ZERO;
        ropts.trailing = Duration::from_millis(2);
    }

    let mut results: Vec<CaseResult> = Vec::with_capacity(cases.len());
    let mut transcripts = Vec::new();
    let (mut sent, mut received) = (0u64, 0u64);
    let mut stream = stream;
    let total = selected.len() + skipped.len();
    for r in skipped {
        if let Some(s) = stream.as_deref_mut() {
            s.push(&r)?;
        }
        progress(&r, results.len() + 1, total);
        results.push(r);
    }
    for case in selected {
        let t0 = Instant::now();
        let link: &mut dyn Link = if fresh_per_case {
            shared = Some(open_link()?);
            shared.as_deref_mut().expect("just opened")
        } else {
            match shared.as_deref_mut() {
                Some(l) => l,
                None => match open_link() {
                    Ok(l) => shared.insert(l).as_mut(),
                    Err(e) => {
                        let r = result_of(case, Verdict::Error, 0.0, Some(format!("cannot reopen the target: {e}")));
                        if let Some(s) = stream.as_deref_mut() {
                            s.push(&r)?;
                        }
                        progress(&r, results.len() + 1, total);
                        results.push(r);
                        continue;
                    }
                },
            }
        };
        let outcome = suite::run_case(case, link, &ropts);
        let ms = t0.elapsed().as_secs_f64() * 1000.0;
        for e in outcome.exchange() {
            sent += e.sent.len() as u64;
            received += e.received.len() as u64;
        }
        let mut r = result_of(case, Verdict::Pass, ms, None);
        match &outcome {
            ReplayOutcome::Pass(_) => {}
            ReplayOutcome::Mismatch(m) => {
                r.verdict = Verdict::Fail;
                r.message = Some(outcome.summary());
                r.diff = Some(Diff {
                    step: m.step,
                    offset: m.offset,
                    expected: m.expected.clone(),
                    actual: m.actual.clone(),
                });
            }
            ReplayOutcome::Timeout(t) => {
                r.verdict = Verdict::Timeout;
                r.message = Some(outcome.summary());
                r.diff =
                    Some(Diff { step: t.step, offset: t.offset, expected: t.expected.clone(), actual: String::new() });
            }
            ReplayOutcome::Disconnected(_) => {
                r.verdict = Verdict::Error;
                r.message = Some(outcome.summary());
                shared = None;
            }
        }
        if let Some(k) = opts.known.lookup(&case.profile, case.id()) {
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
        if r.verdict != Verdict::Pass || opts.keep_transcripts {
            let text = actual_transcript(&case.transcript, outcome.exchange()).to_text();
            if opts.keep_transcripts {
                transcripts.push((case.id().to_string(), text.clone()));
            }
            if r.verdict != Verdict::Pass {
                r.transcript = Some(text);
            }
        }
        if r.verdict.fails_run() && !fresh_per_case && shared.is_some() {
            // Whatever the failing case left pending must not be blamed on the next one.
            if let Some(l) = shared.as_deref_mut() {
                let _ = crate::transcript::record::drain(l, Duration::from_millis(50), Duration::from_secs(5));
            }
        }
        if let Some(s) = stream.as_deref_mut() {
            s.push(&r)?;
        }
        progress(&r, results.len() + 1, total);
        results.push(r);
    }

    let after = match shared.as_deref_mut() {
        Some(l) if !fresh_per_case => liveness(l, &opts.profile, probe_timeout).unwrap_or(false),
        _ => match open_link() {
            Ok(mut l) => liveness(l.as_mut(), &opts.profile, probe_timeout).unwrap_or(false),
            Err(_) => false,
        },
    };
    let actual_ms = wall.elapsed().as_secs_f64() * 1000.0;
    let baud = match &opts.target {
        Target::Serial { baud, .. } => Some(*baud),
        _ => opts.baud,
    };
    let wire = match baud {
        Some(baud) => Some(wire_time(cases, &results, opts, baud, sent, received, actual_ms)?),
        None => None,
    };
    let mut report = RunReport {
        format: REPORT_FORMAT,
        tool: format!("gcl {}", env!("CARGO_PKG_VERSION")),
        target: opts.target.to_string(),
        profile: opts.profile.id.clone(),
        level: opts.level.as_str().to_string(),
        started: started_at.format(&time::format_description::well_known::Rfc3339).unwrap_or_default(),
        duration_ms: actual_ms,
        suite_hash: suite::suite_hash(cases),
        liveness: Liveness { before, after },
        wire,
        summary: Default::default(),
        clauses: Vec::new(),
        cases: results,
    };
    report.tally();
    Ok(RunOutput { report, transcripts })
}

/// The wire-time lower bound: bytes × 10 / baud, plus the simulated motion and pause time
/// the same cases need on the reference model.
fn wire_time(
    cases: &[Case],
    results: &[CaseResult],
    opts: &ConformOptions,
    baud: u32,
    sent: u64,
    received: u64,
    actual_ms: f64,
) -> anyhow::Result<WireTime> {
    let mut motion = Duration::ZERO;
    for r in results.iter().filter(|r| r.verdict != Verdict::Skip) {
        let Some(case) = cases.iter().find(|c| c.id() == r.id) else { continue };
        let mut link = SimLink::new(opts.profile.clone(), Default::default());
        // No quiet-time drain and no trailing wait: they are the runner's, not the case's.
        let quiet = ReplayOptions { trailing: Duration::ZERO, drain_quiet: Duration::ZERO, ..suite::replay_options() };
        let outcome = suite::run_case(case, &mut link, &quiet);
        let bytes: u64 = outcome.exchange().iter().map(|e| (e.sent.len() + e.received.len()) as u64).sum();
        let wire_at_sim = byte_time(link.device().baud()) * bytes as u32;
        motion += link.elapsed().saturating_sub(wire_at_sim);
    }
    let motion_ms = motion.as_secs_f64() * 1000.0;
    let lower_bound_ms = (sent + received) as f64 * 10.0 / f64::from(baud) * 1000.0 + motion_ms;
    Ok(WireTime {
        bytes_sent: sent,
        bytes_received: received,
        baud,
        motion_ms,
        lower_bound_ms,
        actual_ms,
        ratio: if lower_bound_ms > 0.0 { actual_ms / lower_bound_ms } else { 0.0 },
    })
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

    #[test]
    fn level_filter() {
        assert!(LevelFilter::Must.admits(Level::Must));
        assert!(!LevelFilter::Must.admits(Level::Should));
        assert!(LevelFilter::Should.admits(Level::Should));
        assert!(!LevelFilter::Should.admits(Level::Info));
        assert!(LevelFilter::All.admits(Level::Info));
    }
}
