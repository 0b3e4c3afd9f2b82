//! `gcl fuzz device`: grammar-aware wire fuzzing of a hand with the reference model as the
//! oracle.
//!
//! Each run draws a short list of host actions from the profile ([`action`]) or mutates a
//! corpus entry, turns it into a golden transcript the suite's way ([`case`]: the suite's
//! preamble, the model's answers with the suite's elisions), and replays it against the
//! target with the suite's replayer. Any difference, timeout (the hand went silent, or a CR
//! got no prompt), flood or lost link is a finding. Findings are deduplicated by signature
//! (the command being answered where the answer parts from the model's, and the kind of
//! difference, as [`gcl_conformance::triage`] names them, plus `restart` for an unexpected banner, a
//! watchdog reset), minimized by dropping and simplifying actions while the signature holds,
//! and written as `gcl-transcript 1` files that `gcl replay` runs.
//!
//! Inputs that reach new model features ([`coverage`]) are kept in the corpus; a corpus
//! directory holds one JSON file per entry named by its content hash, so workers, machines
//! and runs share and merge corpora.
//!
//! The library prints nothing: progress goes to a callback, errors are [`FuzzError`].
//!
//! ## The campaign
//!
//! Replays take their deadlines from `deadline.rs` outside this process, and minimization is delta
//! debugging against the target. The corpus is shared by `--jobs` workers; corpus files that do not
//! parse are returned to the CLI, which warns. `report.rs` writes JSON, JUnit and HTML.
//!
//! A hand outside this process is probed with `conform::dead_hand` before the campaign
//! (`FuzzError::NotAlive`) and after a case that meets silence (`FuzzSummary::dead_hand`: the
//! campaign ends, exit 2). `FuzzOptions::stop` (set by the CLI's signal handler) and `--duration`
//! end the workers and minimization, so the reports are written; `FuzzReport::stopped` says why a
//! campaign ended early: the signal, a dead hand, or `DROP_LIMIT` drawn cases dropped in a row
//! (`FuzzSummary::no_cases`). `refuse_what_leaves_no_case` refuses, before a campaign, a
//! `--skip-decision` that the case of no action (the preamble every case starts with) rests on
//! (`FuzzError::NothingToTest`). `--skip-decision` drops cases resting on a decision (their
//! `x-decisions`).
//!
//! Outside this process the replayer's parting line is read to its end before a failure is signed
//! (`complete_parting_line`: on a serial line the rest of `1 1 0 1` is still on its way when `1 1`
//! parts), a case that wrote the EEPROM and failed has its restore sent after it (its saved values
//! would show in every later case), and a link just opened waits up to 2 s for its hand's
//! banner.
//!
//! On a link kept across cases a case first runs *quick* (drained to four quiet byte-times, no
//! trailing wait); only *thorough* runs (the replayer's quiet drain and trailing wait) report: a
//! quick failure is run again thoroughly, and bytes the next quick drain meets send the case before
//! it to a thorough run. Minimization runs thoroughly.
//!
//! ## Naming a finding
//!
//! Findings are signed by `align` (each case keeps its tagged model run, made while checking that
//! it passes on a fresh model), plus `restart` and `silence`. They are then *explained* where one
//! bug
//! shows wherever its effect is read back: the case's actions are rewritten as a hand with that bug
//! would take them (every line with a motor prefix widened by one motor; a parameter's pairs
//! dropped
//! from every set line, a line left without pairs sent empty; every line the model refuses for its
//! prefix alone sent without it) and rebuilt by the model. When the rewrite answers what the hand
//! did
//! at every step from the first rewritten one to the failing one, the explanation (`prefix 123+4`,
//! `MCV set without effect`, `prefix accepted on a command that takes none`) is the signature's
//! key.
//!
//! The hand's answers are matched as one stream against the rewrite's expectations in turn (a block
//! of another size moves where each step's answer ends; the rewrite's steps after the failing one
//! may
//! take what the case expected in it, as answers run a step behind their lines after a ^C); the
//! hand's echo of a rewritten line is taken as the rewrite's line wherever it comes (a line sent
//! without waiting is echoed in a later step's answer); and blocks send the bytes the hand was sent
//! where the rewrite's layout has the same size. Wider prefixes are tried first; reads of the
//! parameter are held to what was set; a line sent and then aborted whose answer the hand completed
//! first is rewritten as the line and a ^C after it (the host waited).
//!
//! A new explanation is looked for from a value read back outside RealTime blocks, and (in-process
//! sim only, where block sizes are exact) from a RealTime block's answer, which must then also be
//! confirmed by the hand answering the whole case as the rewrite does (a replay; another layout of
//! the same size can fit by chance); never from a status, except the accepted prefix where the
//! failure shows at a refused line itself. Once found, an explanation is tried first on every later
//! failure of any kind (`judged`'s `known`), and the unexplained findings met before it are run
//! again
//! against it alone; one it covers is dropped with its transcript and its key freed, so a later
//! failure under that key that it does not cover is still found (`report_finding`,
//! `Progress::Joined`, the console's `joined:` line).
//!
//! Where no rewrite holds, `variant.rs` replays the very transcript the hand failed on models that
//! each hold one hypothesis (a parameter set without effect goes through
//! `gcl_model::DeviceConfig::without_effect`; a letter prefix naming one motor more is a patch of
//! the
//! profile; the other side of a decision is played as the fault of that name). It starts afresh
//! only
//! from a wrong or cut-short answer (a silence fits many models), and from a status only the other
//! side of a decision (a set without effect would explain a status never reported). Outside this
//! process the case is built anew on the hypothesis's model (`case::build_case_on` with
//! `Model::Hypothesis`: the shadow, the recorder's shadow, the captures, the relations from the
//! coefficients that model acts on, `Device::effective`, and the model run all on it) with the
//! bands
//! of a hand outside, and a new hypothesis is confirmed on a few cases per finding. `judge_once`
//! judges one list of actions as a campaign does (tests).
//!
//! A new finding that is a value read back wrong and named by the command that decided it (`value
//! at FGET (P) after HOME`, `value at FLISTV (MCV) after RESET`) is then asked of the hand
//! (`probe.rs`, once per new finding, after minimization, from `report_finding`); in process its
//! positions are held to MPE (the model's clock is the hand's there), and
//! `FindingSignature::cause_step`
//! locates the cause as of a read. The finding takes the earliest cause so found (`after LOOP` for
//! stay-in-loop's and lcv-unsigned's), and is dropped if that key was reported already.
//!
//! A written finding names its key in an `x-signature` header, so a folder of findings is a
//! `--baseline`, and a finding it (or `--known-failures`) explains is known, not new: only new ones
//! fail the run. The fuzzer's expectations come from the model through the same path as the suite's
//! goldens, so every written finding replays with `gcl replay`.
//!
//! ## Hands outside this process
//!
//! Before a campaign that lands ^C mid-motion on a hand outside this process, `check_real_time`
//! closes it once from home (`MotionProbe`, which `conform` shares) and refuses (exit 2) a target
//! whose motion took under a quarter of the model's time. For such hands `case.rs` also drops what
//! the model cannot judge there (a motion with the over-temperature limit set, a read among raw
//! bytes, a ^C within 150 ms of a motion's end by the model's clock), and any case where the model
//! answers a ^C with the abort status `requires: abort-timing` (dropped under `--no abort-timing`).
//! There `actions/relate.rs` holds the ratio clauses in feedback blocks whose fields are otherwise
//! any value, and `action.rs` draws half the RealTime sessions as *held* ones (one set of small
//! data,
//! one coefficient set apart for one motor, pauses before the blocks where abort timing is allowed;
//! a pause makes the case require it), only for such hands, so campaigns on `sim` draw what they
//! always drew. There a motion makes positions certain again only when it is absolute (not IC/IO)
//! and moves every motor.

pub use gcl_conformance::actions as action;
pub use gcl_conformance::actions::case;
pub mod coverage;
mod probe;
pub mod report;
mod saved;
mod variant;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use gcl_model::Profile;
use serde::{Deserialize, Serialize};

use self::action::{Allowed, Dice, Generator, HostAction, simpler};
use self::case::{BuiltCase, NotACase, build_case};
use crate::deadline::{self, DeadlinePolicy};
use crate::motion::MotionProbe;
use crate::replay::{ReplayOptions, ReplayOutcome, replay};
use crate::suite::Case;
use gcl_host::link::{Link, LinkError};
use gcl_host::target::{OpenOptions, Target};
use gcl_transcript::Transcript;

/// How long a run goes on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Budget {
    /// This many cases (over all workers).
    Runs(u64),
    /// This much wall time.
    Time(Duration),
}

/// What a fuzzing run does.
#[derive(Debug, Clone)]
pub struct FuzzOptions {
    /// The hand.
    pub target: Target,
    /// How to open it (the sim's faults, profile, noise seed).
    pub open: OpenOptions,
    /// The profile the model speaks.
    pub profile: Arc<Profile>,
    /// Seed of the generator (worker `i` uses `seed + i`).
    pub seed: u64,
    /// When to stop.
    pub budget: Budget,
    /// Stop after this many distinct findings (`None`: run out the budget).
    pub max_findings: Option<usize>,
    /// A corpus directory, read at the start and added to as new coverage is found.
    pub corpus: Option<PathBuf>,
    /// Where minimized transcripts are written.
    pub out: Option<PathBuf>,
    /// What the hand may be asked to do.
    pub allowed: Allowed,
    /// The most EEPROM writes (FSAVE, PSAVE, restores included) the whole run may make.
    pub write_budget: Option<u64>,
    /// Workers (each opens the target once).
    pub jobs: usize,
    /// Minimize findings (on by default; off for raw speed figures).
    pub minimize: bool,
    /// The most replays one minimization may spend.
    pub minimize_budget: usize,
    /// Start the corpus from the suite's cases of the profile (their host sides).
    pub suite_seeds: bool,
    /// Set from outside (a signal handler: SIGTERM, SIGINT, SIGHUP) to end the campaign: the
    /// workers finish the case in hand, minimization stops, and the run returns what it has.
    pub stop: Arc<AtomicBool>,
    /// Only this slice of the campaign (`--shard K/N`): worker `w` draws from generator
    /// stream `K-1 + w*N` (see [`crate::fuzz::shard`]).
    pub shard: Option<crate::fuzz::shard::Shard>,
    /// What the hand is already known to do: findings it explains are *known*, not new.
    pub baseline: Baseline,
}

/// Findings a hand is already known to have, and decisions it took differently: a campaign
/// against it reports what is new (`--baseline`, `--known-failures`, `--skip-decision`).
#[derive(Debug, Clone, Default)]
pub struct Baseline {
    /// Signature keys of earlier findings ([`FindingSignature::key`]).
    pub keys: BTreeSet<String>,
    /// The status keys among them with the command each was seen on (as the finding's id
    /// names it: `fuzz-fget-status-1024-missing` is FGET's): a status key is only its bits,
    /// so without this the same bits on another command would pass for known.
    pub status_at: BTreeSet<(String, String)>,
    /// Known failures: an entry's glob matches a finding's id (`fuzz-fget-order`) or its key.
    pub known: crate::conform::KnownFailures,
    /// The profiles each earlier finding was recorded on (its transcript's `profile:`), by
    /// file: a finding is known only on a profile it was found on
    /// ([`Baseline::recorded_elsewhere`]).
    pub recorded_on: BTreeMap<PathBuf, Vec<String>>,
    /// The digest of the profile spec each earlier finding was recorded on (its transcript's
    /// `x-profile-sha256`), by file; `None` for a finding written before findings named it
    /// ([`Baseline::recorded_on_another_spec`]).
    pub spec_of: BTreeMap<PathBuf, Option<String>>,
}

impl Baseline {
    /// Adds the findings of a folder an earlier campaign wrote with `--out` (each transcript
    /// names its signature in its `x-signature` header); returns how many it read.
    pub fn add_dir(&mut self, dir: &Path) -> Result<usize, FuzzError> {
        let err = |source| FuzzError::Corpus { path: dir.to_path_buf(), source };
        let mut n = 0;
        for e in std::fs::read_dir(dir).map_err(err)? {
            let path = e.map_err(err)?.path();
            if path.extension().is_none_or(|x| x != "gcl") {
                continue;
            }
            let text = gcl_host::files::read_input_text(&path)
                .map_err(|e| FuzzError::Corpus { path: path.clone(), source: std::io::Error::other(e.to_string()) })?;
            let Ok(t) = gcl_transcript::parse(&text) else { continue };
            if let Some((_, key)) = t.header.extensions.iter().find(|(k, _)| k == SIGNATURE_KEY) {
                let at = t.header.id.strip_prefix("fuzz-").and_then(|r| r.split_once("-status")).map(|(c, _)| c);
                if let (true, Some(at)) = (key.starts_with("status "), at) {
                    // (a baseline written against a baseline scopes its statuses already)
                    let bare = key.split(" at ").next().unwrap_or(key).trim_end_matches(" elsewhere");
                    self.status_at.insert((bare.to_string(), at.to_string()));
                    // Every other command its bits showed on in that campaign.
                    for (_, v) in t.header.extensions.iter().filter(|(k, _)| k == STATUS_AT_KEY) {
                        for c in v.split_ascii_whitespace() {
                            self.status_at.insert((bare.to_string(), c.to_string()));
                        }
                    }
                }
                self.keys.insert(key.clone());
                self.recorded_on.insert(path.clone(), t.header.profiles.clone());
                let spec = t.header.extensions.iter().find(|(k, _)| k == PROFILE_SPEC_KEY).map(|(_, v)| v.clone());
                self.spec_of.insert(path.clone(), spec);
                n += 1;
            }
        }
        Ok(n)
    }

    /// The findings of the baseline recorded on profiles other than `profile`, with those
    /// profiles. A baseline says what is known of a hand under one profile: a signature found
    /// under `seed` is no knowledge of `bh8-262-4.3`, so the CLI refuses such a baseline.
    pub fn recorded_elsewhere(&self, profile: &str) -> Vec<(&Path, &[String])> {
        self.recorded_on
            .iter()
            .filter(|(_, ps)| !ps.iter().any(|p| p == profile))
            .map(|(f, ps)| (f.as_path(), ps.as_slice()))
            .collect()
    }

    /// The findings of the baseline recorded on another spec than the campaign's (its
    /// [`crate::report::ProfileSpec`]), with the digest each names: a profile is known by its
    /// spec, not its id, as certificates know it (a file declaring `bh8-262-4.4` with other
    /// contents is another profile). A finding that names no spec (written before findings
    /// named theirs) is taken as recorded on the built-in profile of its id, so it counts only
    /// against exactly that spec.
    pub fn recorded_on_another_spec(&self, spec: &crate::report::ProfileSpec) -> Vec<(&Path, Option<&str>)> {
        let builtin = spec.origin == crate::report::ProfileOrigin::Builtin;
        self.spec_of
            .iter()
            .filter(|(_, s)| match s {
                Some(s) => *s != spec.sha256,
                None => !builtin,
            })
            .map(|(f, s)| (f.as_path(), s.as_deref()))
            .collect()
    }

    /// Scopes a status difference whose bits the baseline already has (on some command):
    /// `at CMD` on a command it had them on (known), `elsewhere` on any other (new, and one
    /// finding however many commands show it).
    pub fn qualify(&self, sig: &mut FindingSignature) {
        sig.scope.clear();
        if sig.kind == "status" && sig.explanation.is_empty() {
            let key = sig.key();
            let here = (key.clone(), slug(&sig.command));
            if self.status_at.contains(&here) {
                sig.scope = format!("at {}", sig.command);
            } else if self.status_at.iter().any(|(k, _)| *k == key) {
                sig.scope = "elsewhere".into();
            }
        }
    }

    /// Why a finding is not new: in the baseline, or a known failure; `None` when it is new.
    pub fn explains(&self, profile: &str, id: &str, sig: &FindingSignature) -> Option<String> {
        let key = sig.key();
        if self.keys.contains(&key) || sig.scope.starts_with("at ") {
            return Some("in the baseline".to_string());
        }
        self.known
            .lookup(profile, id)
            .or_else(|| self.known.lookup(profile, &key))
            .map(|k| format!("known failure: {}", k.reason))
    }
}

/// The transcript header that names a written finding's signature key.
pub const SIGNATURE_KEY: &str = "x-signature";

/// The transcript header that names the digest of the profile spec a written finding was
/// found on ([`crate::report::ProfileSpec::digest`]).
pub const PROFILE_SPEC_KEY: &str = "x-profile-sha256";

impl FuzzOptions {
    /// Options for `target` with the defaults: 1000 runs, one worker, minimization on, and
    /// for `serial:` targets no EEPROM writes at all (a real hand's EEPROM wears out) and no change
    /// of the line's rate ([`Allowed::keep_rate`]).
    pub fn new(target: Target, profile: Arc<Profile>) -> FuzzOptions {
        let serial = matches!(target, Target::Serial { .. });
        let keep_rate = match &target {
            Target::Serial { baud, .. } => Some(*baud),
            _ => None,
        };
        FuzzOptions {
            open: OpenOptions { loaded_profile: Some(profile.clone()), ..OpenOptions::default() },
            target,
            profile,
            seed: 0,
            budget: Budget::Runs(1000),
            max_findings: None,
            corpus: None,
            out: None,
            allowed: Allowed { eeprom: !serial, keep_rate, ..Allowed::default() },
            write_budget: serial.then_some(0),
            jobs: 1,
            minimize: true,
            minimize_budget: 300,
            suite_seeds: true,
            stop: Arc::new(AtomicBool::new(false)),
            shard: None,
            baseline: Baseline::default(),
        }
    }
}

impl FuzzOptions {
    /// Whether answers get the wide bands of a hand outside this process (see
    /// [`case::build_case`]).
    pub fn wide(&self) -> bool {
        !matches!(self.target, Target::Sim { .. })
    }

    /// Whether every case starts with HI (a hand outside this process, when motion is allowed).
    pub fn home(&self) -> bool {
        self.wide() && self.allowed.motion
    }
}

/// Why a run could not go on (exit code 2): the target, the corpus or the output.
#[derive(Debug, thiserror::Error)]
pub enum FuzzError {
    /// The target could not be opened (or reopened).
    #[error("opening the target: {0}")]
    Open(#[source] LinkError),
    /// The corpus directory could not be read or written.
    #[error("corpus {path}: {source}")]
    Corpus {
        /// The file or directory.
        path: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// A finding could not be written.
    #[error("writing {path}: {source}")]
    Out {
        /// The file.
        path: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// The hand vanished and did not come back.
    #[error("the hand vanished and could not be reopened: {0}")]
    Vanished(String),
    /// The hand did not answer the liveness probe before the campaign.
    #[error("the hand at {target} did not answer the liveness probe (^C, CR, then a command line): {why}")]
    NotAlive {
        /// The target as written.
        target: String,
        /// What the probe found instead.
        why: String,
    },
    /// The target's motions end far sooner than a hand's (a simulator whose time follows the
    /// wire, such as `gcl sim --time fast`): ^C cannot land mid-motion there, so every ^C
    /// mid-motion would be a false finding.
    #[error(
        "the target's motions end at once: `{command}` from the home position took {took_ms} ms, \
         where the model's hand takes {model_ms} ms (a simulator with `--time fast`?); ^C cannot \
         land mid-motion on it, so run with `--no abort-timing`"
    )]
    NotRealTime {
        /// The motion command of the probe.
        command: String,
        /// How long the target took for it, bytes included.
        took_ms: u64,
        /// How long the model's hand moves for it, bytes aside.
        model_ms: u64,
    },
    /// No case the fuzzer can draw would be run (every one rests on a skipped decision):
    /// known before the campaign, so it is refused instead of dropping every case it draws.
    #[error("nothing to test: {0}")]
    NothingToTest(String),
}

use crate::align;
pub use crate::align::FindingSignature;

/// One distinct finding.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Finding {
    /// Its signature.
    pub signature: FindingSignature,
    /// The run (1-based, over all workers) that first found it.
    pub run: u64,
    /// Wall time from the start of the fuzzing run until it was first seen.
    #[serde(serialize_with = "ser_ms", deserialize_with = "de_ms", rename = "found_after_ms")]
    pub found_after: Duration,
    /// Actions of the case that first found it.
    pub original_actions: usize,
    /// The minimized actions.
    pub actions: Vec<HostAction>,
    /// The minimized transcript (the model's expectations; not in the JSON report, whose
    /// `transcript_text` is its text).
    #[serde(skip)]
    pub transcript: Transcript,
    /// The transcript's text.
    pub transcript_text: String,
    /// How the minimized transcript ends on the target (expected against actual).
    pub diff: String,
    /// Where the transcript was written.
    pub path: Option<PathBuf>,
    /// Why it is not new (in the baseline, a known failure), or `None` for a new finding.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub known: Option<String>,
    /// How strongly the failure binds the hand: the weakest level among the decisions it
    /// rests on (MUST when it rests on none below). A failure rests on the decisions of its
    /// failing step and the state decisions of the steps before it, not on the whole case's
    /// (see [`BuiltCase::rests_on`]).
    #[serde(default)]
    pub level: gcl_model::Level,
    /// Below MUST, the decisions at that level the failure rests on: the open points a hand
    /// may have decided otherwise (`--skip-decision` drops cases that rest on one).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rests_on: Vec<String>,
}

impl Finding {
    /// The level of a failure that rests on `decisions` (ids of `p`): the weakest of theirs,
    /// MUST when none is below; and, below MUST, those of `decisions` at that level, in the
    /// profile's order.
    pub fn binding(p: &Profile, decisions: &[String]) -> (gcl_model::Level, Vec<String>) {
        let ours = || p.decisions.iter().filter(|d| decisions.contains(&d.id));
        let level = ours().map(|d| d.level).max().unwrap_or_default();
        let rests_on =
            ours().filter(|d| level != gcl_model::Level::Must && d.level == level).map(|d| d.id.clone()).collect();
        (level, rests_on)
    }

    /// Whether the baseline does not explain it.
    pub fn is_new(&self) -> bool {
        self.known.is_none()
    }
}

fn ser_ms<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(d.as_millis() as u64)
}

fn de_ms<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Duration, D::Error> {
    u64::deserialize(d).map(Duration::from_millis)
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct FuzzSummary {
    /// Cases replayed against the target.
    pub runs: u64,
    /// Drawn action lists the model could not make a case of (dropped, not run).
    pub dropped: u64,
    /// Distinct findings, in the order found.
    pub findings: Vec<Finding>,
    /// Every coverage feature reached.
    pub features: BTreeSet<String>,
    /// Corpus entries at the end: the files of the `--corpus` folder, or without one the
    /// cases this run kept for new coverage (the suite's seeds are not counted).
    pub corpus: usize,
    /// EEPROM writes made.
    pub eeprom_writes: u64,
    /// Bytes on the wire in both directions during the cases (drains and minimization aside).
    pub wire_bytes: u64,
    /// The part of `wire_bytes` sent to the hand (the rest came from it: echoes, answers,
    /// prompts, banners).
    pub bytes_sent: u64,
    /// Lines (CRs) sent during the cases, counted as `wire_bytes` is.
    pub lines_sent: u64,
    /// Cases that passed a quick run on a kept link and were judged again thoroughly because
    /// bytes followed them (met when the next case's line was not quiet).
    pub rejudged: u64,
    /// Wall time of the run.
    pub elapsed: Duration,
    /// Time spent minimizing (part of `elapsed`).
    pub minimizing: Duration,
    /// Why the campaign ended before its budget because the hand stopped answering (a case
    /// met silence, then the hand failed the liveness probe or answered no command): an
    /// infrastructure end, exit 2, as `gcl conform`'s dead-hand rule.
    pub dead_hand: Option<String>,
    /// Whether [`FuzzOptions::stop`] ended the campaign (a signal).
    pub interrupted: bool,
    /// Why the campaign ended because it could not make cases: [`DROP_LIMIT`] drawn cases in
    /// a row were dropped (an infrastructure end, exit 2, as [`FuzzSummary::dead_hand`]).
    pub no_cases: Option<String>,
    /// Corpus files that did not read or parse, with why: skipped, and worth a warning.
    pub malformed_corpus: Malformed,
    /// Failures that did not fail again, the same way, when their minimized transcript was
    /// replayed on a fresh connection: notes, never findings.
    pub not_reproduced: Vec<NotReproduced>,
    /// Who the hand says it is, when it names another firmware than the profile models
    /// ([`gcl_conformance::identity::mismatch`]): said before the first case.
    pub identity: Option<String>,
    /// What the campaign left on a hand outside this process as it found it, checked at the
    /// end (the line's rate on a serial line; the EEPROM): one sentence each.
    pub hand_after: Vec<String>,
}

/// A failure whose minimized transcript did not fail again, with the same signature, on every
/// replay on a fresh connection ([`confirmations`]): a note, not a finding.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct NotReproduced {
    /// The signature it had when first met, as people read it.
    pub signature: String,
    /// Its key.
    pub key: String,
    /// Replays that failed with the same signature.
    pub reproduced: u32,
    /// Replays made.
    pub replays: u32,
    /// The minimized transcript's text (what was replayed).
    pub transcript_text: String,
    /// How it failed when met, on the campaign's connection (expected against actual).
    pub diff: String,
}

/// How many times a finding's minimized transcript is replayed on a fresh connection before it
/// is reported: every replay must fail with the same signature. A hand outside this process
/// (a line, a pipe, a socket: timing varies) gets three; the in-process simulator, whose runs
/// are the same every time, one.
pub fn confirmations(target: &Target) -> u32 {
    if matches!(target, Target::Sim { .. }) { 1 } else { 3 }
}

impl FuzzSummary {
    /// Cases per second of wall time, minimization excluded.
    pub fn cases_per_second(&self) -> f64 {
        self.per_second(self.runs)
    }

    /// A count per second of wall time, minimization excluded (as the counts are).
    pub fn per_second(&self, n: u64) -> f64 {
        let t = self.elapsed.saturating_sub(self.minimizing).as_secs_f64();
        if t > 0.0 { n as f64 / t } else { 0.0 }
    }
}

/// What the run tells its caller as it goes.
#[derive(Debug)]
pub enum Progress<'a> {
    /// A case ran.
    Run {
        /// Cases so far.
        runs: u64,
        /// Distinct findings so far.
        findings: usize,
        /// Coverage features so far.
        features: usize,
        /// Wall time so far.
        elapsed: Duration,
    },
    /// A new distinct finding, minimized.
    Finding(&'a Finding),
    /// A line about the hand before the first case (who it says it is, when that is not the
    /// firmware the profile models).
    Note(&'a str),
    /// A failure whose minimized transcript did not fail again the same way on a fresh
    /// connection: not a finding.
    NotReproduced(&'a NotReproduced),
    /// A finding reported earlier that an explanation found since covers: it is that bug, and
    /// no longer a finding of its own (its transcript is removed).
    Joined {
        /// The earlier finding.
        finding: &'a Finding,
        /// The explanation that covers it.
        explanation: &'a str,
    },
}

#[derive(Default)]
struct Shared {
    corpus: Vec<Vec<HostAction>>,
    features: BTreeSet<String>,
    findings: Vec<Finding>,
    /// Signatures seen (found or being minimized).
    seen: BTreeSet<String>,
    /// Every command each status key (its bits, unscoped) showed on: a finding keeps one, the
    /// first, and its transcript names them all (`x-status-at`) so that a `--baseline` made of
    /// it knows them all.
    status_at: BTreeMap<String, BTreeSet<String>>,
    /// What explains a finding so far (see [`judged`]).
    explained: Vec<String>,
    dropped: u64,
    wire_bytes: u64,
    bytes_sent: u64,
    lines_sent: u64,
    rejudged: u64,
    minimizing: Duration,
    error: Option<FuzzError>,
    /// Why the hand was found dead mid-campaign (see [`FuzzSummary::dead_hand`]).
    dead_hand: Option<String>,
    /// Drawn cases dropped since the last case ran, and why the last one was.
    dropped_in_a_row: u64,
    last_drop: String,
    /// See [`FuzzSummary::no_cases`].
    no_cases: Option<String>,
    /// See [`FuzzSummary::not_reproduced`].
    not_reproduced: Vec<NotReproduced>,
}

/// Drawn cases dropped in a row after which a campaign ends, having nothing to run: a few
/// seconds of drawing, where a campaign whose options leave it cases drops a few in a row.
pub const DROP_LIMIT: u64 = 5000;

impl Shared {
    /// Counts a drawn case dropped (`why`); past [`DROP_LIMIT`] in a row the campaign ends
    /// (`true`).
    fn dropped(&mut self, why: &str) -> bool {
        self.dropped += 1;
        self.dropped_in_a_row += 1;
        if self.last_drop != why {
            why.clone_into(&mut self.last_drop);
        }
        if self.dropped_in_a_row >= DROP_LIMIT && self.no_cases.is_none() {
            self.no_cases = Some(format!(
                "the last {DROP_LIMIT} drawn cases were all dropped (the last one: {}): the options leave (next to) \
                 nothing to test",
                self.last_drop
            ));
        }
        self.no_cases.is_some()
    }
}

/// Refuses, before a campaign, options under which no case would run: when the case of no
/// action at all (the preamble every case starts with) rests on a skipped decision, every
/// case does.
pub fn refuse_what_leaves_no_case(opts: &FuzzOptions) -> Result<(), FuzzError> {
    let Ok(b) = case::build_case_sending(&opts.profile, &[], "fuzz", "the preamble", opts.wide(), opts.home(), &[])
    else {
        return Ok(());
    };
    match skipped_decision(opts, &b) {
        Some(why) => Err(FuzzError::NothingToTest(format!(
            "every case starts with the suite's preamble, which {why}: no case would run"
        ))),
        None => Ok(()),
    }
}

/// Why a built case is not run for a decision the hand took differently, if it is not.
fn skipped_decision(opts: &FuzzOptions, b: &BuiltCase) -> Option<String> {
    let rests: Vec<String> = b
        .transcript
        .header
        .extensions
        .iter()
        .filter(|(k, _)| k == crate::suite::build::DECISIONS_KEY)
        .flat_map(|(_, v)| v.split_whitespace().map(str::to_string))
        .collect();
    let d = opts.baseline.known.skipped_by(&opts.profile.id, &rests)?;
    Some(format!("rests on decision {}, decided differently: {}", d.id, d.reason))
}

/// The wait of the dead-hand probe (as `gcl conform`'s).
const PROBE_WAIT: Duration = Duration::from_secs(5);

/// Why the hand is dead, or `None` when it answers: [`crate::conform::dead_hand`].
fn dead_hand(link: &mut dyn Link, p: &Profile) -> Option<String> {
    crate::conform::dead_hand(link, p, PROBE_WAIT)
}

/// The host sides of the suite's cases of a profile, as action lists (generated once per
/// profile and process).
pub fn suite_seeds(p: &Arc<Profile>) -> Arc<Vec<Vec<HostAction>>> {
    static CACHE: Mutex<BTreeMap<String, Arc<Vec<Vec<HostAction>>>>> = Mutex::new(BTreeMap::new());
    let mut c = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    c.entry(p.id.clone())
        .or_insert_with(|| {
            let cases = crate::suite::generate(p).unwrap_or_default();
            // A case whose setup places an object needs it: the fuzzer's hands have none.
            Arc::new(
                cases
                    .iter()
                    .filter(|c| c.header().setup.is_empty())
                    .map(|c| action::from_transcript(p, &c.transcript))
                    .filter(|a| !a.is_empty())
                    .collect(),
            )
        })
        .clone()
}

/// The content-hash name of a corpus entry.
pub fn corpus_name(actions: &[HostAction]) -> String {
    let json = serde_json::to_vec(actions).unwrap_or_default();
    format!("{}.json", &crate::digest::sha256_hex(&json)[..20])
}

pub use crate::fuzz::Malformed;

/// Reads every `*.json` entry of a corpus directory (created if missing); entries that do not
/// read or parse are skipped, and returned with why, so the caller can warn about them.
pub fn load_corpus(dir: &Path) -> Result<(Vec<Vec<HostAction>>, Malformed), FuzzError> {
    let err = |source| FuzzError::Corpus { path: dir.to_path_buf(), source };
    std::fs::create_dir_all(dir).map_err(err)?;
    let (entries, bad) = crate::fuzz::read_json_files(dir).map_err(err)?;
    Ok((entries.into_iter().map(|(_, a)| a).collect(), bad))
}

/// How many entries (`.json` files) the corpus folder holds.
fn corpus_files(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .map_or(0, |d| d.filter_map(Result::ok).filter(|e| e.path().extension().is_some_and(|x| x == "json")).count())
}

fn save_corpus(dir: &Path, actions: &[HostAction]) -> Result<(), FuzzError> {
    let path = dir.join(corpus_name(actions));
    if path.exists() {
        return Ok(());
    }
    let json = serde_json::to_vec_pretty(actions).unwrap_or_default();
    crate::report::write_atomic(&path, &json).map_err(|source| FuzzError::Corpus { path, source })
}

/// A worker's connection to the target: reopened when it fails; for `sim` targets a fresh
/// hand for every case, so a case never depends on the one before.
///
/// A hand outside this process is driven in two gears. A *quick* run follows the drain of
/// [`Hand::settle`], which ends at the first quiet moment of a few byte-times, and has no
/// trailing wait: the case's end is known from the model, and whatever a hand sends after it
/// is met by the next case's settle. A *thorough* run keeps the replayer's
/// quiet drain and trailing wait. Nothing is reported on a quick run alone: a failure, or
/// bytes left over after a case, is judged again by a thorough run (see `worker`).
struct Hand<'o> {
    opts: &'o FuzzOptions,
    link: Option<Box<dyn Link>>,
    /// Whether the link was just opened (its power-up banner may still be on the way).
    new: bool,
    /// Whether the last run failed: it stopped reading mid-case, so the next run drains
    /// thoroughly.
    dirty: bool,
    /// The trailing wait of a thorough run: [`TRAILING`], or [`SURE_TRAILING`] while a case is
    /// judged again or confirmed.
    trailing: Duration,
    /// Hands started ahead, not yet used, the oldest first: the fresh connections of a
    /// finding's confirmations over `exec:` (see [`Hand::open_ahead`]).
    ahead: std::collections::VecDeque<Box<dyn Link>>,
    /// Whether [`Hand::back_to_prompt`] failed on this link (it is not tried again there).
    unsynced: bool,
    /// Whether a transcript run on this link may have written the EEPROM (see
    /// [`Hand::start_afresh`]).
    saved_on_link: bool,
}

/// How long a link just opened to a hand outside this process is given to say its first byte
/// (a power-up banner) before the first case; a hand that says nothing costs this once.
const POWER_UP_WAIT: Duration = Duration::from_secs(2);

/// The most bytes of a power-up banner read to find its prompt (the rest is drained).
const POWER_UP_BYTES: usize = 4096;

/// ^C sent at most by [`Hand::back_to_prompt`]: more than the data bytes of the longest
/// control block (4 motors × LCV, LCPG and a 2-byte LCT), as the host client's resync.
const RESYNC_ATTEMPTS: usize = 18;

/// The quiet that ends [`Hand::back_to_prompt`] once a prompt came (prompts of earlier ^C may
/// still be on their way).
const RESYNC_QUIET: Duration = Duration::from_millis(50);

/// The shortest wait for each answer of [`Hand::back_to_prompt`]'s resynchronisation.
const RESYNC_WAIT: Duration = Duration::from_millis(200);

/// The trailing wait of a thorough run: bytes a hand sends after a case's last answer.
const TRAILING: Duration = Duration::from_millis(50);

/// The trailing wait of a thorough run that judges bytes already seen to follow a case (a case
/// judged again because bytes followed its quick run) or that confirms a finding. A hand
/// outside this process on a busy machine can be late by more than [`TRAILING`]: a finding of
/// bytes after the last answer then failed one of its confirmations and became a note (CI,
/// under the test lanes' load).
const SURE_TRAILING: Duration = Duration::from_millis(500);

impl<'o> Hand<'o> {
    fn new(opts: &'o FuzzOptions) -> Self {
        Hand {
            opts,
            link: None,
            new: true,
            dirty: false,
            trailing: TRAILING,
            ahead: Default::default(),
            unsynced: false,
            saved_on_link: false,
        }
    }

    /// Runs `f` with the longer trailing wait of [`SURE_TRAILING`] on a hand outside this
    /// process (the simulator in process answers whole, at once).
    fn surely<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        let outside = !matches!(self.opts.target, Target::Sim { .. });
        let was = std::mem::replace(&mut self.trailing, if outside { SURE_TRAILING } else { TRAILING });
        let r = f(self);
        self.trailing = was;
        r
    }

    fn link(&mut self) -> Result<&mut Box<dyn Link>, FuzzError> {
        let fresh = matches!(self.opts.target, Target::Sim { .. });
        if fresh || self.link.is_none() {
            self.new = true;
            self.unsynced = false;
            self.saved_on_link = false;
            self.link = Some(match self.ahead.pop_front() {
                Some(l) => l,
                None => gcl_host::target::open(&self.opts.target, &self.opts.open).map_err(FuzzError::Open)?,
            });
        }
        self.link.as_mut().ok_or_else(|| FuzzError::Vanished("no link".into()))
    }

    /// On an `exec:` target, starts hands until `n` wait unused, for the next fresh
    /// connections: their start-up (a process, an interpreter, a power-up banner) runs at
    /// once, not one after the other. A Python hand behind a pyenv shim took about 0.6 s to
    /// start, three times per finding (issue 37 item 4). A serial port or a TCP server takes one
    /// connection at a time: nothing is started ahead there, nor for a hand in this process.
    fn open_ahead(&mut self, n: u32) {
        if !matches!(self.opts.target, Target::Exec { .. }) {
            return;
        }
        while self.ahead.len() < n as usize {
            match gcl_host::target::open(&self.opts.target, &self.opts.open) {
                Ok(l) => self.ahead.push_back(l),
                // (the next connection opened in turn says what failed)
                Err(_) => return,
            }
        }
    }

    /// After a finding's confirmations, on an `exec:` target: the next case on a fresh hand.
    /// The campaign's link is then the last confirmation's, or the last earlier case tried
    /// before the failing one (see [`Met::before`]), and what those replays saved is in that
    /// hand's EEPROM, known to no list of the worker's: a later failure resting on it
    /// reproduced on no fresh hand (issue 37: `value at FLISTAV (MCV) after FDEF` after the
    /// confirmations of `value at FLISTV (MCV) after FDEF` on a hand whose FDEF skips MCV, an
    /// MCV the earlier case saved). A fresh `exec:` hand has the factory's EEPROM; a serial or
    /// TCP hand is the same hand after a reopen, so nothing is gained there; nor on a link
    /// where nothing saved (a fresh hand costs a process start: a Python hand's took about a
    /// second under load). Says whether the link starts afresh (the worker's lists of earlier
    /// cases are then emptied).
    fn start_afresh(&mut self) -> bool {
        if !matches!(self.opts.target, Target::Exec { .. }) || !self.saved_on_link {
            return false;
        }
        self.link = None;
        true
    }

    /// The quiet that ends a quick drain: four byte-times on a serial line (at least 1 ms),
    /// 1 ms elsewhere. Only what the last case left is drained; every case begins with ^C
    /// and RESET, whose exact answers catch anything later.
    fn quick_quiet(&self) -> Duration {
        match &self.opts.target {
            Target::Serial { baud, .. } => {
                Duration::from_secs_f64(40.0 / f64::from((*baud).max(1))).max(Duration::from_millis(1))
            }
            _ => Duration::from_millis(1),
        }
    }

    /// The longest wait for the rest of a line the hand parted in (see
    /// [`complete_parting_line`]): the profile's longest line twice over at the line's rate, and
    /// 20 ms for the hand to write it; 50 ms off a serial line.
    fn line_wait(&self) -> Duration {
        match &self.opts.target {
            Target::Serial { baud, .. } => {
                let bytes = 2.0 * self.opts.profile.framing.max_line as f64;
                Duration::from_secs_f64(10.0 * bytes / f64::from((*baud).max(1))) + Duration::from_millis(20)
            }
            _ => Duration::from_millis(50),
        }
    }

    /// Whether a quick run comes next.
    fn quick(&self, thorough: bool) -> bool {
        !matches!(self.opts.target, Target::Sim { .. }) && !thorough && !self.new && !self.dirty && self.link.is_some()
    }

    /// Before a quick run: drains the line to its first quiet moment and says whether there
    /// was anything to drain (the case before said more than the model did, or said it late).
    fn settle(&mut self) -> Result<bool, FuzzError> {
        if !self.quick(false) {
            return Ok(false);
        }
        let quiet = self.quick_quiet();
        let limit = crate::suite::replay_options().drain_limit;
        match crate::replay::discard(self.link()?.as_mut(), quiet, limit) {
            Ok(d) => Ok(d.bytes > 0),
            Err(_) => {
                self.link = None;
                Ok(false)
            }
        }
    }

    /// Replays a case's transcript with deadlines from the model; `thorough` as the type says.
    fn run(&mut self, t: &Transcript, thorough: bool) -> Result<ReplayOutcome, FuzzError> {
        let out = self.replay(t, thorough)?;
        self.saved_on_link |= t.header.requires.contains(&gcl_transcript::Requirement::Eeprom);
        if !out.is_pass() && self.opts.wide() && t.header.requires.contains(&gcl_transcript::Requirement::Eeprom) {
            self.restore_eeprom()?;
        }
        Ok(out)
    }

    /// After a case that writes the EEPROM failed on a hand outside this process: the factory
    /// values written back (defaults, then save, for the motors and the globals), as the case
    /// would have done at its end had it got there. Otherwise the values it saved stay in the
    /// hand for every later case: a later RESET or load reads them back, and each such read is a
    /// finding of its own (`value at FLISTV after RESET` in a campaign against a bug in the
    /// RealTime flags). The writes are the case's own restore, already in its budget.
    fn restore_eeprom(&mut self) -> Result<(), FuzzError> {
        let p = &self.opts.profile;
        let lines: Vec<HostAction> = [
            gcl_model::spec::CommandKind::MotorDefaults,
            gcl_model::spec::CommandKind::MotorSave,
            gcl_model::spec::CommandKind::GlobalDefaults,
            gcl_model::spec::CommandKind::GlobalSave,
        ]
        .into_iter()
        .filter_map(|k| p.command_of_kind(k))
        .map(|id| HostAction::Line(p.command(id).name.clone()))
        .collect();
        if let Ok(b) = build_case(p, &lines, "fuzz", "EEPROM restore", true, false) {
            self.replay(&b.transcript, true)?;
        }
        Ok(())
    }

    /// After a failed run on a kept link to a hand outside this process: brings the hand back
    /// to its prompt before the next run: ^C, one at a time, until an answer holds a prompt
    /// (as the liveness probe, any prompt-like answer: a hand with another line ending is back
    /// too), then the line's quiet. A run that failed stopped sending mid-case, and may have
    /// left the hand in the middle of a RealTime block (a hand whose control block is longer
    /// than the model's waits for more data): there a ^C is data, so the next case's first ^C
    /// completed the block and was answered `*`, and that case failed as `value at ^C`, on this
    /// link only (issue 37: the candidate that never reproduced on a fresh connection). A hand
    /// that does not come back within [`RESYNC_ATTEMPTS`] is left as it is, and not tried again
    /// on this link (a hand that never says a prompt would pay the attempts after every failed
    /// case): the next run says how it answers; a lost link is reopened. Says whether the hand
    /// came back.
    fn back_to_prompt(&mut self) -> bool {
        if self.unsynced {
            return false;
        }
        let wait = self.line_wait().max(RESYNC_WAIT);
        let p = self.opts.profile.clone();
        let prompt = p.framing.prompt.trim_end().as_bytes().to_vec();
        let Some(link) = self.link.as_mut() else { return false };
        let mut got = Vec::new();
        for _ in 0..RESYNC_ATTEMPTS {
            if link.send(&[p.framing.abort]).is_err() {
                self.link = None;
                return false;
            }
            got.clear();
            let until = link.elapsed() + wait;
            loop {
                if !prompt.is_empty() && got.windows(prompt.len()).any(|w| w == prompt.as_slice()) {
                    let _ = crate::replay::discard(link.as_mut(), RESYNC_QUIET, wait);
                    return true;
                }
                let left = until.saturating_sub(link.elapsed());
                if left.is_zero() || got.len() > POWER_UP_BYTES {
                    break;
                }
                match link.recv(&mut got, left) {
                    Ok(0) => break,
                    Ok(_) => {}
                    Err(_) => {
                        self.link = None;
                        return false;
                    }
                }
            }
        }
        self.unsynced = true;
        false
    }

    /// The dead-hand rule after a case met silence: the hand brought back to its prompt
    /// first ([`Hand::back_to_prompt`]). A hand that waits for the rest of a RealTime block (its
    /// control block is longer than the model's) takes the probe's ^C and CR as data: it is
    /// not dead, and it was said to be (`lcv-ignored` over exec ended its campaigns so).
    fn dead(&mut self) -> Result<Option<String>, FuzzError> {
        let _ = self.back_to_prompt();
        let p = self.opts.profile.clone();
        Ok(dead_hand(self.link()?.as_mut(), &p))
    }

    /// One replay of a transcript (see [`Hand::run`]).
    fn replay(&mut self, t: &Transcript, thorough: bool) -> Result<ReplayOutcome, FuzzError> {
        let p = self.opts.profile.clone();
        let mut ro = ReplayOptions { trailing: self.trailing, ..crate::suite::replay_options() };
        let outside = !matches!(self.opts.target, Target::Sim { .. });
        if outside {
            let case = Case { profile: p.id.clone(), transcript: t.clone() };
            let policy = DeadlinePolicy::for_target(&self.opts.target);
            if let Some(pred) = deadline::predict(&case, &p) {
                let baud = match &self.opts.target {
                    Target::Serial { baud, .. } => Some(*baud),
                    _ => None,
                };
                ro.budgets = deadline::budgets(&p, &case, &pred, &policy, baud);
            }
            ro.silent_wait = policy.silent_wait;
        }
        let quick_quiet = self.quick_quiet();
        // A serial port or TCP connection opened again after a failed run meets the same hand,
        // as a kept link does: it may wait mid-block too. Over a pty a finding's three
        // confirmations (each on a port opened again) began with a ^C such a hand took as
        // block data, and `missing at RealTime block` of `lcpg-ignored` and `lcv-ignored` became
        // notes (0 and 1 of 3, issue 37's pty sweep). A new `exec:` hand is another process.
        if outside && self.dirty && self.link.is_none() && !matches!(self.opts.target, Target::Exec { .. }) {
            self.link()?;
        }
        // (the resynchronisation ends in a quiet line: the replay's drain need not wait one out
        // again)
        if outside && self.dirty && self.back_to_prompt() {
            ro.drain_quiet = quick_quiet;
        }
        if self.link.is_none() {
            ro.drain_quiet = crate::suite::replay_options().drain_quiet.max(Duration::from_millis(300));
        }
        // A quick run's drain is the one [`Hand::settle`] made just before it.
        if self.quick(thorough) {
            ro.drain_quiet = Duration::ZERO;
            ro.trailing = Duration::ZERO;
        }
        let line_wait = self.line_wait();
        let opened = self.link.is_none();
        let link = self.link()?;
        if opened && outside {
            // A hand just started (a child process) may print its power-up banner later than
            // the drain's quiet: under load a Python hand's came after 300 ms, and the first
            // case met it as the answer to its ^C. Its first byte is waited for, a while.
            // A banner that ends in the prompt has ended: only what follows at once is
            // drained; otherwise the line must fall quiet. The replay's own drain then only
            // takes what followed (it waited out the same quiet again: with the quiet after
            // the prompt, 600 ms per fresh connection, three per finding).
            let mut first = Vec::new();
            if link.recv(&mut first, POWER_UP_WAIT).is_ok_and(|n| n > 0) {
                let prompt = [p.framing.line_ending.as_bytes(), p.framing.prompt.as_bytes()].concat();
                let until = link.elapsed() + ro.drain_limit;
                let mut quiet = ro.drain_quiet;
                while first.len() < POWER_UP_BYTES && link.elapsed() < until {
                    if first.ends_with(&prompt) {
                        quiet = quick_quiet;
                        break;
                    }
                    if !link.recv(&mut first, ro.drain_quiet).is_ok_and(|n| n > 0) {
                        break;
                    }
                }
                let _ = crate::replay::discard(link.as_mut(), quiet, ro.drain_limit);
                ro.drain_quiet = quick_quiet;
            }
        }
        let mut out = replay(t, link.as_mut(), &ro);
        if outside {
            complete_parting_line(link.as_mut(), &mut out, &p, line_wait);
        }
        self.new = false;
        self.dirty = !out.is_pass();
        if matches!(out, ReplayOutcome::Disconnected(_)) {
            self.link = None;
        }
        Ok(out)
    }
}

/// After a mismatch on a hand outside this process, reads on until the line the hand parted in
/// has ended (its line ending or the prompt after the parting byte), at most `wait`, and adds
/// what came to the failing step's answer. The replayer stops reading at the parting byte, and
/// on a serial line the rest of the line is still on its way then: `1 1` of `1 1 0 1` reads as a
/// wrong value, where the whole line shows the values in another order (the signature and the
/// explanations judge the line the hand sent, as they do in process, where an answer comes
/// whole). Bytes past the line's end that came with it are kept too; nothing else is read.
fn complete_parting_line(link: &mut dyn Link, out: &mut ReplayOutcome, p: &Profile, wait: Duration) {
    let ReplayOutcome::Mismatch(m) = out else { return };
    if m.trailing {
        return;
    }
    let Some(e) = m.exchange.last_mut() else { return };
    let eol = p.framing.line_ending.as_bytes();
    let ends = |r: &[u8]| {
        let rest = r.get(m.offset..).unwrap_or_default();
        eol.is_empty() || rest.windows(eol.len()).any(|w| w == eol)
    };
    let ceiling = m.offset.saturating_add(crate::replay::ceiling_for(eol.len() + p.framing.max_line));
    let until = link.elapsed() + wait;
    let before = e.received.len();
    while !ends(&e.received) && e.received.len() < ceiling {
        let left = until.saturating_sub(link.elapsed());
        if left.is_zero() {
            break;
        }
        match link.recv(&mut e.received, left) {
            Ok(0) | Err(_) => break,
            Ok(_) => {}
        }
    }
    if e.received.len() > before {
        m.actual = gcl_transcript::matcher::show(e.received.get(m.offset..).unwrap_or_default(), m.form);
    }
}

/// The signature of a failed replay of a built case, `None` for a pass (see [`crate::align`]).
pub fn signature(p: &Profile, built: &BuiltCase, out: &ReplayOutcome, whole_reads: bool) -> Option<FindingSignature> {
    // A pass (most cases) has no signature.
    out.failed_step()?;
    align::signature(p, &built.transcript, &built.model, out, whole_reads)
}

/// [`signature`], then what explains the whole failure, if something does (see [`explain`]).
///
/// `known`: what already explains a finding of this campaign. A failure of any kind that one
/// of them explains is that bug showing again (a move's status, a RealTime block read after
/// the wrong motor moved, a ^C that lands elsewhere), so it takes its key. A new explanation
/// is looked for only where the evidence is exact enough not to fit by chance:
///
/// - a value read back in an answer line;
/// - a RealTime block's answer on a link that hands over answers whole (the in-process sim),
///   where a rewrite must give the block's exact size and every field within the model's
///   tight bands, and still another layout of the same size can fit by chance: such a new
///   explanation holds only if the hand, replayed the whole case, answers as the rewrite does;
/// - on a hand outside this process, a value or a block's answer (or an answer cut short) that
///   a model holding the hypothesis expects where the profile's model does not
///   ([`variant::explains`]), which holds only if the hand answers the hypothesis's own case
///   as it expects up to the step where it parted ([`confirms`]): a few cases per finding.
///
/// Not from a status: its key is already its bits, whatever command shows them, and a set
/// without effect would explain a status never reported as well as the bug that never reports
/// it (mpe-ignored gave six findings when statuses were explained afresh). Nor from framing
/// outside blocks, a restart, a flood or a lost link: no effect read back.
fn judged(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    actions: &[HostAction],
    built: &BuiltCase,
    out: &ReplayOutcome,
    known: &[String],
) -> Result<Option<FindingSignature>, FuzzError> {
    let Some(mut sig) = signature(&opts.profile, built, out, !opts.wide()) else { return Ok(None) };
    let block = sig.command == "RealTime block";
    let rewrite = sig.kind == "value" && !block || block && !opts.wide();
    let fresh = Fresh {
        rewrite,
        exact: rewrite || block || sig.kind == "missing",
        decision: sig.kind == "status" && !opts.wide(),
    };
    let link = sig.kind == "link";
    if !link && let Some(e) = explain(opts, hand, actions, built, out, known, fresh, &sig.command)? {
        // A block's answer that a rewrite fits up to where the hand parted may fit by chance
        // (another layout of the same size, values within the bands): a new explanation from
        // one holds only if the hand answers the whole case as the rewrite does. (Outside this
        // process a rewrite explains afresh only a value read back.)
        let check = block && !known.contains(&e.says) && !e.exact;
        let confirmed = match (&e.whole, check) {
            (_, false) => true,
            (Some(t), true) => confirms(opts, &hand.run(t, true)?, out),
            (None, true) => false,
        };
        if confirmed {
            sig.explanation = e.says;
        } else if let Some(says) = variant::explains(opts, hand, actions, built, out, known, fresh)? {
            // (a rewrite's chance fit, unconfirmed, leaves the case to a model that answers
            // it as the hand did)
            sig.explanation = says;
        }
    }
    opts.baseline.qualify(&mut sig);
    Ok(Some(sig))
}

/// One hypothesis about the hand: the case's actions as the hand took them, and what that
/// says.
struct Hypothesis {
    /// What it says (a finding's key when it holds).
    says: String,
    /// The actions as the hand would have taken them.
    actions: Vec<HostAction>,
    /// Lines rewritten as sent and as the variant sends them: where the hand's echo of the
    /// first is taken as the second. Steps whose line changed otherwise are not compared.
    echoes: Vec<(String, String)>,
    /// A parameter stored as set but without effect: steps that read it back (a get naming
    /// it, a listing of values) are held to the case's own expectation, not the rewrite's.
    stored: Option<gcl_model::spec::ParamId>,
    /// The commands at which it may explain a failure of any kind afresh, a status included:
    /// those of the lines it rewrites, where the model refuses them and the hand did not (see
    /// [`explain`]). Elsewhere it explains only once known: a rewrite that changes the state
    /// can loosen a later step's expectation enough to fit a failure of another bug.
    any_kind: Vec<String>,
}

/// What explains a failure as one bug, tried on the model: the case's actions rewritten as a
/// hand with that bug would take them, rebuilt by the model, and held against what the hand
/// answered at every step from the first rewritten one up to the failing one. A bug whose
/// first difference shows wherever its effect is read back (a motor prefix that reaches
/// another motor, a parameter stored but without effect) otherwise gives as many signatures
/// as there are commands that read it back; the explanation is the one thing they share, and
/// the finding's key. Tried, in order:
///
/// - a motor prefix read as its motors and one more: every line with that prefix widened
///   (written out in motor digits; `123+4`);
/// - a set without effect: the parameter's pairs dropped from every set line (`MCV set without
///   effect`); the set lines' own answers are not compared, and reads of the parameter are
///   held to the case's own expectation (the hand stores what was set).
///
/// The rewrite's blocks send the bytes the hand was sent where its layout gives them the same
/// size; a block the rewrite must encode anew (another control layout) sends other bytes, and
/// its answer is not compared, as for any other line the rewrite changed. `known` explanations
/// are tried first; the others only when `fresh`, and a new one holds only if no other new one
/// does (a case that two bugs explain alike tells neither: lcvc-ignored's blocks were once
/// explained as `prefix 2+1`).
#[allow(clippy::too_many_arguments)]
fn explain(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    actions: &[HostAction],
    built: &BuiltCase,
    out: &ReplayOutcome,
    known: &[String],
    fresh: Fresh,
    at: &str,
) -> Result<Option<Explained>, FuzzError> {
    if let Some(e) = explain_by_rewrite(opts, actions, built, out, known, fresh.rewrite, at) {
        return Ok(Some(e));
    }
    // (a variant's is shown: byte for byte in process, confirmed on the hand outside it)
    Ok(variant::explains(opts, hand, actions, built, out, known, fresh)?.map(|says| Explained {
        says,
        whole: None,
        exact: true,
    }))
}

/// Whether a replay `again` of a hypothesis's case on a hand outside this process confirms it
/// for the failure `out`: the hand answers it as it expects up to the step where it parted
/// from the case, and that step too (a case that two of the hand's differences meet fails
/// later at the other). In process: the whole case.
fn confirms(opts: &FuzzOptions, again: &ReplayOutcome, out: &ReplayOutcome) -> bool {
    match (opts.wide(), again.failed_step(), out.failed_step()) {
        (_, None, _) => true,
        (true, Some(s), Some(failed)) => s > failed,
        _ => false,
    }
}

/// The explanation of a prefix the hand accepts on a command that takes none (a rewrite's and
/// a [`variant`]'s: one key for the bug whichever finds it).
const PREFIX_ACCEPTED: &str = "prefix accepted on a command that takes none";

/// Where [`explain`] may find an explanation no finding has yet: by a rewrite (a value read
/// back; a block in process), and by a model that holds the hypothesis (a value, a block, or an
/// answer cut short: the hand said part of it, then nothing; see [`variant::explains`]).
#[derive(Clone, Copy)]
struct Fresh {
    rewrite: bool,
    exact: bool,
    /// In process, from a status too, but only the other side of a decision the model takes
    /// (a refused set applied in part, RESET keeping RAM, a prefix accepted): a model that
    /// holds it answering every step byte for byte as the hand did, the status included. (Not
    /// a set without effect: that explains a status never reported as well as the bug that
    /// never reports it, as mpe-ignored showed.)
    decision: bool,
}

impl Fresh {
    const NONE: Fresh = Fresh { rewrite: false, exact: false, decision: false };
}

/// [`explain`]'s rewrites (see there); what they cannot follow, [`variant`] may still name.
///
/// The hypotheses (prefixes widened, sets without effect, a prefix accepted) → the known ones
/// first, the rest when `fresh` → the first that holds on the hand's answers.
fn explain_by_rewrite(
    opts: &FuzzOptions,
    actions: &[HostAction],
    built: &BuiltCase,
    out: &ReplayOutcome,
    known: &[String],
    fresh: bool,
    at: &str,
) -> Option<Explained> {
    let p = &opts.profile;
    let failed = out.failed_step()?;
    let mut hyps = prefix_hypotheses(p, actions);
    hyps.extend(set_hypotheses(p, actions));
    hyps.extend(prefix_accepted_hypothesis(p, actions));
    let answered = answered_before_abort(p, actions, built, out);
    // What already explains a finding first, then (when `fresh`) the rest.
    hyps.retain(|h| fresh || h.any_kind.iter().any(|c| c == at) || known.contains(&h.says));
    if hyps.is_empty() {
        return None;
    }
    hyps.sort_by_key(|h| !known.contains(&h.says));
    let mut found: Option<Explained> = None;
    for h in hyps {
        let Some(whole) = rewrite_holds(opts, &h, &answered, built, out, failed) else { continue };
        if known.contains(&h.says) {
            return Some(Explained { says: h.says, whole: None, exact: false });
        }
        // (a new one: another bug that explains the case as well leaves it unexplained)
        if found.is_some() {
            return None;
        }
        found = Some(Explained { says: h.says, whole, exact: false });
    }
    found
}

/// Takes an action; gives its line, when it sends one (a line, or a line then ^C).
fn line_of(a: &HostAction) -> Option<String> {
    match a {
        HostAction::Line(l) | HostAction::LineThenAbort { line: l, .. } => Some(l.clone()),
        _ => None,
    }
}

/// Takes an action that sends a line and another line; gives the action sending that one.
fn with_line(a: &HostAction, l: String) -> HostAction {
    match a {
        HostAction::LineThenAbort { after_ms, .. } => HostAction::LineThenAbort { line: l, after_ms: *after_ms },
        _ => HostAction::Line(l),
    }
}

/// Takes a line; gives its shortest tail that is the same command (`command`), unprefixed.
fn unprefixed_tail<'l>(p: &Profile, line: &'l str, command: gcl_model::spec::CommandId) -> Option<&'l str> {
    use gcl_model::grammar::{Line, parse_line};
    (1..line.len()).filter(|k| line.is_char_boundary(*k)).map(|k| &line[k..]).find(
        |t| matches!(parse_line(p, t.as_bytes()), Ok(Line::Command(d)) if d.prefix.is_none() && d.command == command),
    )
}

/// Takes the case's actions; gives the prefix hypotheses: each prefix of its lines widened by
/// one motor, on every line with that prefix (wider prefixes first).
fn prefix_hypotheses(p: &Profile, actions: &[HostAction]) -> Vec<Hypothesis> {
    use gcl_model::MotorSet;
    use gcl_model::grammar::{Line, parse_line};
    let digits = |m: MotorSet| m.iter().map(|x| x.to_string()).collect::<String>();
    let mut hyps: Vec<Hypothesis> = Vec::new();
    // Prefixes: each prefixed line, its prefix, and the line without it (the shortest tail
    // that is the same command, unprefixed).
    let mut prefixed: Vec<(usize, MotorSet, String)> = Vec::new();
    for (i, a) in actions.iter().enumerate() {
        let Some(line) = line_of(a) else { continue };
        let Ok(Line::Command(c)) = parse_line(p, line.as_bytes()) else { continue };
        let Some(pre) = c.prefix else { continue };
        if let Some(t) = unprefixed_tail(p, &line, c.command) {
            prefixed.push((i, pre, t.to_string()));
        }
    }
    // (wider prefixes first: where a group's line and a single motor's line both moved the
    // motor read back, the group's name is the likelier slip)
    let mut sets: Vec<MotorSet> = prefixed.iter().map(|(_, s, _)| *s).collect();
    sets.sort_by_key(|s| (std::cmp::Reverse(s.len()), s.bits()));
    sets.dedup();
    for pre in sets {
        for m in MotorSet::ALL.iter().filter(|m| !pre.contains(*m)) {
            let wide = MotorSet::from_bits(pre.bits() | MotorSet::single(m).map_or(0, MotorSet::bits));
            let mut h = Hypothesis {
                says: format!("prefix {}+{m}", digits(pre)),
                actions: actions.to_vec(),
                echoes: Vec::new(),
                stored: None,
                any_kind: Vec::new(),
            };
            for (i, _, tail) in prefixed.iter().filter(|(_, s, _)| *s == pre) {
                let new_line = format!("{}{tail}", digits(wide));
                h.echoes.push((line_of(&actions[*i]).unwrap_or_default(), new_line.clone()));
                h.actions[*i] = with_line(&actions[*i], new_line);
            }
            hyps.push(h);
        }
    }
    hyps
}

/// Takes the case's actions; gives the sets-without-effect hypotheses: a parameter's pair
/// dropped from every set line, one hypothesis per parameter.
fn set_hypotheses(p: &Profile, actions: &[HostAction]) -> Vec<Hypothesis> {
    use gcl_model::grammar::{Args, Line, parse_line};
    use gcl_model::spec::CommandKind;
    // Sets without effect: a parameter's pair dropped from every set line (a line left without
    // pairs becomes an empty line, which changes nothing, keeps the steps in step and is
    // answered as the set was, but for the echo: the hand's echo of the line as sent is taken
    // as the rewrite's line).
    let mut by_param: BTreeMap<gcl_model::spec::ParamId, Vec<(usize, String)>> = BTreeMap::new();
    for (i, a) in actions.iter().enumerate() {
        let Some(line) = line_of(a) else { continue };
        let Ok(Line::Command(c)) = parse_line(p, line.as_bytes()) else { continue };
        let (CommandKind::MotorSet | CommandKind::GlobalSet, Args::Pairs(pairs)) = (c.kind(p), &c.args) else {
            continue;
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.len() != 1 + 2 * pairs.len() {
            continue;
        }
        for (n, (id, _)) in pairs.iter().enumerate() {
            let kept: Vec<&str> =
                words.iter().enumerate().filter(|(w, _)| *w != 1 + 2 * n && *w != 2 + 2 * n).map(|(_, x)| *x).collect();
            let rewritten = if kept.len() > 1 { kept.join(" ") } else { String::new() };
            by_param.entry(*id).or_default().push((i, rewritten));
        }
    }
    let mut hyps = Vec::new();
    for (id, lines) in by_param {
        let mut v = actions.to_vec();
        let mut echoes = Vec::new();
        for (i, l) in lines {
            echoes.push((line_of(&actions[i]).unwrap_or_default(), l.clone()));
            v[i] = with_line(&actions[i], l);
        }
        hyps.push(Hypothesis {
            says: format!("{} set without effect", p.param(id).name),
            actions: v,
            echoes,
            stored: Some(id),
            any_kind: Vec::new(),
        });
    }
    hyps
}

/// Takes the case's actions; gives the prefix-accepted hypothesis, when a line is refused for
/// its prefix alone: every such line sent without it.
fn prefix_accepted_hypothesis(p: &Profile, actions: &[HostAction]) -> Option<Hypothesis> {
    use gcl_model::grammar::{Line, parse_line};
    // A prefix accepted where the command takes none: every line the model refuses for its
    // prefix alone, sent without it (the shortest tail that is the same command unprefixed).
    // The hand's echo is of the line as sent. A hand that ignores the prefix answers as the
    // command does, where the model answers 4096; one that refuses it otherwise does not.
    let mut accepted = Hypothesis {
        says: PREFIX_ACCEPTED.to_string(),
        actions: actions.to_vec(),
        echoes: Vec::new(),
        stored: None,
        any_kind: Vec::new(),
    };
    for (i, a) in actions.iter().enumerate() {
        let Some(line) = line_of(a) else { continue };
        let Err(r) = parse_line(p, line.as_bytes()) else { continue };
        if r.problems != [gcl_model::grammar::Problem::PrefixNotAllowed] {
            continue;
        }
        let lenient = gcl_model::grammar::ParseOptions { ignore_forbidden_prefix: true, ..Default::default() };
        let Ok(Line::Command(c)) = gcl_model::grammar::parse_line_with(p, line.as_bytes(), lenient) else { continue };
        if let Some(t) = unprefixed_tail(p, &line, c.command) {
            accepted.echoes.push((line.clone(), t.to_string()));
            accepted.any_kind.push(p.command(c.command).name.clone());
            accepted.actions[i] = with_line(a, t.to_string());
        }
    }
    (!accepted.echoes.is_empty()).then_some(accepted)
}

/// Takes a step of a replay; gives what the hand answered to it.
fn received_at(out: &ReplayOutcome, s: usize) -> Option<Vec<u8>> {
    out.exchange().iter().find(|e| e.step == s).map(|e| e.received.clone())
}

/// Takes a step; gives the bytes it sends.
fn sent_by(s: &gcl_transcript::Step) -> Option<Vec<u8>> {
    s.send.as_ref().map(|h| h.bytes.clone())
}

/// Takes the case's actions and the replay; gives, per action, whether it is a line sent then
/// aborted whose answer the hand completed before the ^C (the host waited for it).
fn answered_before_abort(p: &Profile, actions: &[HostAction], built: &BuiltCase, out: &ReplayOutcome) -> Vec<bool> {
    // A line sent and then aborted whose answer the hand completed before the ^C (the host
    // waited for it, as the case expected): in a rewrite the ^C comes after the answer too,
    // wherever the model would have had it land.
    let pe = [p.framing.line_ending.as_bytes(), p.framing.prompt.as_bytes()].concat();
    let mut answered = Vec::new();
    let mut from = 0;
    for a in actions {
        let HostAction::LineThenAbort { line, .. } = a else {
            answered.push(false);
            continue;
        };
        let mut bytes = line.as_bytes().to_vec();
        bytes.push(p.framing.terminator);
        let at = (from..built.transcript.steps.len())
            .find(|s| sent_by(&built.transcript.steps[*s]).as_deref() == Some(&bytes[..]));
        from = at.map_or(from, |s| s + 1);
        // (the step's answer ends at a prompt after the line's echo: not at the answer before
        // it, which ends a step whose line is answered in the next one)
        let echoed = |r: &[u8]| !p.framing.echo || r.windows(line.len()).any(|w| w == line.as_bytes());
        answered.push(at.and_then(|s| received_at(out, s)).is_some_and(|r| r.ends_with(&pe) && echoed(&r)));
    }
    answered
}

/// Takes a hypothesis's actions and which were answered before their ^C; gives the actions
/// in the hand's time (such a line sent, then ^C after its answer).
fn in_hand_time(v: Vec<HostAction>, answered: &[bool]) -> Vec<HostAction> {
    v.into_iter()
        .zip(answered)
        .flat_map(|(a, done)| match a {
            HostAction::LineThenAbort { line, .. } if *done => vec![HostAction::Line(line), HostAction::Abort],
            a => vec![a],
        })
        .collect()
}

/// Takes a step and a parameter; gives whether the step's line reads the parameter back.
fn reads_back(p: &Profile, s: &gcl_transcript::Step, id: gcl_model::spec::ParamId) -> bool {
    use gcl_model::grammar::{Args, Line, parse_line};
    use gcl_model::spec::CommandKind;
    let line = sent_by(s).unwrap_or_default();
    let line = line.strip_suffix(&[p.framing.terminator]).unwrap_or(&line);
    match parse_line(p, line) {
        Ok(Line::Command(c)) => match (c.kind(p), &c.args) {
            (CommandKind::MotorGet | CommandKind::GlobalGet, Args::Names(ids)) => ids.contains(&id),
            (k, _) => matches!(
                k,
                CommandKind::MotorListValues
                    | CommandKind::MotorListAllValues
                    | CommandKind::GlobalListValues
                    | CommandKind::GlobalListAllValues
            ),
        },
        _ => false,
    }
}

/// Takes a hypothesis and the replay that failed at step `failed`: builds its rewrite and
/// judges the hand's answers by it. Gives `None` when it does not hold, else the whole case
/// as the hand meets it under the explanation (when the rewrite keeps the steps' count).
fn rewrite_holds(
    opts: &FuzzOptions,
    h: &Hypothesis,
    answered: &[bool],
    built: &BuiltCase,
    out: &ReplayOutcome,
    failed: usize,
) -> Option<Option<Transcript>> {
    let p = &opts.profile;
    let received = |s: usize| received_at(out, s);
    // (the blocks send the bytes the hand was sent, whatever layout the rewrite has)
    let b = build_for_sending(opts, &in_hand_time(h.actions.clone(), answered), "fuzz", "explain", &built.block_bytes)
        .ok()?;
    let (old, new) = (&built.transcript.steps, &b.transcript.steps);
    if new.len() <= failed || old.len() <= failed {
        return None;
    }
    let d = (0..=failed).find(|s| sent_by(&old[*s]) != sent_by(&new[*s]))?;
    // The hand's answers from step d on, as one stream: a rewrite that changes a block's
    // size moves where one step's answer ends and the next begins (the replay read each
    // step as long as the original case expected), so the rewrite's expectations are
    // matched in turn along the stream, each ending where the next byte would break it.
    let gots = (d..=failed).map(received).collect::<Option<Vec<Vec<u8>>>>()?;
    let reads = |s: &gcl_transcript::Step, id: gcl_model::spec::ParamId| reads_back(p, s, id);
    let (stream, judges, need, complete) = rewritten_stream(p, h, &gots, d, failed, old, new, &reads, &sent_by);
    let mismatch = matches!(out, ReplayOutcome::Mismatch(_));
    // (the values the hand's answers before step d captured, as the rewrite's steps there
    // capture them: a relation from d on reads them)
    let mut caps = gcl_transcript::Captures::new();
    for (s, step) in new.iter().enumerate().take(d) {
        let got = received(s).unwrap_or_default();
        match step.expect.matches_with(&caps, &got) {
            Some(c) => caps = c,
            None => break,
        }
    }
    if !(complete && follows(&judges, &stream, need, mismatch, &caps)) {
        return None;
    }
    // The whole case as the hand meets it under the explanation: the rewrite's steps,
    // with the lines it rewrote sent as they were (their answers are echo and prompt,
    // or held to the case's own expectation).
    Some((old.len() == new.len()).then(|| {
        let mut t = b.transcript.clone();
        for (i, st) in t.steps.iter_mut().enumerate() {
            if sent_by(&old[i]) != sent_by(st) {
                *st = old[i].clone();
            }
        }
        t
    }))
}

/// The hand's answers to steps `d..=failed` (`gots`, one per step) as one stream, as the
/// hypothesis `h` would have the hand answer them, with the step each part is judged by.
///
/// Where the rewrite changed a step's line and the hand echoed the line as it was sent, the
/// echo is taken as the rewrite's line, wherever it comes: in the step's own answer or, for a
/// line sent without waiting (after a ^C, or queued behind a motion), in a later step's. A line
/// the rewrite changed otherwise (no echo of it is found) is not compared: its step's answer
/// and judge are left out. Returns the stream, the judges, and whether the failing step is
/// among them (a stream that ends before the parting judges nothing of it).
#[allow(clippy::too_many_arguments)]
fn rewritten_stream<'t>(
    p: &Profile,
    h: &Hypothesis,
    gots: &[Vec<u8>],
    d: usize,
    failed: usize,
    old: &'t [gcl_transcript::Step],
    new: &'t [gcl_transcript::Step],
    reads: &dyn Fn(&gcl_transcript::Step, gcl_model::spec::ParamId) -> bool,
    send: &dyn Fn(&gcl_transcript::Step) -> Option<Vec<u8>>,
) -> (Vec<u8>, Vec<&'t gcl_transcript::Step>, usize, bool) {
    let term = p.framing.terminator;
    let raw: Vec<u8> = gots.concat();
    let mut starts = Vec::with_capacity(gots.len() + 1);
    let mut at = 0;
    for g in gots {
        starts.push(at);
        at += g.len();
    }
    starts.push(at);
    // Echo substitutions, in the raw stream's positions: (where, length, the rewrite's line).
    let mut subs: Vec<(usize, usize, &str)> = Vec::new();
    let mut skipped = vec![false; gots.len()];
    let mut cursor = 0;
    for s in d..=failed {
        let k = s - d;
        if send(&old[s]) == send(&new[s]) {
            continue;
        }
        let sent = send(&old[s]).unwrap_or_default();
        let line = sent.strip_suffix(&[term]).unwrap_or(&sent);
        let pair = h.echoes.iter().find(|(w, _)| w.as_bytes() == line);
        let from = starts[k].max(cursor);
        let found = pair.and_then(|(was, now)| {
            let w = was.as_bytes();
            let i = raw.get(from..)?.windows(w.len().max(1)).position(|x| x == w)? + from;
            // (an echo split between two steps' reads is not taken)
            let end = starts.iter().copied().find(|e| *e > i).unwrap_or(raw.len());
            (i + w.len() <= end).then_some((i, w.len(), now.as_str()))
        });
        match found {
            Some(sub) => {
                cursor = sub.0 + sub.1;
                subs.push(sub);
            }
            None => skipped[k] = true,
        }
    }
    let mut stream = Vec::with_capacity(raw.len());
    let mut judges = Vec::new();
    for s in d..=failed {
        let k = s - d;
        if skipped[k] {
            continue;
        }
        let (a, b) = (starts[k], starts[k + 1]);
        let mut i = a;
        for (pos, len, now) in subs.iter().filter(|(pos, _, _)| (a..b).contains(pos)) {
            stream.extend_from_slice(&raw[i..*pos]);
            stream.extend_from_slice(now.as_bytes());
            i = pos + len;
        }
        stream.extend_from_slice(&raw[i..b]);
        judges.push(if h.stored.is_some_and(|id| reads(&old[s], id)) { &old[s] } else { &new[s] });
    }
    let complete = !skipped[failed - d];
    // (the rewrite may answer later than the case did: where answers run a step behind their
    // lines, an answer the case expected in the failing step may be the rewrite's next step's)
    let need = judges.len();
    for s in failed + 1..new.len().min(old.len()) {
        judges.push(if h.stored.is_some_and(|id| reads(&old[s], id)) { &old[s] } else { &new[s] });
    }
    (stream, judges, need, complete)
}

/// What [`explain`] found: the explanation, and for one no finding had yet, the whole case as
/// the hand would meet it under the explanation (`None` when the rewrite changed the number of
/// steps), for [`judged`] to replay where a chance fit is possible.
struct Explained {
    says: String,
    whole: Option<Transcript>,
    /// Shown by a model with the bug answering the case byte for byte as the hand did
    /// ([`variant`]): no chance fit, nothing to confirm.
    exact: bool,
}

/// Whether `stream` is the answers `judges` expect, one after another, each ending as soon as
/// it is whole and the next one takes the byte that follows (as the replay reads an answer
/// until it is whole: an answer ending in `{any}` takes nothing of the next). With `short` (the
/// hand parted from the case with a wrong byte, and the replay read no further) the stream may
/// end anywhere: every byte up to the parting one, that one included, is what the rewrite
/// expects. Without it the stream ends where the first `need` answers end. Values an answer
/// captures (`{i8 as v1}`, from `caps` on) hold the relations of the answers after it.
fn follows(
    judges: &[&gcl_transcript::Step],
    stream: &[u8],
    need: usize,
    short: bool,
    caps: &gcl_transcript::Captures,
) -> bool {
    use gcl_transcript::{Feed, Matcher};
    let Some(first) = judges.first() else { return false };
    let mut k = 0;
    let mut mt = Matcher::with_captures(&first.expect, caps);
    for b in stream {
        // (a whole answer ends here when the next one begins with this byte)
        while mt.is_complete() && k + 1 < judges.len() {
            let known = mt.captures().unwrap_or_else(|| caps.clone());
            let next = Matcher::with_captures(&judges[k + 1].expect, &known);
            if next.is_complete() {
                // (the next answer is empty: it ends here too)
                k += 1;
                mt = next;
                continue;
            }
            if next.clone().feed(*b) != Feed::Dead {
                k += 1;
                mt = next;
            }
            break;
        }
        if mt.feed(*b) == Feed::Dead {
            return false;
        }
    }
    short || k + 1 == need && mt.is_complete()
}

/// [`build_case`] with the run's bands, refusing (as a case the model cannot make) one that
/// needs what the run does not allow: a ^C that lands mid-motion under `--no abort-timing`.
fn build_for(opts: &FuzzOptions, actions: &[HostAction], id: &str, title: &str) -> Result<BuiltCase, NotACase> {
    build_for_sending(opts, actions, id, title, &[])
}

/// [`build_for`] with blocks sending given bytes (see [`case::build_case_sending`]).
fn build_for_sending(
    opts: &FuzzOptions,
    actions: &[HostAction],
    id: &str,
    title: &str,
    blocks: &[Option<Vec<u8>>],
) -> Result<BuiltCase, NotACase> {
    let b = case::build_case_sending(&opts.profile, actions, id, title, opts.wide(), opts.home(), blocks)?;
    admitted(opts, b)
}

/// [`build_for`] without the model's own replay of the case ([`case::build_case_unchecked`]):
/// for the campaign's draws in this process, checked only when the hand fails the case.
fn build_unchecked_for(
    opts: &FuzzOptions,
    actions: &[HostAction],
    id: &str,
    title: &str,
) -> Result<BuiltCase, NotACase> {
    let b = case::build_case_unchecked(&opts.profile, actions, id, title, opts.wide(), opts.home())?;
    admitted(opts, b)
}

/// A built case unless the run refuses it (see [`build_for`]).
fn admitted(opts: &FuzzOptions, b: BuiltCase) -> Result<BuiltCase, NotACase> {
    // A case resting on a decision the hand took differently judges nothing of it.
    if let Some(why) = skipped_decision(opts, &b) {
        return Err(NotACase(why));
    }
    if !opts.allowed.abort_timing && b.transcript.header.requires.contains(&gcl_transcript::Requirement::AbortTiming) {
        return Err(NotACase("a ^C lands mid-motion, and abort timing is refused".into()));
    }
    Ok(b)
}

/// Before a campaign that lands ^C mid-motion on a hand outside this process: closes the
/// hand from its home position once ([`MotionProbe`]) and refuses a target whose motion took
/// under a quarter of the model's time with [`FuzzError::NotRealTime`]: its answers to ^C
/// mid-motion are right for it and wrong for the model, so every such case would be a false
/// finding. `gcl conform` runs the same probe and skips its abort-timing cases instead.
pub fn check_real_time(opts: &FuzzOptions) -> Result<(), FuzzError> {
    if !(opts.wide() && opts.allowed.motion && opts.allowed.abort_timing) {
        return Ok(());
    }
    let p = &opts.profile;
    let Some(probe) = MotionProbe::new(p) else { return Ok(()) };
    let mut hand = Hand::new(opts);
    let out = hand.run(&probe.transcript, true)?;
    match probe.judge(p, &out) {
        Some(n) => Err(FuzzError::NotRealTime { command: n.command, took_ms: n.took_ms, model_ms: n.model_ms }),
        None => Ok(()),
    }
}

/// One case as a campaign judges it: `actions` built into a case, run thoroughly on the
/// target, and signed and explained with no explanation known yet (`None` when the case
/// passes). The inner error: the model makes no case of the actions.
pub fn judge_once(
    opts: &FuzzOptions,
    actions: &[HostAction],
) -> Result<Result<Option<FindingSignature>, NotACase>, FuzzError> {
    let built = match build_for(opts, actions, "fuzz", "a case") {
        Ok(b) => b,
        Err(e) => return Ok(Err(e)),
    };
    let mut hand = Hand::new(opts);
    let out = hand.run(&built.transcript, true)?;
    judged(opts, &mut hand, actions, &built, &out, &[]).map(Ok)
}

/// Runs the fuzzer. `progress` is called from worker threads.
pub fn run(opts: &FuzzOptions, progress: &(dyn Fn(Progress<'_>) + Sync)) -> Result<FuzzSummary, FuzzError> {
    refuse_what_leaves_no_case(opts)?;
    let mut identity = None;
    let mut saved_before = None;
    if opts.wide() {
        // As `gcl conform`: a hand that answers nothing is an infrastructure problem (exit 2),
        // not a campaign of "silence" findings.
        let mut l = gcl_host::target::open(&opts.target, &opts.open).map_err(FuzzError::Open)?;
        if let Some(why) = dead_hand(l.as_mut(), &opts.profile) {
            return Err(FuzzError::NotAlive { target: opts.target.to_string(), why });
        }
        // Who the hand says it is, first: a hand of another firmware fails wherever the two
        // differ, and every such failure would be a finding.
        let policy = DeadlinePolicy::for_target(&opts.target);
        identity = crate::preflight::run(l.as_mut(), &opts.profile, &policy).ok().and_then(|p| p.identity);
        if let Some(who) = &identity {
            progress(Progress::Note(who));
        }
        // What the hand has saved, before a case may save over it (see [`saved`]).
        if opts.allowed.eeprom && opts.write_budget != Some(0) {
            saved_before = Some(saved::read(l, &opts.profile).1);
        }
    }
    check_real_time(opts)?;
    let start = Instant::now();
    let (mut corpus, mut malformed) = (Vec::new(), Vec::new());
    if let Some(dir) = &opts.corpus {
        (corpus, malformed) = load_corpus(dir)?;
    }
    let loaded = corpus.len();
    if opts.suite_seeds {
        corpus.extend(suite_seeds(&opts.profile).iter().cloned());
    }
    // Entries from other runs or the suite may do what this run refuses.
    let generator = Generator::new(&opts.profile, opts.allowed).holding_velocities(opts.wide());
    let mut i = 0;
    let mut seeds = 0;
    corpus.retain(|a| {
        let keep = generator.permits(a);
        seeds += usize::from(keep && i >= loaded);
        i += 1;
        keep
    });
    let shared = Mutex::new(Shared {
        corpus,
        features: BTreeSet::new(),
        findings: Vec::new(),
        seen: BTreeSet::new(),
        status_at: BTreeMap::new(),
        explained: Vec::new(),
        dropped: 0,
        wire_bytes: 0,
        bytes_sent: 0,
        lines_sent: 0,
        rejudged: 0,
        minimizing: Duration::ZERO,
        error: None,
        dead_hand: None,
        dropped_in_a_row: 0,
        last_drop: String::new(),
        no_cases: None,
        not_reproduced: Vec::new(),
    });
    let runs = AtomicU64::new(0);
    let tickets = AtomicU64::new(0);
    let writes = AtomicU64::new(0);
    let stop = AtomicBool::new(false);
    let jobs = opts.jobs.max(1);
    std::thread::scope(|s| {
        for w in 0..jobs {
            let counters = Counters { runs: &runs, tickets: &tickets, writes: &writes, stop: &stop };
            let shared = &shared;
            s.spawn(move || {
                if let Err(e) = worker(opts, w, start, shared, counters, progress) {
                    let stop = counters.stop;
                    stop.store(true, Ordering::SeqCst);
                    let mut g = shared.lock().unwrap_or_else(|e| e.into_inner());
                    g.error.get_or_insert(e);
                }
            });
        }
    });
    let mut sh = shared.into_inner().unwrap_or_else(|e| e.into_inner());
    if let Some(e) = sh.error {
        return Err(e);
    }
    name_status_commands(&mut sh.findings, &sh.status_at);
    let hand_after = hand_after(opts, writes.load(Ordering::SeqCst), saved_before.as_ref());
    Ok(FuzzSummary {
        runs: runs.load(Ordering::SeqCst),
        dropped: sh.dropped,
        findings: sh.findings,
        features: sh.features,
        // What a user can count: the corpus folder's entries, or without one, the cases this
        // run kept (the suite's seeds, taken into memory, are the suite's, not the corpus's).
        corpus: match &opts.corpus {
            Some(dir) => corpus_files(dir),
            None => sh.corpus.len() - seeds,
        },
        eeprom_writes: writes.load(Ordering::SeqCst),
        wire_bytes: sh.wire_bytes,
        bytes_sent: sh.bytes_sent,
        lines_sent: sh.lines_sent,
        rejudged: sh.rejudged,
        elapsed: start.elapsed(),
        dead_hand: sh.dead_hand,
        interrupted: opts.stop.load(Ordering::SeqCst),
        no_cases: sh.no_cases,
        malformed_corpus: malformed,
        minimizing: sh.minimizing,
        not_reproduced: sh.not_reproduced,
        identity,
        hand_after,
    })
}

/// What a campaign left on a hand outside this process as it found it, checked where it can
/// be: on a serial line, whether the hand still answers at the rate the campaign started at
/// (no case changes it, [`Allowed::keep_rate`]; or, with [`OpenOptions::follow_rate`], every
/// connection set it back before it closed); and what became of the EEPROM.
fn hand_after(opts: &FuzzOptions, eeprom_writes: u64, saved: Option<&Result<saved::Saved, String>>) -> Vec<String> {
    if !opts.wide() {
        return Vec::new();
    }
    let mut said = Vec::new();
    // (the saved values first: the line is checked after the restore's own sets)
    let eeprom = match saved {
        _ if eeprom_writes == 0 => "EEPROM: no writes; the saved parameters are as they were found".to_string(),
        Some(Ok(s)) => {
            let rate = match &opts.target {
                Target::Serial { baud, .. } => Some(*baud),
                _ => None,
            };
            let done = match gcl_host::target::open(&opts.target, &opts.open) {
                Ok(l) => saved::restore(l, &opts.profile, s, rate).1,
                Err(e) => {
                    format!("the hand could not be reached to save back the values saved before the campaign: {e}")
                }
            };
            format!("EEPROM: {eeprom_writes} writes; {done}")
        }
        Some(Err(why)) => format!(
            "EEPROM: {eeprom_writes} writes; every case that saved parameters saved the factory defaults back, and \
             the values saved before the campaign could not be read ({why}): a hand whose saved values were not \
             the factory defaults now has the factory defaults"
        ),
        None => format!(
            "EEPROM: {eeprom_writes} writes; every case that saved parameters saved the factory defaults back \
             (the values saved before the campaign were not read, so a hand whose saved values were not the \
             factory defaults now has the factory defaults)"
        ),
    };
    if let Target::Serial { baud, .. } = &opts.target {
        // (a plain port at the first rate: the check does not follow anything)
        let plain = gcl_host::target::OpenOptions { follow_rate: false, ..opts.open.clone() };
        let followed = if opts.open.follow_rate {
            " (cases could change it, --allow rate-change: the port followed each change and set the hand back)"
        } else {
            ""
        };
        said.push(match gcl_host::target::open(&opts.target, &plain) {
            Ok(mut l) => match dead_hand(l.as_mut(), &opts.profile) {
                None => format!("line: the hand answers at {baud} baud, the rate it started at{followed}"),
                Some(why) => format!("line: the hand no longer answers at {baud} baud, the rate it started at: {why}"),
            },
            Err(e) => format!("line: the port could not be opened again at {baud} baud to check the hand: {e}"),
        });
    }
    said.push(eeprom);
    said
}

impl Shared {
    /// Notes a failure's signature: whether it is new (not seen before), and for a status
    /// difference the command it showed on.
    fn saw(&mut self, sig: &FindingSignature) -> bool {
        if sig.kind == "status" && sig.explanation.is_empty() {
            let bare = FindingSignature { scope: String::new(), ..sig.clone() }.key();
            self.status_at.entry(bare).or_default().insert(slug(&sig.command));
        }
        self.seen.insert(sig.key())
    }
}

/// Names in each status finding's transcript (and rewrites its file) every command its bits
/// showed on in the campaign (`x-status-at`, see [`Baseline::add_dir`]).
fn name_status_commands(findings: &mut [Finding], status_at: &BTreeMap<String, BTreeSet<String>>) {
    for f in findings.iter_mut().filter(|f| f.signature.kind == "status" && f.signature.explanation.is_empty()) {
        let bare = FindingSignature { scope: String::new(), ..f.signature.clone() }.key();
        let Some(at) = status_at.get(&bare).filter(|at| at.len() > 1) else { continue };
        let ext = &mut f.transcript.header.extensions;
        ext.retain(|(k, _)| k != STATUS_AT_KEY);
        ext.push((STATUS_AT_KEY.to_string(), at.iter().cloned().collect::<Vec<_>>().join(" ")));
        f.transcript_text = f.transcript.to_text();
        if let Some(path) = &f.path {
            // (a file that cannot be rewritten keeps its first command, as before)
            let _ = crate::report::write_atomic(path, f.transcript_text.as_bytes());
        }
    }
}

/// The transcript header of a status finding that names every command (as file-name words:
/// `fget io`) its status bits showed on in the campaign.
pub const STATUS_AT_KEY: &str = "x-status-at";

/// The run's counters, shared by the workers.
#[derive(Clone, Copy)]
struct Counters<'a> {
    /// Cases run.
    runs: &'a AtomicU64,
    /// Cases started (a `Runs` budget is handed out as tickets).
    tickets: &'a AtomicU64,
    /// EEPROM writes.
    writes: &'a AtomicU64,
    /// Set to end every worker.
    stop: &'a AtomicBool,
}

fn worker(
    opts: &FuzzOptions,
    w: usize,
    start: Instant,
    shared: &Mutex<Shared>,
    c: Counters<'_>,
    progress: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<(), FuzzError> {
    let Counters { runs, tickets, writes, stop } = c;
    let p = opts.profile.clone();
    let lock = || shared.lock().unwrap_or_else(|e| e.into_inner());
    let mut allowed = opts.allowed;
    let gen_all = Generator::new(&p, allowed).holding_velocities(opts.wide());
    allowed.eeprom = false;
    let gen_no_eeprom = Generator::new(&p, allowed).holding_velocities(opts.wide());
    let stream = opts.shard.map_or(w as u64, |s| s.global(w as u64));
    let mut dice = Dice::new(opts.seed.wrapping_add(stream));
    let mut hand = Hand::new(opts);
    // The last case that passed a quick run, with its run number.
    let mut prev: Option<(Vec<HostAction>, BuiltCase, u64)> = None;
    // The cases that passed last on this link, the latest last (see [`Met::before`]).
    let mut recent: std::collections::VecDeque<Vec<HostAction>> = std::collections::VecDeque::new();
    // The cases that wrote the EEPROM last on this link, passed or failed, the latest last: what
    // they saved outlives any number of cases between (see [`Met::before`]).
    let mut writers: std::collections::VecDeque<Vec<HostAction>> = std::collections::VecDeque::new();
    let wrote = |writers: &mut std::collections::VecDeque<Vec<HostAction>>, b: &BuiltCase, a: &[HostAction]| {
        if b.eeprom_writes > 0 {
            if writers.len() == RECENT_CASES {
                writers.pop_front();
            }
            writers.push_back(a.to_vec());
        }
    };
    loop {
        if stop.load(Ordering::SeqCst) || opts.stop.load(Ordering::SeqCst) {
            return Ok(());
        }
        if let Budget::Time(t) = opts.budget
            && start.elapsed() >= t
        {
            return Ok(());
        }
        if let Budget::Runs(r) = opts.budget
            && tickets.load(Ordering::SeqCst) >= r
        {
            return Ok(());
        }
        let budget_left = opts.write_budget.is_none_or(|b| writes.load(Ordering::SeqCst) < b);
        let g = if budget_left { &gen_all } else { &gen_no_eeprom };
        let base = {
            let sh = lock();
            if !sh.corpus.is_empty() && dice.chance(50) {
                sh.corpus.get(dice.below(sh.corpus.len())).cloned()
            } else {
                None
            }
        };
        let actions = match base {
            Some(b) => g.mutate(&mut dice, &b),
            None => g.case(&mut dice),
        };
        // (the generator draws no set of a guarded line rate; a mutation may still copy one in)
        if opts.allowed.keep_rate.is_some() && !g.permits(&actions) {
            if lock().dropped("it would change the line's rate") {
                stop.store(true, Ordering::SeqCst);
            }
            continue;
        }
        // (in this process the model's own replay of the case waits for a failure: see
        // [`case::build_case_unchecked`])
        let built = if opts.wide() {
            build_for(opts, &actions, "fuzz", "a generated case")
        } else {
            build_unchecked_for(opts, &actions, "fuzz", "a generated case")
        };
        let mut built = match built {
            Ok(b) => b,
            Err(NotACase(why)) => {
                if lock().dropped(&why) {
                    stop.store(true, Ordering::SeqCst);
                }
                continue;
            }
        };
        if let Some(b) = opts.write_budget {
            let w = built.eeprom_writes as u64;
            if w > 0 && writes.fetch_add(w, Ordering::SeqCst) + w > b {
                writes.fetch_sub(w, Ordering::SeqCst);
                if lock().dropped("needs EEPROM writes past the write budget") {
                    stop.store(true, Ordering::SeqCst);
                }
                continue;
            }
        } else {
            writes.fetch_add(built.eeprom_writes as u64, Ordering::SeqCst);
        }
        if let Budget::Runs(r) = opts.budget
            && tickets.fetch_add(1, Ordering::SeqCst) >= r
        {
            return Ok(());
        }
        // Bytes on the line before this case belong to the case before it, which passed
        // without a trailing wait: that case is judged again, thoroughly, first.
        if hand.settle()?
            && let Some((pa, pb, prun)) = prev.take()
        {
            lock().rejudged += 1;
            let out = hand.surely(|h| h.run(&pb.transcript, true))?;
            let known = lock().explained.clone();
            if let Some(sig) = judged(opts, &mut hand, &pa, &pb, &out, &known)? {
                let new = lock().saw(&sig);
                let met = Met { actions: &pa, built: &pb, run: prun, before: &[] };
                if new && report_finding(opts, &mut hand, shared, start, met, sig, progress)? {
                    stop.store(true, Ordering::SeqCst);
                    return Ok(());
                }
                if new && hand.start_afresh() {
                    recent.clear();
                    writers.clear();
                }
            }
        }
        let mut outcome = hand.run(&built.transcript, false)?;
        if !outcome.is_pass() && built.check(&p).is_err() {
            // No case after all: the model fails it too.
            tickets.fetch_sub(1, Ordering::SeqCst);
            lock().dropped += 1;
            continue;
        }
        let run_no = runs.fetch_add(1, Ordering::SeqCst) + 1;
        lock().dropped_in_a_row = 0;
        let known = if outcome.is_pass() { Vec::new() } else { lock().explained.clone() };
        let mut sig = judged(opts, &mut hand, &actions, &built, &outcome, &known)?;
        // A quick run's new failure counts only if a thorough run of the case fails too.
        if opts.wide() && sig.as_ref().is_some_and(|s| !lock().seen.contains(&s.key())) {
            outcome = hand.run(&built.transcript, true)?;
            sig = judged(opts, &mut hand, &actions, &built, &outcome, &known)?;
        }
        let (new_cov, nfeat, nfind) = {
            let mut sh = lock();
            for e in outcome.exchange() {
                sh.wire_bytes += (e.sent.len() + e.received.len()) as u64;
                sh.bytes_sent += e.sent.len() as u64;
                sh.lines_sent += e.sent.iter().filter(|&&b| b == b'\r').count() as u64;
            }
            let new_cov = !built.features.is_subset(&sh.features);
            if new_cov {
                sh.features.extend(built.features.iter().cloned());
                sh.corpus.push(actions.clone());
            }
            (new_cov, sh.features.len(), sh.findings.len())
        };
        if new_cov && let Some(dir) = &opts.corpus {
            save_corpus(dir, &actions)?;
        }
        progress(Progress::Run { runs: run_no, findings: nfind, features: nfeat, elapsed: start.elapsed() });
        let Some(sig) = sig else {
            if recent.len() == RECENT_CASES {
                recent.pop_front();
            }
            recent.push_back(actions.clone());
            wrote(&mut writers, &built, &actions);
            prev = Some((actions, built, run_no));
            continue;
        };
        prev = None;
        // Silence from a hand outside this process: is it dead? Then the campaign ends (exit
        // 2, as `gcl conform`), keeping the case that met the silence unminimized, since a
        // dead hand cannot minimize it.
        if opts.wide()
            && matches!(&outcome, ReplayOutcome::Timeout(to) if to.offset == 0)
            && let Some(why) = hand.dead()?
        {
            lock().dead_hand.get_or_insert(format!(
                "the hand stopped answering at run {run_no} (the case met silence, then {why})"
            ));
            stop.store(true, Ordering::SeqCst);
            if lock().saw(&sig) {
                let o = FuzzOptions { minimize: false, ..opts.clone() };
                let met = Met { actions: &actions, built: &built, run: run_no, before: &[] };
                report_finding(&o, &mut hand, shared, start, met, sig, progress)?;
            }
            return Ok(());
        }
        let new = lock().saw(&sig);
        // (the writers the passed cases do not hold first: they are tried after them)
        let before: Vec<Vec<HostAction>> =
            writers.iter().filter(|w| !recent.contains(w)).chain(recent.iter()).cloned().collect();
        let met = Met { actions: &actions, built: &built, run: run_no, before: &before };
        if new && report_finding(opts, &mut hand, shared, start, met, sig, progress)? {
            stop.store(true, Ordering::SeqCst);
        }
        wrote(&mut writers, &built, &actions);
        if new && hand.start_afresh() {
            recent.clear();
            writers.clear();
        }
    }
}

/// A failing case as a campaign met it.
#[derive(Clone, Copy)]
struct Met<'a> {
    /// Its actions.
    actions: &'a [HostAction],
    /// The case built from them.
    built: &'a BuiltCase,
    /// Its run number.
    run: u64,
    /// The actions of the cases that passed last before it on the same link, the latest last
    /// (at most [`RECENT_CASES`]): a state one of them left (a parameter a broken preamble did
    /// not reset) may be part of the failure. Before them, tried after them, the cases that
    /// wrote the EEPROM last on the link (at most [`RECENT_CASES`]) that are not among them: a
    /// saved value outlives every case between. A hand whose FDEF skips MCV saved the MCV of
    /// a case 12 cases back with that case's closing FDEF and FSAVE, and each RESET since
    /// loaded it: the failure it made reproduced after that case alone, never after the 8
    /// before it (issue 37: `value at FLISTV (MCV) after FDEF`, 0 of 3 on a fresh `exec:`
    /// hand, whose EEPROM is the factory's).
    before: &'a [Vec<HostAction>],
}

/// How many of the cases that passed last on a link a failure that does not reproduce alone is
/// tried after (see [`report_finding`]).
const RECENT_CASES: usize = 8;

/// The preamble every case starts with (^C, RESET, FDEF, PDEF, HI when it moves), as host
/// actions: what stood between two cases run one after the other on a link.
fn preamble_actions(opts: &FuzzOptions) -> Vec<HostAction> {
    let p = &opts.profile;
    let mut v = vec![HostAction::Abort, HostAction::Line("RESET".into()), HostAction::Line("FDEF".into())];
    if p.command_id("PDEF").is_some() {
        v.push(HostAction::Line("PDEF".into()));
    }
    if opts.home() {
        v.push(HostAction::Line("HI".into()));
    }
    v
}

/// Minimizes a new finding, confirms it on fresh connections, writes its transcript, and adds
/// it to the run's findings; says whether the run has found as many as it was to find.
///
/// A failure whose minimized transcript does not fail again on a fresh connection may rest on
/// a state an earlier case left on the link (a hand whose FDEF skips MCV shows it only after a
/// case that set MCV): each case that passed last before it (the latest first), the preamble
/// and the failing case are then tried as one case on fresh connections, and the first that
/// fails every time is reported whole. Otherwise the failure is a [`NotReproduced`] note.
fn report_finding(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    shared: &Mutex<Shared>,
    start: Instant,
    met: Met<'_>,
    sig: FindingSignature,
    progress: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<bool, FuzzError> {
    let Met { actions, built, run: run_no, before } = met;
    let found_after = start.elapsed();
    let t0 = Instant::now();
    // (the confirmations' hands start while the finding is minimized)
    hand.open_ahead(confirmations(&opts.target));
    let (mut min_actions, min_case) = if opts.minimize {
        minimize(opts, hand, actions, built, &sig, minimizing_ends(opts.budget, start))?
    } else {
        (actions.to_vec(), built.clone())
    };
    let mut final_case = build_for(opts, &min_actions, "fuzz", "a finding").unwrap_or(min_case);
    let mut out = hand.run(&final_case.transcript, true)?;
    let mut sig = sig;
    let mut with_before = false;
    let alive = shared.lock().unwrap_or_else(|e| e.into_inner()).dead_hand.is_none();
    // Confirmed before it is reported: the minimized transcript, replayed on a fresh
    // connection, fails with the same signature every time (a dead hand cannot be asked).
    if alive {
        let of = confirmations(&opts.target);
        let mut again = reproductions(opts, hand, &min_actions, &final_case, &sig, of, false)?;
        for earlier in before.iter().rev() {
            if again == of {
                break;
            }
            let mut whole = earlier.clone();
            whole.extend(preamble_actions(opts));
            whole.extend(actions.iter().cloned());
            if let Ok(b) = build_for(opts, &whole, "fuzz", "a finding with a case before it")
                && reproductions(opts, hand, &whole, &b, &sig, of, true)? == of
            {
                (min_actions, final_case, again) = (whole, b, of);
                with_before = true;
                out = hand.run(&final_case.transcript, true)?;
            }
        }
        if again < of {
            let nr = NotReproduced {
                signature: sig.to_string(),
                key: sig.key(),
                reproduced: again,
                replays: of,
                transcript_text: final_case.transcript.to_text(),
                diff: out.render(),
            };
            progress(Progress::NotReproduced(&nr));
            let mut sh = shared.lock().unwrap_or_else(|e| e.into_inner());
            sh.minimizing += t0.elapsed();
            sh.not_reproduced.push(nr);
            return Ok(false);
        }
    }
    // A position wrong before the motion named: the hand is asked where it began (a dead
    // hand is not). Named so, it may be a finding already reported.
    if alive && let Some(s) = probe::named(opts, hand, &min_actions, &final_case, &out, &sig)? {
        sig = s;
        let mut sh = shared.lock().unwrap_or_else(|e| e.into_inner());
        if !sh.seen.insert(sig.key()) {
            sh.minimizing += t0.elapsed();
            return Ok(opts.max_findings.is_some_and(|m| sh.findings.len() >= m));
        }
    }
    let id = finding_id(&sig);
    let title = if with_before {
        format!(
            "gcl fuzz device: {sig} (an earlier case, the preamble and the failing case: it fails only after the \
             state the earlier case left)"
        )
    } else {
        format!("gcl fuzz device: {sig} (minimized from {} actions)", actions.len())
    };
    (final_case.transcript.header.id, final_case.transcript.header.title) = (id.clone(), title);
    final_case.transcript.header.extensions.push((SIGNATURE_KEY.to_string(), sig.key()));
    final_case
        .transcript
        .header
        .extensions
        .push((PROFILE_SPEC_KEY.to_string(), crate::report::ProfileSpec::digest(&opts.profile)));
    let diff = out.render();
    // The steps of this (the final) transcript's run where it fails: what the finding rests on.
    let failing = crate::align::failing_steps(&opts.profile, &final_case.transcript, &final_case.model, &out);
    let (level, rests_on) = Finding::binding(&opts.profile, &final_case.rests_on(failing));
    // (the transcript written says the finding's level: `gcl conform --level` and a baseline
    // read it from there, and the case's own level is its weakest step's, not its failure's)
    final_case.transcript.header.level = level;
    let text = final_case.transcript.to_text();
    let path = match &opts.out {
        Some(dir) => {
            // Never over another finding (an earlier campaign's, of another bug, under the
            // same name): the next free name instead.
            let path = crate::outputs::write_unique(dir, &id, "gcl", text.as_bytes())
                .map_err(|source| FuzzError::Out { path: dir.join(format!("{id}.gcl")), source })?;
            Some(path)
        }
        None => None,
    };
    let known = opts.baseline.explains(&opts.profile.id, &id, &sig);
    let finding = Finding {
        known,
        level,
        rests_on,
        signature: sig,
        run: run_no,
        found_after,
        original_actions: actions.len(),
        actions: min_actions,
        transcript: final_case.transcript,
        transcript_text: text,
        diff,
        path,
    };
    progress(Progress::Finding(&finding));
    let mut sh = shared.lock().unwrap_or_else(|e| e.into_inner());
    sh.minimizing += t0.elapsed();
    let fresh = Some(finding.signature.explanation.clone()).filter(|e| !e.is_empty() && !sh.explained.contains(e));
    if let Some(e) = &fresh {
        sh.explained.push(e.clone());
    }
    sh.findings.push(finding);
    // Findings met before this explanation that it covers (a status, a ^C or a block that
    // showed the bug before a value read back explained it) are this bug: each unexplained
    // finding's case is run again and tried against this explanation alone. One it covers is
    // dropped, and its key freed, so a later failure under that key that the explanation does
    // not cover (another bug with the same status bits) is still found.
    let Some(e) = fresh else { return Ok(opts.max_findings.is_some_and(|m| sh.findings.len() >= m)) };
    let earlier: Vec<(String, Vec<HostAction>)> = sh
        .findings
        .iter()
        .filter(|f| f.signature.explanation.is_empty() && !matches!(f.signature.kind.as_str(), "link" | "restart"))
        .map(|f| (f.signature.key(), f.actions.clone()))
        .collect();
    drop(sh);
    let mut joined = Vec::new();
    for (key, actions) in earlier {
        let Ok(b) = build_for(opts, &actions, "fuzz", "join") else { continue };
        let out = hand.run(&b.transcript, true)?;
        if explain(opts, hand, &actions, &b, &out, std::slice::from_ref(&e), Fresh::NONE, "")?
            .is_some_and(|x| x.says == e)
        {
            joined.push(key);
        }
    }
    let mut sh = shared.lock().unwrap_or_else(|e| e.into_inner());
    let (gone, kept): (Vec<Finding>, Vec<Finding>) = std::mem::take(&mut sh.findings)
        .into_iter()
        .partition(|f| f.signature.explanation.is_empty() && joined.contains(&f.signature.key()));
    sh.findings = kept;
    for f in &gone {
        sh.seen.remove(&f.signature.key());
        if let Some(path) = &f.path {
            let _ = std::fs::remove_file(path);
        }
        progress(Progress::Joined { finding: f, explanation: &e });
    }
    Ok(opts.max_findings.is_some_and(|m| sh.findings.len() >= m))
}

/// How many of `of` replays of a finding's case, each on a fresh connection, fail with its
/// signature (its own explanation, if it has one, known: the replay must keep it); with
/// `first_miss`, the count stops at the first replay that does not.
fn reproductions(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    actions: &[HostAction],
    case: &BuiltCase,
    sig: &FindingSignature,
    of: u32,
    first_miss: bool,
) -> Result<u32, FuzzError> {
    let known: Vec<String> = [sig.explanation.clone()].into_iter().filter(|e| !e.is_empty()).collect();
    let mut again = 0;
    hand.open_ahead(of);
    for _ in 0..of {
        hand.link = None;
        let out = hand.surely(|h| h.run(&case.transcript, true))?;
        if judged(opts, hand, actions, case, &out, &known)?.is_some_and(|s| s.key() == sig.key()) {
            again += 1;
        } else if first_miss {
            break;
        }
    }
    Ok(again)
}

/// When minimization ends (it also ends on a signal), keeping the best so far: with the
/// campaign's time budget (`--duration`), counted from the campaign's `start`; never under a
/// budget of runs.
fn minimizing_ends(budget: Budget, start: Instant) -> Option<Instant> {
    match budget {
        Budget::Time(t) => Some(start + t),
        Budget::Runs(_) => None,
    }
}

/// Delta debugging over the action list: drop chunks (halves, quarters, ... single
/// actions), then simplify each action's arguments, keeping every change after which the
/// case still fails with the same signature. Each try rebuilds the expectations from the
/// model.
fn minimize(
    opts: &FuzzOptions,
    hand: &mut Hand<'_>,
    actions: &[HostAction],
    built: &BuiltCase,
    sig: &FindingSignature,
    until: Option<Instant>,
) -> Result<(Vec<HostAction>, BuiltCase), FuzzError> {
    let mut tries = 0usize;
    let mut best = (actions.to_vec(), built.clone());
    // (the finding's own explanation, if it has one: the smaller case must keep it)
    let known: Vec<String> = [sig.explanation.clone()].into_iter().filter(|e| !e.is_empty()).collect();
    let mut check = |cand: &[HostAction], tries: &mut usize| -> Result<Option<BuiltCase>, FuzzError> {
        if opts.stop.load(Ordering::SeqCst) || until.is_some_and(|u| Instant::now() >= u) {
            // Out of time: every loop below ends at the budget of tries.
            *tries = opts.minimize_budget;
            return Ok(None);
        }
        *tries += 1;
        let Ok(b) = build_for(opts, cand, "fuzz", "minimizing") else { return Ok(None) };
        if b.eeprom_writes > built.eeprom_writes {
            return Ok(None);
        }
        let out = hand.run(&b.transcript, true)?;
        Ok((judged(opts, hand, cand, &b, &out, &known)?.is_some_and(|s| s.key() == sig.key())).then_some(b))
    };
    let mut chunk = best.0.len().div_ceil(2).max(1);
    while chunk >= 1 && tries < opts.minimize_budget {
        let mut i = 0;
        let mut changed = false;
        while i < best.0.len() && tries < opts.minimize_budget {
            let mut cand = best.0.clone();
            cand.drain(i..(i + chunk).min(cand.len()));
            if !cand.is_empty()
                && let Some(b) = check(&cand, &mut tries)?
            {
                best = (cand, b);
                changed = true;
            } else {
                i += chunk;
            }
        }
        if chunk == 1 && !changed {
            break;
        }
        if !changed || chunk > 1 {
            chunk = (chunk / 2).max(1);
        }
    }
    let mut i = 0;
    while i < best.0.len() && tries < opts.minimize_budget {
        let mut improved = false;
        for s in simpler(&best.0[i]) {
            let mut cand = best.0.clone();
            cand[i] = s;
            if let Some(b) = check(&cand, &mut tries)? {
                best = (cand, b);
                improved = true;
                break;
            }
        }
        if !improved {
            i += 1;
        }
    }
    Ok(best)
}

/// A finding's id and file name: `fuzz-COMMAND-KIND`, then what else its key holds
/// (`fuzz-fget-order`, `fuzz-fget-value-after-m`, `fuzz-vers-status-1024-missing`).
pub fn finding_id(sig: &FindingSignature) -> String {
    let mut id = format!("fuzz-{}-{}", slug(&sig.command), sig.kind);
    let key = sig.key();
    let rest = key
        .strip_prefix(&format!("{} at {}", sig.kind, sig.command))
        .or_else(|| key.strip_prefix(&format!("{} ", sig.kind)))
        .unwrap_or_default();
    let rest: String =
        rest.to_ascii_lowercase().chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect();
    let rest: Vec<&str> = rest.split('-').filter(|w| !w.is_empty()).collect();
    if !rest.is_empty() {
        id.push('-');
        id.push_str(&rest.join("-"));
    }
    id
}

/// A command word as part of a file name: `^C` is `abort`, `RealTime block` is `block`.
fn slug(command: &str) -> String {
    let s: String = match command {
        "^C" => "abort".into(),
        "RealTime block" => "block".into(),
        "CR" => "cr".into(),
        c => c.to_ascii_lowercase().chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect(),
    };
    if s.is_empty() { "line".into() } else { s }
}

/// Findings grouped by signature kind, for summaries.
pub fn kinds(findings: &[Finding]) -> BTreeMap<String, usize> {
    let mut m = BTreeMap::new();
    for f in findings {
        *m.entry(f.signature.kind.clone()).or_insert(0) += 1;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A case that drives the fingers past the model's joint stop rests on seed-motion-model
    /// (see `actions::case`'s `a_case_whose_answers_rest_on_the_joint_stops_names_the_motion_decision`),
    /// and a finding of it says so: `[INFO: rests on seed-motion-model]`.
    #[test]
    fn a_finding_past_the_joint_stop_is_info() {
        let p = Profile::builtin("seed").unwrap();
        let past = build_case(&p, &[HostAction::Line("C".into()), HostAction::Line("IC".into())], "t", "t", true, true)
            .expect("a case");
        let (level, rests_on) = Finding::binding(&p, &past.rests_on(None));
        assert_eq!((level, rests_on), (gcl_model::Level::Info, vec!["seed-motion-model".to_string()]));
    }

    /// Issue 29 item 2: a campaign that draws only cases it drops ends after [`DROP_LIMIT`] of
    /// them in a row, saying why; a case run in between starts the count again.
    #[test]
    fn a_campaign_that_drops_every_case_it_draws_ends() {
        let mut sh = Shared::default();
        for _ in 0..DROP_LIMIT - 1 {
            assert!(!sh.dropped("rests on decision x"));
        }
        sh.dropped_in_a_row = 0;
        for _ in 0..DROP_LIMIT - 1 {
            assert!(!sh.dropped("rests on decision x"));
        }
        assert!(sh.dropped("needs EEPROM writes past the write budget"));
        let why = sh.no_cases.unwrap();
        assert!(why.contains("5000 drawn cases") && why.contains("the write budget"), "{why}");
        assert_eq!(sh.dropped, 2 * DROP_LIMIT - 1);
    }

    /// README: "minimization stops at `--duration`". A case of four actions fails on a hand
    /// that rejects lower-case commands at its one lower-case line: with runs to spend it is
    /// minimized to that line; found once a `--duration` has passed, it is kept as found,
    /// without one more replay.
    #[test]
    fn minimization_stops_at_the_campaigns_duration() {
        let p = Profile::builtin("seed").unwrap();
        let mut opts = FuzzOptions::new(Target::Sim { profile: None }, p);
        opts.open.faults = vec![gcl_model::Fault::LowercaseRejected];
        let actions: Vec<HostAction> =
            ["FGET MCV", "vers", "FGET DP", "FGET MOV"].iter().map(|l| HostAction::Line(l.to_string())).collect();
        let built = build_for(&opts, &actions, "t", "t").unwrap();
        let mut hand = Hand::new(&opts);
        let out = hand.run(&built.transcript, true).unwrap();
        let sig = judged(&opts, &mut hand, &actions, &built, &out, &[]).unwrap().expect("the lower-case line fails");
        let start = Instant::now();
        let (shrunk, _) =
            minimize(&opts, &mut hand, &actions, &built, &sig, minimizing_ends(Budget::Runs(5), start)).unwrap();
        assert_eq!(shrunk, vec![HostAction::Line("vers".into())]);
        // A campaign of 30 s that started 31 s ago.
        let long_ago = start.checked_sub(Duration::from_secs(31)).expect("a monotonic clock 31 s on");
        let until = minimizing_ends(Budget::Time(Duration::from_secs(30)), long_ago);
        assert_eq!(until, Some(long_ago + Duration::from_secs(30)));
        let (kept, _) = minimize(&opts, &mut hand, &actions, &built, &sig, until).unwrap();
        assert_eq!(kept, actions, "minimized past the campaign's duration");
    }

    /// The finding a case of `lines` makes on a sim of profile `p` with `fault`, through the
    /// campaign's own judging and reporting, kept unminimized (minimizing would drop the lines
    /// that do not fail, and what they rest on with them).
    fn unminimized_finding(p: &str, fault: gcl_model::Fault, lines: &[&str]) -> (BuiltCase, Finding) {
        let mut opts = FuzzOptions::new(Target::Sim { profile: None }, Profile::builtin(p).unwrap());
        opts.open.faults = vec![fault];
        opts.minimize = false;
        let actions: Vec<HostAction> = lines.iter().map(|l| HostAction::Line(l.to_string())).collect();
        let built = build_for(&opts, &actions, "t", "t").unwrap();
        let mut hand = Hand::new(&opts);
        let out = hand.run(&built.transcript, true).unwrap();
        let sig = judged(&opts, &mut hand, &actions, &built, &out, &[]).unwrap().expect("the fault shows");
        let shared = Mutex::new(Shared::default());
        let met = Met { actions: &actions, built: &built, run: 1, before: &[] };
        report_finding(&opts, &mut hand, &shared, Instant::now(), met, sig, &|_| {}).unwrap();
        let mut findings = shared.into_inner().unwrap().findings;
        assert_eq!(findings.len(), 1, "{findings:?}");
        (built, findings.remove(0))
    }

    /// `value at RealTime block (LFDP) [INFO: rests on bh8-err-format]` was lcv-unsigned's:
    /// an ERR line that passed, early in the case, made a MUST bug an open point. A finding
    /// rests on its failing step's decisions and the earlier steps' state decisions, not on
    /// how an earlier answer that passed is written.
    #[test]
    fn a_bug_after_an_answer_resting_on_an_open_format_is_must() {
        let (built, f) =
            unminimized_finding("bh8-262", gcl_model::Fault::FgetReversed, &["ERR 15907", "1FSET MCV 50", "FGET MCV"]);
        // (the case as a whole rests on the INFO format of ERR's lines)
        let whole = crate::suite::decisions_of_header(&built.transcript.header);
        assert!(whole.iter().any(|d| d == "bh8-err-format"), "{whole:?}");
        assert_eq!(f.signature.command, "FGET", "{}", f.signature);
        // (and the transcript written says so: `gcl conform --level must` keeps it)
        assert_eq!(f.transcript.header.level, gcl_model::Level::Must);
        assert!(f.transcript_text.contains("\nlevel: MUST\n"), "{}", f.transcript_text);
        assert_eq!((f.level, f.rests_on), (gcl_model::Level::Must, vec![]));
    }

    /// A failing step that rests on an open decision still says so; an earlier step's state
    /// decision (what a set of 0 does) counts too, an earlier answer's format does not.
    #[test]
    fn a_finding_rests_on_its_failing_steps_decisions_and_earlier_state_decisions() {
        let (_, f) = unminimized_finding("bh8-262", gcl_model::Fault::LowercaseRejected, &["ERR 3", "fget mcv"]);
        assert_eq!(f.signature.command, "FGET", "{}", f.signature);
        assert_eq!((f.level, f.rests_on), (gcl_model::Level::Should, vec!["framing-case".to_string()]));
        let (_, f) = unminimized_finding(
            "bh8-262",
            gcl_model::Fault::FgetReversed,
            &["FSET LCVC 0", "ERR 15907", "1FSET MCV 50", "FGET MCV"],
        );
        assert_eq!((f.level, f.rests_on), (gcl_model::Level::Info, vec!["bh8-coefficient-range".to_string()]));
    }

    /// Where the model's joint stops are counts from the first step whose answer rests on
    /// them: a bug that shows before a motion stalls at a stop does not rest on them; one
    /// read after it does.
    #[test]
    fn the_joint_stops_count_from_the_step_that_stalls_at_one() {
        let stall = "1M 20000";
        let (built, f) =
            unminimized_finding("bh8-262", gcl_model::Fault::FgetReversed, &["1FSET MCV 50", "FGET MCV", stall]);
        let whole = crate::suite::decisions_of_header(&built.transcript.header);
        assert!(whole.iter().any(|d| d == "bh8-position-bounds"), "{whole:?}");
        assert_eq!((f.level, f.rests_on), (gcl_model::Level::Must, vec![]));
        let (_, f) =
            unminimized_finding("bh8-262", gcl_model::Fault::FgetReversed, &[stall, "1FSET MCV 50", "FGET MCV"]);
        assert_eq!((f.level, f.rests_on), (gcl_model::Level::Info, vec!["bh8-position-bounds".to_string()]));
    }

    /// A status key is only its bits; against a baseline that has those bits on FGET, the same
    /// bits on another command are new (the independent seed hand's extra-args-ignored, `C 5`
    /// run instead of refused, hid behind its clean baseline's `FGET` with 26 names this way),
    /// one finding for all such commands; on FGET they stay known; other bits are new as before.
    #[test]
    fn a_status_the_baseline_has_on_another_command_is_new() {
        let dir = tempfile::tempdir().unwrap();
        let finding = |id: &str, key: &str| {
            format!(
                "gcl-transcript 1\nid: {id}\ntitle: t\nclause: seed: Supervisory mode\nlevel: MUST\nprofile: seed\nx-signature: {key}\n\nsend \"FGET\\r\"\nexpect \"FGET\\n\\rERR 1024\\n\\r=> \"\n"
            )
        };
        std::fs::write(dir.path().join("a.gcl"), finding("fuzz-fget-status-1024-missing", "status 1024 missing"))
            .unwrap();
        let mut b = Baseline::default();
        assert_eq!(b.add_dir(dir.path()).unwrap(), 1);
        let status = |command: &str, detail: &str| {
            let mut s = FindingSignature {
                command: command.into(),
                kind: "status".into(),
                detail: detail.into(),
                motors: String::new(),
                cause: String::new(),
                cause_step: None,
                explanation: String::new(),
                scope: String::new(),
            };
            b.qualify(&mut s);
            s
        };
        let known = |s: &FindingSignature| b.explains("seed", &finding_id(s), s).is_some();
        let (fget, c, o) = (status("FGET", "1024 missing"), status("C", "1024 missing"), status("O", "1024 missing"));
        assert!(known(&fget), "{}", fget.key());
        // New, and one finding for every other command that shows them (one bug, `C 5` and
        // `O 5` both run).
        assert!(!known(&c) && c.key() == "status 1024 missing elsewhere", "{}", c.key());
        assert_eq!(c.key(), o.key());
        let other = status("C", "64 missing");
        assert!(!known(&other) && other.key() == "status 64 missing", "{}", other.key());
        // A baseline written by a campaign against a baseline keys its statuses by command.
        std::fs::write(
            dir.path().join("a.gcl"),
            finding("fuzz-fget-status-1024-missing-at-fget", "status 1024 missing at FGET"),
        )
        .unwrap();
        let mut b2 = Baseline::default();
        b2.add_dir(dir.path()).unwrap();
        let mut again = status("FGET", "1024 missing");
        b2.qualify(&mut again);
        assert!(b2.explains("seed", &finding_id(&again), &again).is_some(), "{}", again.key());
        // A finding names every command its bits showed on in its campaign (`x-status-at`):
        // those are known too.
        let text = finding("fuzz-fget-status-1024-missing", "status 1024 missing")
            .replace("x-signature:", "x-status-at: fget io\nx-signature:");
        std::fs::write(dir.path().join("a.gcl"), text).unwrap();
        let mut b3 = Baseline::default();
        b3.add_dir(dir.path()).unwrap();
        let known3 = |command: &str| {
            let mut s = status(command, "1024 missing");
            b3.qualify(&mut s);
            b3.explains("seed", &finding_id(&s), &s).is_some()
        };
        assert!(known3("IO") && known3("FGET") && !known3("C"));
    }
}
