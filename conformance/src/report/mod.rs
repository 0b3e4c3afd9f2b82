//! Conformance reports: the results of a run as data, and the writers CI systems and people
//! read (JSON with a schema, JUnit XML, a self-contained HTML page).
//!
//! Results are also streamed to `results.jsonl` as each case ends (one flushed line per
//! case), so a crash or a kill mid-run leaves everything already decided readable.
//!
//! `RunReport` has a `kind` (conform, certify, fuzz host, check-host), a host report's campaign in
//! `host`, a hand's `profile_spec` and, for certify, `certificate`. `RunReport::outcome` is the one
//! verdict line of a hand's run (PASS, PARTIAL, FAIL, ERROR, with its counts) that the console,
//! `report.json`, JUnit, the page and a certificate show. The schema of `report.json` is
//! `reports/report.schema.json`; JUnit XML is `junit.rs`.
//!
//! The pages: `page.rs` is the one page design every HTML report uses (the fuzz device's too), with
//! the one `esc` every page writer escapes with: title, verdict first, the options that changed
//! what
//! ran, findings or groups, details folded in `<details>`, one inline style sheet, no script, no
//! external resource. `html.rs` renders a `RunReport` in it (a transcript step by step with the
//! failing step marked and shared preambles shown once). `diff.rs` is the one notation of a diff
//! (the
//! one-line summary JUnit and the console show, the golden and the actual aligned under a caret, a
//! RealTime block decoded field by field, its layout found by feeding the transcript's sends to a
//! fresh model); a diff carries its golden's form (`Diff::form`, text or hex). `merged.rs` says
//! which shards a merged report holds (`Merged`). `svg.rs` draws plots as inline SVG (series,
//! golden
//! bands, windows, failure marks); conform keeps the exchange of every RealTime case, passing too,
//! for the plots. `program.rs` is the page of the RealTime example program's run (`--example
//! realtime -- --plot`), each finger's positions over the band of the reference model's own run.
//!
//! `harness/tests/it/report_pages.rs` parses every kind of page with an HTML5 parser and reads every
//! `junit.xml` with Python's `junitparser` (`.ci/run` makes its venv); `reports/screenshot.sh`
//! renders every kind of page with headless Chromium.

pub mod diff;
pub mod html;
pub mod junit;
pub mod merged;
pub mod page;
pub mod program;
pub mod svg;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use html::to_html;
pub use junit::to_junit;

/// The version of the report format (bump on incompatible changes).
pub const REPORT_FORMAT: u32 = 1;

/// How a case ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Verdict {
    /// The device's answers matched.
    Pass,
    /// An answer differed from the golden one.
    Fail,
    /// A step waited past its deadline.
    Timeout,
    /// The device vanished (disconnect, exited process) or the link failed.
    Error,
    /// Not run: filtered out by level or glob, or the target lacks what the case requires.
    Skip,
    /// Failed, and listed as a known failure.
    Xfail,
    /// Passed, but listed as a known failure: the list is stale, and the run fails.
    Xpass,
}

impl Verdict {
    /// Every verdict, in report order.
    pub const ALL: [Verdict; 7] =
        [Verdict::Pass, Verdict::Fail, Verdict::Timeout, Verdict::Error, Verdict::Skip, Verdict::Xfail, Verdict::Xpass];

    /// Whether this verdict makes the run fail.
    pub fn fails_run(self) -> bool {
        matches!(self, Verdict::Fail | Verdict::Timeout | Verdict::Error | Verdict::Xpass)
    }

    /// The upper-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "PASS",
            Verdict::Fail => "FAIL",
            Verdict::Timeout => "TIMEOUT",
            Verdict::Error => "ERROR",
            Verdict::Skip => "SKIP",
            Verdict::Xfail => "XFAIL",
            Verdict::Xpass => "XPASS",
        }
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Where the device's answer parted from the golden one.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Diff {
    /// The step of the transcript, numbered from 1 as in every message.
    pub step: usize,
    /// The byte offset within that step's answer.
    pub offset: usize,
    /// The expected answer from the parting byte on, escaped (with elisions as written).
    pub expected: String,
    /// The actual answer from the parting byte on, escaped.
    pub actual: String,
    /// The answer just before the parting byte (at most [`CONTEXT_CHARS`] characters), escaped:
    /// the part both agree on, shown in front of `expected` and `actual`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub before: String,
    /// The step's whole golden expectation in the form of `expected` and `actual` (escaped
    /// text or hex tokens, elisions in braces, no quotes).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub golden: String,
    /// Whether the step's golden answer is text or binary (a RealTime block in hex tokens), as
    /// the golden says; absent in reports written before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub form: Option<AnswerForm>,
}

/// The form of a golden answer: text, or binary written as hex tokens.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AnswerForm {
    /// Text, escaped.
    Text,
    /// Binary, as hex tokens (a RealTime block).
    Hex,
}

impl From<gcl_transcript::Form> for AnswerForm {
    fn from(f: gcl_transcript::Form) -> AnswerForm {
        match f {
            gcl_transcript::Form::Text => AnswerForm::Text,
            gcl_transcript::Form::Hex => AnswerForm::Hex,
        }
    }
}

/// Characters of agreed answer kept in [`Diff::before`].
pub const CONTEXT_CHARS: usize = 40;

/// The longest text a report keeps of an actual answer or a transcript; longer ones are cut
/// with a note saying how much was left out.
pub const MAX_SHOWN: usize = 8192;

/// The id of the case that says a host session (`gcl check-host`, `gcl fuzz host`) judged
/// nothing or was stopped.
pub const SESSION_CASE: &str = "host-session";

/// The file name a case's transcript has in a bundle's `transcripts/` (without `.gcl`).
pub(crate) fn safe_name(id: &str) -> String {
    id.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '.' { c } else { '_' }).collect()
}

/// Words as one command line for a POSIX shell, each quoted as it needs by the `shlex` crate:
/// pasted into `sh`, the line runs exactly these words as its argv (`-- sh -c 'sleep 0.1; exit
/// 3'`, a target holding `'; touch X; echo '`), never a command of its own. Every command a
/// report or the console offers to run again is written by it. A word holding a NUL byte,
/// which no argv can hold, has it written `\x00` (that word cannot be run as it was given).
pub fn shell_command<S: AsRef<str>>(words: &[S]) -> String {
    let word = |w: &S| {
        let w = w.as_ref().replace('\0', "\\x00");
        shlex::try_quote(&w).map(|q| q.into_owned()).unwrap_or(w)
    };
    words.iter().map(word).collect::<Vec<_>>().join(" ")
}

/// `s` cut to at most `max` bytes (on a character boundary) with a note of what was left out.
pub fn truncate_note(s: &str, max: usize) -> String {
    if s.len() <= max {
        return s.to_string();
    }
    let mut cut = max;
    while !s.is_char_boundary(cut) {
        cut -= 1;
    }
    format!("{}… [{} more bytes not shown]", &s[..cut], s.len() - cut)
}

/// Why a run ended before its last case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopCause {
    /// `--max-failures` (or `--fail-fast`) was reached.
    MaxFailures,
    /// The hand stopped answering: consecutive TIMEOUTs, then no answer to the liveness probe.
    DeadHand,
    /// The hand floods: after consecutive failing cases it did not stop sending.
    Flooding,
    /// A signal (SIGINT, SIGTERM, SIGHUP: a CI job's time limit, Ctrl-C) stopped the run.
    Signal,
    /// The run could not test: the host never opened the port or sent nothing.
    CannotTest,
}

/// A run that ended early: the remaining cases are SKIP, "not run".
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stopped {
    /// Why.
    pub cause: StopCause,
    /// Where: the case that reached `--max-failures`, or the first of the timeouts (or
    /// floods) in a row after which the run ended.
    pub case: String,
    /// One line for people.
    pub message: String,
}

/// Failures that part from their goldens the same way: one likely root cause.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FailureGroup {
    /// The command being answered where the cases part (`FGET`, `^C`, `CR`, `RealTime block`).
    pub command: String,
    /// The kind of difference: order, value, framing, status, missing-answer, flood, link.
    pub kind: String,
    /// One line for people: "120 cases: FGET: the values come in another order".
    pub summary: String,
    /// The clause most likely at fault: that of the group's case with the smallest golden
    /// transcript.
    pub clause: String,
    /// The case whose diff represents the group (the one with the smallest transcript).
    pub representative: String,
    /// Its diff.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diff: Option<Diff>,
    /// Every case of the group.
    pub cases: Vec<String>,
    /// The group's cases that do not check its clause: blocked by it, not failing on their own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub blocked: Vec<String>,
}

/// The result of one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// The case's stable id.
    pub id: String,
    /// Its title.
    pub title: String,
    /// The spec clauses it checks.
    pub clauses: Vec<String>,
    /// Every decision of the profile the case rests on (ids): those it checks and those its
    /// framing, preamble and read-backs touch. `--skip-decision` drops cases by these.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub decisions: Vec<String>,
    /// MUST, SHOULD, MAY or INFO.
    pub level: String,
    /// The verdict.
    pub verdict: Verdict,
    /// Wall time spent, milliseconds.
    pub duration_ms: f64,
    /// One line saying why (for anything but PASS).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    /// Where the answer parted from the golden one (FAIL, XFAIL).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diff: Option<Diff>,
    /// How it failed, as the root-cause grouping names it: the step (from 1) and the
    /// difference's key (`step 6: order at FGET (P)`). A known-failures entry's `how`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// The exchange as it happened, in transcript text (for failures, for RealTime cases, whose
    /// blocks the page plots, and in certificates).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transcript: Option<String>,
}

/// Wire-time accounting of a run over a paced link.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WireTime {
    /// Bytes the harness sent in the cases counted.
    pub bytes_sent: u64,
    /// Bytes the device sent in the cases counted.
    pub bytes_received: u64,
    /// The line rate used for the bound, bit/s.
    pub baud: u32,
    /// Simulated motion time the passing cases need, milliseconds.
    pub motion_ms: f64,
    /// The lower bound, milliseconds, summed over the cases counted and [`WireTime::probes_ms`]:
    /// for a passing case its
    /// pauses plus the larger of its bytes sent × 10 / baud and the sum over its steps of the
    /// larger of the step's bytes received × 10 / baud (full duplex, the echo overlapping what
    /// is sent) and the model's motion time on the step; for a failing case its bytes in one
    /// direction (`conform::wire_time`).
    pub lower_bound_ms: f64,
    /// How many cases the bound counts: those that ran to their end or to a mismatch (PASS,
    /// FAIL and their known-failure forms); TIMEOUT and ERROR cases are left out.
    #[serde(default)]
    pub counted_cases: usize,
    /// The part of the lower bound, milliseconds, that is what the run puts on the line
    /// before its first case, by the same rule as a case's steps: the framing pre-flight's
    /// exchanges and the motion-time probe's (its close counted for as long as it is watched).
    /// The liveness probes and the waits for quiet are not counted.
    #[serde(default)]
    pub probes_ms: f64,
    /// The run's wall time, milliseconds.
    pub actual_ms: f64,
    /// actual / lower bound.
    pub ratio: f64,
}

impl WireTime {
    /// Whether the run itself refutes the bound: it took less time than its bytes would take
    /// at `baud`, so the hand did not pace its bytes at that rate (an unpaced simulator, or a
    /// link faster than the baud given) and the bound, which assumes it did, says nothing.
    pub fn refuted(&self) -> bool {
        self.actual_ms < self.lower_bound_ms
    }

    /// The sentence a report gives instead of a bound the run refutes.
    pub fn refuted_text(&self) -> String {
        format!(
            "no wire-time bound: the run took {:.3} s, less than the {:.3} s its {} PASS/FAIL cases' bytes \
would take at {} baud, so the hand does not pace its bytes at {} baud (an unpaced simulator?); the bound \
assumes a hand that does",
            self.actual_ms / 1000.0,
            self.lower_bound_ms / 1000.0,
            self.counted_cases,
            self.baud,
            self.baud
        )
    }
}

/// Every option that changed what a run ran or how it was judged, so a report (and a
/// certificate) says what it is a report of.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunOptions {
    /// `--only` globs: only matching cases ran (the others are absent from the report).
    #[serde(default)]
    pub only: Vec<String>,
    /// `--skip` globs: matching cases are SKIP.
    #[serde(default)]
    pub skip: Vec<String>,
    /// `--no` requirements the operator refused: cases needing them are SKIP.
    #[serde(default)]
    pub refused: Vec<String>,
    /// `--fixture` set-ups the operator declared in place: cases needing them ran on a hand
    /// `gcl` cannot set up.
    #[serde(default)]
    pub fixtures: Vec<String>,
    /// `--fault`s given to a simulated hand.
    #[serde(default)]
    pub faults: Vec<String>,
    /// The seed of a simulated hand's noise.
    #[serde(default)]
    pub seed: Option<u64>,
    /// `--suite DIR`: the committed goldens in DIR ran instead of the generated suite.
    #[serde(default)]
    pub suite_dir: Option<String>,
    /// `--timeout`: the per-step deadline, milliseconds.
    #[serde(default)]
    pub step_timeout_ms: Option<u64>,
    /// `--known-failures FILE`.
    #[serde(default)]
    pub known_failures_file: Option<String>,
    /// Every known-failures entry for this profile, and whether it matched a case.
    #[serde(default)]
    pub known_failures: Vec<KnownFailureEntry>,
    /// `--skip-decision` ids (and `[[skip-decision]]` entries of the known-failures file):
    /// the cases resting on them are SKIP.
    #[serde(default)]
    pub skip_decisions: Vec<String>,
    /// `certify --partial`: the run was not meant to certify the whole suite.
    #[serde(default)]
    pub partial: bool,
}

/// One known-failures entry as a report records it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct KnownFailureEntry {
    /// The glob over case ids.
    pub case: String,
    /// Why it fails.
    pub reason: String,
    /// Whether it matches a case of the profile's suite (an entry that does not is stale).
    pub matched: bool,
}

impl RunOptions {
    /// The options that were given, as (name, value) pairs for people: empty for a run of
    /// the whole suite with no options.
    pub fn pairs(&self) -> Vec<(&'static str, String)> {
        let mut v = Vec::new();
        let list = |l: &[String]| l.join(", ");
        if !self.only.is_empty() {
            v.push(("only", list(&self.only)));
        }
        if !self.skip.is_empty() {
            v.push(("skip", list(&self.skip)));
        }
        if !self.refused.is_empty() {
            v.push(("no", list(&self.refused)));
        }
        if !self.fixtures.is_empty() {
            v.push(("fixture", list(&self.fixtures)));
        }
        if !self.faults.is_empty() {
            v.push(("fault", list(&self.faults)));
        }
        if !self.skip_decisions.is_empty() {
            v.push(("skip-decision", list(&self.skip_decisions)));
        }
        if let Some(d) = &self.suite_dir {
            v.push(("suite", d.clone()));
        }
        if let Some(t) = self.step_timeout_ms {
            v.push(("timeout", format!("{t} ms")));
        }
        if let Some(f) = &self.known_failures_file {
            let stale: Vec<&str> = self.known_failures.iter().filter(|k| !k.matched).map(|k| k.case.as_str()).collect();
            let mut s = format!("{f} ({} entries", self.known_failures.len());
            if !stale.is_empty() {
                s.push_str(&format!("; matching no case: {}", stale.join(", ")));
            }
            s.push(')');
            v.push(("known-failures", s));
        }
        if self.partial {
            v.push(("partial", "yes".to_string()));
        }
        v
    }
}

/// How many cases of each verdict.
pub type Summary = BTreeMap<Verdict, usize>;

/// One spec clause and how the cases that check it fared.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ClauseCoverage {
    /// The clause.
    pub clause: String,
    /// Ids of the cases that check it.
    pub cases: Vec<String>,
    /// The worst verdict among them.
    pub verdict: Verdict,
    /// Whether it fails only through another clause's bug: no group names it, and every case
    /// that fails it is in a group that names another clause.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub blocked: bool,
}

/// A whole conformance run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunReport {
    /// The report format version.
    pub format: u32,
    /// The command that wrote it.
    #[serde(default)]
    pub kind: ReportKind,
    /// `gcl` and its version.
    pub tool: String,
    /// The target as given.
    pub target: String,
    /// The profile the suite was selected for.
    pub profile: String,
    /// The level filter: must, should or all.
    pub level: String,
    /// Start time, RFC 3339 UTC.
    pub started: String,
    /// Wall time of the run, milliseconds.
    pub duration_ms: f64,
    /// The suite version: SHA-256 over every golden transcript.
    pub suite_hash: String,
    /// Whether the device answered the liveness probe before and after the suite.
    pub liveness: Liveness,
    /// The options that changed what ran (selection, refusals, faults, the suite's source,
    /// known failures).
    #[serde(default)]
    pub options: RunOptions,
    /// The framing pre-flight's one line (prompt, line ending, echo, banner, status format).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preflight: Option<String>,
    /// Set when the run ended before its last case.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<Stopped>,
    /// Failures grouped by where they part from their goldens, largest group first.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub groups: Vec<FailureGroup>,
    /// Wire-time accounting, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wire: Option<WireTime>,
    /// Counts per verdict.
    pub summary: Summary,
    /// Per-clause verdicts.
    pub clauses: Vec<ClauseCoverage>,
    /// Every case.
    pub cases: Vec<CaseResult>,
    /// A host report's campaign (fuzz host, check-host).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub host: Option<HostDetails>,
    /// The verdict line every output of the run shows ([`RunReport::verdict_line`]), in the
    /// words of the reference's table (`docs/src/reference.md`, Verdicts); filled when the
    /// report is written.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub verdict: String,
    /// Which spec the profile came from: a built-in one, or a file (with the hash of what ran).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile_spec: Option<ProfileSpec>,
    /// A run that made a certificate (`gcl certify`): what the certificate adds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certificate: Option<CertificateFacts>,
}

/// Where a run's profile came from. A report or a certificate names a built-in profile only
/// when the spec that ran is that built-in's spec (the same hash); a file that declares a
/// built-in's id with other contents is named as the file it is.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ProfileSpec {
    /// `builtin` or `file`.
    pub origin: ProfileOrigin,
    /// The built-in profile's id, or the file as given.
    pub name: String,
    /// The id the spec declares.
    pub id: String,
    /// SHA-256 of the spec as loaded (every include resolved), as JSON: [`ProfileSpec::digest`].
    pub sha256: String,
}

/// Whether a spec is a built-in profile's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProfileOrigin {
    /// The spec is exactly the built-in profile's of its id.
    Builtin,
    /// A file, whatever id it declares.
    File,
}

impl ProfileSpec {
    /// The spec of `profile`, loaded from `given` (a built-in name or a file).
    pub fn of(given: &str, profile: &gcl_model::Profile) -> ProfileSpec {
        let sha256 = ProfileSpec::digest(profile);
        let builtin = gcl_model::Profile::builtin(&profile.id).is_ok_and(|b| ProfileSpec::digest(&b) == sha256);
        ProfileSpec {
            origin: if builtin { ProfileOrigin::Builtin } else { ProfileOrigin::File },
            name: if builtin { profile.id.clone() } else { given.to_string() },
            id: profile.id.clone(),
            sha256,
        }
    }

    /// SHA-256 of a loaded profile: of its JSON form, every include resolved, so two files
    /// that load to the same profile have the same hash.
    pub fn digest(profile: &gcl_model::Profile) -> String {
        crate::digest::sha256_hex(&serde_json::to_vec(profile).unwrap_or_default())
    }

    /// How people see it: `bh8-262-4.3` for a built-in; for a file, the file, the id it
    /// declares and the start of its hash, saying it is not the built-in of that id.
    pub fn label(&self) -> String {
        match self.origin {
            ProfileOrigin::Builtin => self.name.clone(),
            ProfileOrigin::File => {
                let builtin = gcl_model::Profile::builtin(&self.id).is_ok();
                format!(
                    "{} (a profile file declaring id {}{}; sha256 {})",
                    self.name,
                    self.id,
                    if builtin { ", not that built-in profile" } else { "" },
                    &self.sha256[..self.sha256.len().min(16)]
                )
            }
        }
    }
}

/// What a certificate adds to its run's report, so that the bundle's page says what it is.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CertificateFacts {
    /// Cases of the certified levels in the whole suite (`--only` aside): a certificate is
    /// partial when fewer ran.
    pub cases_total: usize,
    /// What the hand answered to `VERS`.
    pub firmware_version: Vec<String>,
    /// The fingerprint of the key that signs the bundle, or `None` for an unsigned bundle.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signed_by: Option<String>,
}

/// The verdicts of `bad` (the cases that fail a run) counted by word, `TIMEOUT 300, FAIL 56`,
/// or `None` when every one is FAIL: a line that says they "fail" must not hide that a table
/// beside it says TIMEOUT.
pub(crate) fn verdict_counts(bad: &[&CaseResult]) -> Option<String> {
    if bad.iter().all(|c| c.verdict == Verdict::Fail) {
        return None;
    }
    let mut counts: BTreeMap<Verdict, usize> = BTreeMap::new();
    for c in bad {
        *counts.entry(c.verdict).or_default() += 1;
    }
    let mut by: Vec<(Verdict, usize)> = counts.into_iter().collect();
    by.sort_by_key(|(v, n)| (std::cmp::Reverse(*n), *v));
    Some(by.iter().map(|(v, n)| format!("{v} {n}")).collect::<Vec<_>>().join(", "))
}

/// What a hand's run amounts to, computed by [`RunReport::outcome`] alone: the console's
/// `result:` line, `report.json`'s `verdict`, JUnit's `gcl.verdict` property, the page's
/// verdict and a certificate's `verdict` all show it, so they never disagree on the verdict,
/// the counts or what was excused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Outcome {
    /// `PASS`, `PARTIAL`, `FAIL` or `ERROR`: the verdict's first word.
    pub word: &'static str,
    /// The verdict line: `PASS`, `FAIL`, `ERROR`, `PARTIAL: 12 of 336 cases`, `PARTIAL: 91 of
    /// 216 cases passed, 125 known failures excused`, `FAIL (PARTIAL: 297 of 354 cases)`.
    pub verdict: String,
    /// The counts behind it, for people: `148 of 297 cases that ran fail (MUST 100, SHOULD
    /// 48); 3 likely root cause(s)`.
    pub detail: String,
    /// Whether the run covers only part of what it judges: cases not run, known failures
    /// excused, or `certify --partial`.
    pub partial: bool,
    /// Cases that ran (every verdict but SKIP).
    pub cases_run: usize,
    /// Cases judged: those of the levels run (for a certificate, of the whole suite).
    pub cases_total: usize,
    /// Known failures excused (XFAIL).
    pub excused: usize,
}

/// A verdict line: see [`Outcome::verdict`]. `excused` is the number of known failures (XFAIL)
/// among the `cases_run`; any makes the verdict partial. `error`: the run ended on the hand
/// (it stopped answering), not on a verdict.
pub fn verdict_line(
    passed: bool,
    error: bool,
    partial: bool,
    cases_run: usize,
    cases_total: usize,
    excused: usize,
) -> String {
    let covered = if excused > 0 {
        format!("{} of {cases_total} cases passed, {excused} known failures excused", cases_run.saturating_sub(excused))
    } else {
        format!("{cases_run} of {cases_total} cases")
    };
    let bad = if error { "ERROR" } else { "FAIL" };
    match (partial || excused > 0, passed && !error) {
        (false, true) => "PASS".to_string(),
        (false, false) => bad.to_string(),
        (true, true) => format!("PARTIAL: {covered}"),
        (true, false) => format!("{bad} (PARTIAL: {covered})"),
    }
}

/// Which command wrote a report: each has its own page title and leaves out what means nothing
/// for it (a host report has no liveness probe, suite hash or level filter to show).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReportKind {
    /// `gcl conform`.
    #[default]
    Conform,
    /// `gcl certify`.
    Certify,
    /// `gcl fuzz host`.
    FuzzHost,
    /// `gcl check-host`.
    CheckHost,
}

impl ReportKind {
    /// The command, as a page title names it.
    pub fn command(self) -> &'static str {
        match self {
            ReportKind::Conform => "gcl conform",
            ReportKind::Certify => "gcl certify",
            ReportKind::FuzzHost => "gcl fuzz host",
            ReportKind::CheckHost => "gcl check-host",
        }
    }

    /// Whether the report judges a host program (not a hand).
    pub fn is_host(self) -> bool {
        matches!(self, ReportKind::FuzzHost | ReportKind::CheckHost)
    }
}

/// What a host report (`gcl fuzz host`, `gcl check-host`) adds to its cases: the command that
/// ran, the campaign's figures, the misbehaviours fired by protocol state, and each finding's
/// bundle. Fields a later version adds (measured host timeouts, say) go in `facts`, which
/// every writer shows as they come.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct HostDetails {
    /// The host command and its arguments.
    pub command: Vec<String>,
    /// Runs made (fuzz host; 1 for check-host).
    pub runs: u64,
    /// Runs in which the host opened the port and sent the hand at least one byte: the runs
    /// that judged anything of it (absent in reports written before it was counted).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reached: Option<u64>,
    /// Runs made to minimize findings.
    #[serde(default)]
    pub minimize_runs: u64,
    /// The schedules' seed.
    pub seed: u64,
    /// The misbehaviours drawn from (`--ops`), with weights; empty: every operator.
    #[serde(default)]
    pub ops: Vec<String>,
    /// How often each misbehaviour fired at each protocol state.
    #[serde(default)]
    pub fired_at: BTreeMap<String, BTreeMap<String, u64>>,
    /// Figures for people, in order (name, value): transport, time mode, timeouts measured...
    #[serde(default)]
    pub facts: Vec<(String, String)>,
    /// Each distinct finding.
    #[serde(default)]
    pub findings: Vec<HostFinding>,
    /// A report `gcl fuzz merge` folded from shards: which it holds, of how many.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merged: Option<merged::Merged>,
    /// The host's code coverage over the campaign (fuzz host with `--coverage` on an
    /// instrumented host): (milliseconds since the start, runs, edges reached) at each rise
    /// and at the end.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub edges_over_time: Vec<(u64, u64, u64)>,
    /// The runs that reached edges no run before them had: (run, new edges, schedule).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub added_coverage: Vec<(u64, u64, String)>,
}

/// One finding of `gcl fuzz host`, with what a person needs to run it again.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct HostFinding {
    /// The case id it has in the report.
    pub case: String,
    /// crash, hang, exit or violation.
    pub kind: String,
    /// Its signature.
    pub signature: String,
    /// The run that first found it (0-based).
    pub run: u64,
    /// The bundle's folder, when written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bundle: Option<String>,
    /// The command that replays it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replay: Option<String>,
    /// The host's whole stderr in that run (as kept: the first 256 KiB).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub stderr: String,
}

/// The liveness probe results.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Liveness {
    /// Before the first case.
    pub before: bool,
    /// After the last case.
    pub after: bool,
}

impl RunReport {
    /// Whether the run as a whole passed. A run where no case ran (every one SKIP) did not.
    pub fn passed(&self) -> bool {
        self.liveness.before
            && self.liveness.after
            && self.ran() > 0
            && self.stopped.is_none()
            && !self.cases.iter().any(|c| c.verdict.fails_run())
    }

    /// The run's verdict line, the one the console's `result:`, `report.json`'s `verdict`,
    /// JUnit's `gcl.verdict` and the page's banner show, in the words of the reference's table
    /// (`docs/src/reference.md`, Verdicts): a hand's run, [`RunReport::outcome`]'s line; a
    /// host's, `PASS` or `FAIL` (check-host), `NO FINDING` or `FINDINGS` (fuzz host),
    /// `NOT TESTED` (the host never talked to the hand), `STOPPED` (a signal ended it before
    /// anything failed) or `INCOMPLETE` (a merge that lacks shards).
    pub fn verdict_line(&self) -> String {
        if !self.kind.is_host() {
            return self.outcome().verdict;
        }
        let ok = self.passed();
        let incomplete = self.host.as_ref().and_then(|h| h.merged.as_ref()).is_some_and(|m| !m.complete());
        let campaign = self.kind == ReportKind::FuzzHost;
        let word = if campaign && incomplete {
            "INCOMPLETE"
        } else if campaign && ok {
            "NO FINDING"
        } else if let Some(w) = self.host_unjudged().filter(|_| !ok) {
            w
        } else if campaign {
            "FINDINGS"
        } else if ok {
            "PASS"
        } else {
            "FAIL"
        };
        word.to_string()
    }

    /// The verdict of a host report that failed nothing it judged but did not pass either:
    /// `STOPPED` (a signal ended it) or `NOT TESTED` (the host never talked to the hand).
    fn host_unjudged(&self) -> Option<&'static str> {
        let failing = self.cases.iter().any(|c| matches!(c.verdict, Verdict::Fail | Verdict::Timeout | Verdict::Xpass));
        let errors = self.cases.iter().any(|c| c.verdict == Verdict::Error);
        match self.stopped.as_ref().map(|s| s.cause) {
            _ if failing => None,
            Some(StopCause::Signal) => Some("STOPPED"),
            _ if errors => Some("NOT TESTED"),
            _ => None,
        }
    }

    /// How many cases ran (every verdict but SKIP).
    pub fn ran(&self) -> usize {
        self.cases.iter().filter(|c| c.verdict != Verdict::Skip).count()
    }

    /// What a hand's run amounts to (see [`Outcome`]). The cases judged are those of the
    /// levels run (a case of a level not selected is out of scope, not missing), or for a
    /// certificate the suite's cases of the certified levels; the run is partial when some of
    /// them did not run, when known failures were excused, or when `certify --partial` asked.
    pub fn outcome(&self) -> Outcome {
        let judged = crate::suite::LevelFilter::from_name(&self.level).unwrap_or(crate::suite::LevelFilter::All);
        let in_scope = |c: &&CaseResult| c.level.parse::<gcl_transcript::Level>().map_or(true, |l| judged.admits(l));
        let scoped = self.cases.iter().filter(in_scope).count();
        let cases_total = self.certificate.as_ref().map_or(scoped, |c| c.cases_total);
        let cases_run = self.ran();
        let excused = self.cases.iter().filter(|c| c.verdict == Verdict::Xfail).count();
        let partial = self.options.partial || cases_run < cases_total || excused > 0;
        let error = self.stopped.as_ref().is_some_and(|st| st.cause != StopCause::MaxFailures);
        let verdict = verdict_line(self.passed(), error, partial, cases_run, cases_total, excused);
        let word = ["PASS", "PARTIAL", "FAIL", "ERROR"].into_iter().find(|w| verdict.starts_with(w)).unwrap_or("FAIL");
        let bad: Vec<&CaseResult> = self.cases.iter().filter(|c| c.verdict.fails_run()).collect();
        let mut parts: Vec<String> = Vec::new();
        if cases_run == 0 {
            parts.push(format!("nothing ran of {cases_total} cases"));
        } else if !bad.is_empty() {
            let mut by_level: BTreeMap<gcl_transcript::Level, usize> = BTreeMap::new();
            for c in &bad {
                *by_level.entry(c.level.parse().unwrap_or(gcl_transcript::Level::Info)).or_default() += 1;
            }
            let levels: Vec<String> = by_level.iter().map(|(l, n)| format!("{l} {n}")).collect();
            parts.push(match verdict_counts(&bad) {
                // Not all of them FAIL: the page's table names them by their verdicts.
                Some(words) => format!(
                    "{} of the {cases_run} cases that ran did not pass ({words}; {})",
                    bad.len(),
                    levels.join(", ")
                ),
                None => format!("{} of the {cases_run} cases that ran fail ({})", bad.len(), levels.join(", ")),
            });
            if !self.groups.is_empty() {
                parts.push(format!("{} likely root cause(s)", self.groups.len()));
            }
        } else if partial {
            parts.push(format!("none of the {cases_run} cases that ran failed"));
        } else {
            parts.push(format!("every one of the {cases_total} cases passed"));
        }
        if cases_total > cases_run && cases_run > 0 {
            parts.push(format!("{} of the {cases_total} cases did not run", cases_total - cases_run));
        }
        if excused > 0 {
            parts.push("the known failures excused count as not covered, not as passed".to_string());
        }
        if self.options.partial {
            parts.push("certify --partial: not meant to cover the whole suite".to_string());
        }
        if let Some(st) = &self.stopped {
            parts.push(format!("ended early: {}", st.message));
        }
        if !self.liveness.before || !self.liveness.after {
            parts.push("the hand did not answer the liveness probe".to_string());
        }
        Outcome { word, verdict, detail: parts.join("; "), partial, cases_run, cases_total, excused }
    }

    /// How much a host report judged, in one line for people, or `None` for a report of a
    /// hand: `4 of 6 clauses exercised` (check-host), `12 of 12 runs reached the host` (fuzz
    /// host). Every writer shows it, so a green one says what it rests on.
    pub fn judged(&self) -> Option<String> {
        let h = self.host.as_ref();
        match self.kind {
            ReportKind::CheckHost => {
                let clauses = self.cases.iter().filter(|c| c.id != SESSION_CASE);
                let (n, exercised) =
                    clauses.fold((0, 0), |(n, e), c| (n + 1, e + usize::from(c.verdict != Verdict::Skip)));
                Some(format!("{exercised} of {n} clauses exercised"))
            }
            ReportKind::FuzzHost => {
                let runs = h.map_or(0, |h| h.runs);
                Some(match h.and_then(|h| h.reached) {
                    Some(r) => format!("{r} of {runs} runs reached the host"),
                    None => format!("{runs} runs"),
                })
            }
            _ => None,
        }
    }

    /// The ids of the failing cases another clause's group explains (see
    /// [`FailureGroup::blocked`]).
    pub fn blocked(&self) -> std::collections::BTreeSet<&str> {
        self.groups.iter().flat_map(|g| g.blocked.iter().map(String::as_str)).collect()
    }

    /// Fills `summary` and `clauses` from `cases` (and `groups`, for blocked cases).
    pub fn tally(&mut self) {
        self.summary = Verdict::ALL.iter().map(|v| (*v, 0)).collect();
        for c in &self.cases {
            *self.summary.entry(c.verdict).or_default() += 1;
        }
        // (cases, worst verdict, whether it fails on its own): a clause fails on its own when a
        // group names it, or when a failing case that no group holds checks it; any other
        // failing clause fails through another clause's bug, named by its group.
        let grouped: std::collections::BTreeSet<&str> =
            self.groups.iter().flat_map(|g| g.cases.iter().map(String::as_str)).collect();
        let named: std::collections::BTreeSet<&str> = self.groups.iter().map(|g| g.clause.as_str()).collect();
        let mut by_clause: BTreeMap<&str, (Vec<String>, Verdict, bool)> = BTreeMap::new();
        for c in &self.cases {
            for cl in &c.clauses {
                let e = by_clause.entry(cl.as_str()).or_insert((Vec::new(), Verdict::Pass, false));
                e.0.push(c.id.clone());
                e.1 = worse(e.1, c.verdict);
                e.2 |= c.verdict.fails_run() && (named.contains(cl.as_str()) || !grouped.contains(c.id.as_str()));
            }
        }
        self.clauses = by_clause
            .into_iter()
            .map(|(clause, (cases, verdict, own))| ClauseCoverage {
                clause: clause.to_string(),
                cases,
                verdict,
                blocked: verdict.fails_run() && !own,
            })
            .collect();
    }
}

/// The worse of two verdicts for a clause: anything failing beats SKIP/XFAIL beats PASS.
fn worse(a: Verdict, b: Verdict) -> Verdict {
    let rank = |v: Verdict| match v {
        Verdict::Pass => 0,
        Verdict::Skip => 1,
        Verdict::Xfail => 2,
        Verdict::Xpass => 3,
        Verdict::Timeout => 4,
        Verdict::Fail => 5,
        Verdict::Error => 6,
    };
    if rank(b) > rank(a) { b } else { a }
}

/// Streams case results to `results.jsonl`, one flushed line per case.
pub struct ResultStream {
    out: BufWriter<File>,
    path: PathBuf,
}

impl ResultStream {
    /// Creates `dir/results.jsonl` afresh (a new file, never written through a link), creating `dir`.
    pub fn create(dir: &Path) -> std::io::Result<ResultStream> {
        let path = dir.join("results.jsonl");
        Ok(ResultStream { out: BufWriter::new(crate::outputs::create_stream(&path)?), path })
    }

    /// Appends one result and flushes it to the file.
    pub fn push(&mut self, r: &CaseResult) -> std::io::Result<()> {
        serde_json::to_writer(&mut self.out, r)?;
        self.out.write_all(b"\n")?;
        self.out.flush()
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

pub use crate::outputs::write_atomic;

/// Writes `report.json`, `junit.xml` and `report.html` into `dir`; `report.json` with its
/// verdict line ([`RunReport::verdict_line`]).
pub fn write_all(dir: &Path, report: &RunReport) -> std::io::Result<Vec<PathBuf>> {
    let json = dir.join("report.json");
    let verdict = report.verdict_line();
    if report.verdict == verdict {
        write_atomic(&json, &serde_json::to_vec_pretty(report)?)?;
    } else {
        write_atomic(&json, &serde_json::to_vec_pretty(&RunReport { verdict, ..report.clone() })?)?;
    }
    let junit = dir.join("junit.xml");
    write_atomic(&junit, to_junit(report)?.as_bytes())?;
    let html = dir.join("report.html");
    write_atomic(&html, to_html(report).as_bytes())?;
    Ok(vec![json, junit, html])
}

/// The JSON Schema of `report.json`, as committed in `reports/report.schema.json`.
pub const SCHEMA: &str = include_str!("../../../reports/report.schema.json");

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn sample() -> RunReport {
        let mut r = RunReport {
            format: REPORT_FORMAT,
            kind: ReportKind::Conform,
            host: None,
            verdict: String::new(),
            profile_spec: None,
            certificate: None,
            tool: "gcl 0.1.0".into(),
            target: "sim".into(),
            profile: "seed".into(),
            level: "all".into(),
            started: "2026-11-22T00:00:00Z".into(),
            duration_ms: 12.5,
            suite_hash: "00".repeat(32),
            liveness: Liveness { before: true, after: true },
            options: RunOptions::default(),
            preflight: Some("pre-flight: framing as the profile says".into()),
            stopped: None,
            groups: vec![],
            wire: None,
            summary: Summary::new(),
            clauses: vec![],
            cases: vec![
                CaseResult {
                    id: "framing-echo".into(),
                    title: "Echo <all> bytes & keeps case".into(),
                    clauses: vec!["decision:framing-echo".into()],
                    decisions: vec!["framing-echo".into()],
                    level: "MUST".into(),
                    verdict: Verdict::Pass,
                    duration_ms: 0.3,
                    message: None,
                    diff: None,
                    failure: None,
                    transcript: None,
                },
                CaseResult {
                    id: "fget-dp-default".into(),
                    title: "FGET DP reads the defaults".into(),
                    clauses: vec!["seed: FGET".into(), "decision:framing-echo".into()],
                    decisions: vec!["framing-echo".into(), "seed-fget-format".into()],
                    level: "MUST".into(),
                    verdict: Verdict::Fail,
                    duration_ms: 0.5,
                    message: Some("answer differs at byte 7".into()),
                    diff: Some(Diff {
                        step: 2,
                        offset: 7,
                        expected: "\\n\\r1000".into(),
                        actual: "\\r\\n1000".into(),
                        before: "FGET DP".into(),
                        golden: "FGET DP\\n\\r1000".into(),
                        form: Some(AnswerForm::Text),
                    }),
                    failure: Some("step 2: framing at FGET".into()),
                    transcript: Some("> FGET DP\\r\n< FGET DP\\r\\n1000".into()),
                },
            ],
        };
        r.tally();
        r
    }

    #[test]
    fn tally_counts_and_ranks_clauses() {
        let r = sample();
        assert_eq!(r.summary[&Verdict::Pass], 1);
        assert_eq!(r.summary[&Verdict::Fail], 1);
        assert!(!r.passed());
        let echo = r.clauses.iter().find(|c| c.clause == "decision:framing-echo").unwrap();
        assert_eq!(echo.verdict, Verdict::Fail);
        assert_eq!(echo.cases.len(), 2);
    }

    #[test]
    fn json_round_trips_and_names_verdicts_in_capitals() {
        let r = sample();
        let text = serde_json::to_string(&r).unwrap();
        assert!(text.contains("\"verdict\":\"FAIL\""));
        let back: RunReport = serde_json::from_str(&text).unwrap();
        assert_eq!(back, r);
    }

    #[test]
    fn long_actuals_are_cut_with_a_note() {
        let long = "é".repeat(10_000);
        let cut = truncate_note(&long, MAX_SHOWN);
        assert!(cut.len() < MAX_SHOWN + 64, "{}", cut.len());
        assert!(
            cut.ends_with(&format!("… [{} more bytes not shown]", long.len() - MAX_SHOWN)),
            "{}",
            &cut[cut.len() - 40..]
        );
        assert_eq!(truncate_note("short", MAX_SHOWN), "short");
    }

    #[test]
    fn atomic_write_replaces_whole_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("report.json");
        write_atomic(&p, b"old").unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file left behind");
    }

    #[test]
    fn stream_survives_without_a_final_report() {
        let dir = tempfile::tempdir().unwrap();
        let r = sample();
        {
            let mut s = ResultStream::create(dir.path()).unwrap();
            s.push(&r.cases[0]).unwrap();
            // Dropped without finishing, as a killed run would be (the line is already flushed).
            std::mem::forget(s);
        }
        let text = std::fs::read_to_string(dir.path().join("results.jsonl")).unwrap();
        let first: CaseResult = serde_json::from_str(text.lines().next().unwrap()).unwrap();
        assert_eq!(first.id, "framing-echo");
    }
}
