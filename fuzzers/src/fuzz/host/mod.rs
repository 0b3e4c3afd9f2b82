//! `gcl fuzz host`: an adversarial hand for host libraries.
//!
//! Each run starts a fresh simulated hand ([`session`]) whose answers a seeded
//! [`Schedule`] of misbehaviours changes ([`crate::sim::misbehave`]), runs the host command to
//! its end, and judges it ([`judge`]): a crash (signal, sanitizer report, Rust panic, Python
//! traceback, an exception a C++ runtime saw nobody catch), a hang, an unexpected exit code,
//! or a protocol violation ([`check`]). Findings are deduplicated by signature; each distinct
//! one is minimized (the fewest misbehaviours that still give the same signature) and written
//! as a bundle ([`bundle`]) that `--replay` runs again. Before the runs, [`calibrate`]
//! measures the host's own give-up time at each kind of answer (within a quarter of the
//! campaign's duration) for the hang timeout; a hang a run shows is a suspect until
//! [`confirm`] runs its schedule again waiting as long as the run budget allows: a host that
//! still neither sends nor exits is hung, one that acts late is a note. Before any random draw, a systematic pass (`systematic_pass`) puts every
//! misbehaviour, one per run, at every kind of answer the run without misbehaviour showed
//! (and makes one run at the hand's line rate when the campaign is unpaced). Guidance keeps
//! the schedules whose runs made the host take a new path after a misbehaviour (an operator
//! at a protocol state followed by a command not seen there before, or a new command
//! sequence) and mutates them; with the host's code coverage ([`coverage`], `--coverage`), also
//! those whose runs reached an edge of the host's code no earlier run had, mutated from a power
//! schedule (`next_covered`, `mutate`).
//!
//! Library code: no clap, no printing; progress goes to the caller through [`Event`]s.
//!
//! Calibration measures the host's give-up time at several kinds of answer at once (the hand goes
//! silent at the first answer of that kind), and the confirmer runs in a thread beside the runs. A campaign
//! without `--runs` or `--duration` is a 5-minute one. The systematic pass is built from run 0's
//! kinds of answer (each operator at each kind it applies to, in rounds; a line-rate run first when
//! unpaced). A silent wrong value is named by the host's `WHERE`, else by the answer it came from.
//! Operators are counted by protocol state and notes by runs. Runs are taken in index order and run
//! i is scheduled from run 0 and runs 0..=i-jobs only, so `--jobs` campaigns repeat run for run
//! (and the pass starts at run 1 whatever `--jobs`).
//!
//! The campaign (`Campaign`) is `fuzz.json` beside the reports; its schema is
//! `reports/fuzz-host.schema.json` (`SCHEMA`, checked by `tests/it/report_schema.rs`). A campaign
//! whose run without misbehaviour (the calibration's, or run 0) did not reach the host ends
//! (`Campaign::untested`); `Campaign::reached` counts the runs that reached it, and a stop by a
//! signal is `Campaign::stopped`; both become the report's `stopped` (`StopCause::CannotTest`,
//! `StopCause::Signal`) and exit 2 without a finding. A run in which the host never opened the port
//! or sent no byte is found by `unreached` (from `RunResult::port_opened` and the traffic).
//!
//! Under `--shard K/N` (`fuzz/shard.rs`) it runs its indices unguided, each schedule the pass's
//! entry for its index, then a schedule of the `--corpus` base read at its start ([`corpus`]), or
//! drawn from the seed and the index (`fresh_schedule`); a shard without run
//! 0 makes one uncounted run 0 for the answer count schedules span and the pass. Each shard's
//! report
//! records what makes it part of its campaign (`shard::Provenance`: `--shard`, seed, every option
//! that changed what ran, set by the CLI; a merged folder's `merged` slices). The merged host
//! report
//! is built by the same `campaign_report` as a shard's.

pub mod bundle;
pub mod check;
pub mod corpus;
pub mod coverage;
pub mod detect;
pub mod session;

use std::collections::{BTreeMap, BTreeSet};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Condvar, Mutex, mpsc};
use std::time::{Duration, Instant};

use rand_core::{RngCore, SeedableRng};
use rand_pcg::Pcg64Mcg;
use serde::{Deserialize, Serialize};

/// The JSON Schema of the campaign's `fuzz.json` ([`Campaign`]).
pub const SCHEMA: &str = include_str!("../../../../reports/fuzz-host.schema.json");

pub use check::{HostChecker, HostClause, HostViolation};
pub use session::{
    Dir, Exchange, HostEnd, HostRun, LONG_WAIT, Leftover, RunError, RunResult, Transport, Wait, WrongValue, run_once,
    run_once_until,
};

use crate::sim::Pace;
use crate::sim::misbehave::{AnswerKindSeen, Operator, Planned, Schedule};

/// What kind of finding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FindingKind {
    /// Death by a signal, or a sanitizer report, Rust panic or Python traceback on stderr.
    Crash,
    /// The host went silent, or overran its run budget.
    Hang,
    /// The host exited with a code not in `--ok-exit-codes`.
    ExitCode,
    /// The host broke the protocol.
    Violation,
    /// The host left a process behind that held the port or its stderr after it ended (killed).
    Leftover,
    /// The host observed a value the hand never sent and did not say anything was wrong
    /// (`gcl-observe:` lines).
    #[serde(rename = "silent-wrong-value")]
    WrongValue,
}

impl FindingKind {
    /// The kebab-case name.
    pub fn name(self) -> &'static str {
        match self {
            FindingKind::Crash => "crash",
            FindingKind::Hang => "hang",
            FindingKind::ExitCode => "exit-code",
            FindingKind::Violation => "violation",
            FindingKind::Leftover => "leftover",
            FindingKind::WrongValue => "silent-wrong-value",
        }
    }
}

/// One problem a run showed.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Verdict {
    /// Its kind.
    pub kind: FindingKind,
    /// Stable across runs of the same bug (the deduplication key).
    pub signature: String,
    /// One line for people.
    pub message: String,
}

/// A hang's signature and message: by the host's stack when it could be taken (one bug, one
/// signature, whatever the protocol state it hangs in), else by the protocol state without
/// the command it followed.
fn hang_verdict(r: &RunResult, state: &str, over_budget: bool) -> Verdict {
    let what = if over_budget { "the host overran its run budget" } else { "the host neither sent nor exited" };
    match &r.stack {
        Some(st) => Verdict {
            kind: FindingKind::Hang,
            signature: format!("hang in {}", st.site()),
            message: match &st.blocked_in {
                Some(b) => format!(
                    "{what} ({state}), blocked in {} called from {} ({}; a pyserial port's deadline is its timeout)",
                    b.call, st.frames, st.by
                ),
                None => match &st.waits_in {
                    Some(w) => format!("{what} ({state}), stuck in {}, waiting in {w} ({})", st.frames, st.by),
                    None => format!("{what} ({state}), stuck in {} ({})", st.frames, st.by),
                },
            },
        },
        None => {
            let coarse = state.split(" after ").next().unwrap_or(state);
            let budget = if over_budget { "over budget, " } else { "" };
            Verdict {
                kind: FindingKind::Hang,
                signature: format!("hang: {budget}{coarse}"),
                message: format!("{what} ({state}; no stack could be taken)"),
            }
        }
    }
}

/// The signature of a host killed at the run budget while it still sent (a poll without end, a
/// flood the hand's line rate holds up): it never exited by itself.
pub const OVER_BUDGET_SENDING: &str = "over budget: still sending when the run budget ended";

/// An unexpected exit code's signature: the class of the exit and the hand's mode when the
/// host left, not the code. A host whose code says what went wrong (the last status it read,
/// an errno) exits with a different code for every cause the hand gives it, and one habit
/// (exiting non-zero where it must not) is one finding; the code is in the message. A host
/// that leaves non-zero in RealTime and also in supervisory mode does so from two places in
/// its code: two findings.
fn exit_code_signature(ended_in: &str) -> String {
    let mode = if ended_in.starts_with("RealTime") { "in RealTime" } else { "in supervisory mode" };
    format!("exit-code: not an accepted code, {mode}")
}

/// The INFO notes of a run: how the host reacted to the hand's own misbehaviour where that
/// was no unsafe reaction ([`HostViolation::is_note`]), as `clause: kind` with the detail.
pub fn notes(r: &RunResult) -> Vec<(String, String)> {
    r.violations
        .iter()
        .filter(|x| x.is_note())
        .map(|x| (format!("note: {}: {}", x.clause.id(), x.kind), format!("{}: {}", x.clause.title(), x.detail)))
        .collect()
}

/// Judges a run: every problem it shows, the most serious first (crash, hang, exit code,
/// leftover processes, violations). Violations that are only notes are not among them.
pub fn judge(r: &RunResult, ok_exit_codes: &[i32]) -> Vec<Verdict> {
    let mut v = Vec::new();
    let report = detect::crash_report(&r.stderr);
    match (&r.end, &report) {
        // An exception nobody caught ends in SIGABRT: what was thrown (and where) says more.
        (HostEnd::Signal(s), Some(c)) if c.kind == "c++" => v.push(Verdict {
            kind: FindingKind::Crash,
            signature: format!("crash: {}", c.signature),
            message: format!("the host died of {}: {}", detect::signal_name(*s), c.headline),
        }),
        (HostEnd::Signal(s), _) => {
            let frames = report.as_ref().map(|c| format!(" ({})", c.signature)).unwrap_or_default();
            let name = detect::signal_name(*s);
            v.push(Verdict {
                kind: FindingKind::Crash,
                signature: format!("crash: {name}{frames}"),
                message: format!("the host died of {name}{frames}"),
            });
        }
        (_, Some(c)) => v.push(Verdict {
            kind: FindingKind::Crash,
            signature: format!("crash: {}", c.signature),
            message: c.headline.clone(),
        }),
        (HostEnd::Hung(state), _) => v.push(hang_verdict(r, state, false)),
        // Still sending when the budget stopped it: acting, not hung in one place of its
        // code (its pending line is judged as it stood), but it never ended by itself, and
        // ending within the run budget is the host's to do: one finding, whatever it sent.
        (HostEnd::OverBudget(state), _) if r.talking_at_end => v.push(Verdict {
            kind: FindingKind::Hang,
            signature: OVER_BUDGET_SENDING.to_string(),
            message: format!(
                "the host was still sending when the run budget ended ({state}) and was killed: it never exited by itself"
            ),
        }),
        (HostEnd::OverBudget(state), _) => v.push(hang_verdict(r, state, true)),
        (HostEnd::Exit(c), _) if !ok_exit_codes.contains(c) => {
            let last = r.stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or_default();
            v.push(Verdict {
                kind: FindingKind::ExitCode,
                signature: exit_code_signature(&r.ended_in),
                message: match last.trim() {
                    "" => format!("the host exited with {c} ({})", r.ended_in),
                    last => format!(
                        "the host exited with {c} ({}): {}",
                        r.ended_in,
                        crate::report::truncate_note(last, 200)
                    ),
                },
            });
        }
        (HostEnd::Exit(_) | HostEnd::Served, _) => {}
    }
    if !r.leftovers.is_empty() {
        // Named by what was left (its command line, the same from run to run); where it was
        // (its stack, which may differ) goes into the message.
        let mut commands: Vec<&str> = r.leftovers.iter().map(|l| l.command.as_str()).collect();
        commands.sort_unstable();
        commands.dedup();
        let left: Vec<String> = r.leftovers.iter().map(ToString::to_string).collect();
        v.push(Verdict {
            kind: FindingKind::Leftover,
            signature: format!("leftover: {}", commands.join(" + ")),
            message: format!(
                "the host left {} behind holding the port or its stderr (or, over TCP, under the write watch) after it ended; killed",
                left.join("; ")
            ),
        });
    }
    if let Some(first) = r.wrong_values.first() {
        let seen: Vec<&str> = r.wrong_values.iter().map(|w| w.observed.as_str()).collect();
        v.push(Verdict {
            kind: FindingKind::WrongValue,
            signature: format!("silent wrong value: {} {}", first.name(), first.site()),
            message: format!(
                "the host observed {} that the hand never sent ({}), and reported nothing wrong",
                seen.join(", "),
                first.context()
            ),
        });
    }
    for x in r.violations.iter().filter(|x| !x.is_note()) {
        v.push(Verdict {
            kind: FindingKind::Violation,
            signature: format!("violation: {}: {}", x.clause.id(), x.kind),
            message: format!("{}: {}", x.clause.title(), x.detail),
        });
    }
    v.into_iter().map(bounded).collect()
}

/// The longest signature kept whole. A signature quotes the host's own text (a panic's path,
/// a function's name, an exception's line), which a host may make as long as it likes (a
/// 100 KB panic path was a 100 KB finding line and heading in every report).
pub const SIGNATURE_CAP: usize = 240;

/// The longest message of a finding kept.
const MESSAGE_CAP: usize = 4096;

/// `v` with its signature and message within [`SIGNATURE_CAP`] and [`MESSAGE_CAP`]: a longer
/// signature is cut and ends with a digest of the whole (`… #1a2b3c4d`), so that it stays the
/// same from run to run and two long ones stay apart.
fn bounded(mut v: Verdict) -> Verdict {
    if v.signature.len() > SIGNATURE_CAP {
        let mut cut = SIGNATURE_CAP - 16;
        while !v.signature.is_char_boundary(cut) {
            cut -= 1;
        }
        let digest = crate::digest::sha256_hex(v.signature.as_bytes());
        v.signature = format!("{}… #{}", &v.signature[..cut], &digest[..8]);
    }
    if v.message.len() > MESSAGE_CAP {
        v.message = crate::report::truncate_note(&v.message, MESSAGE_CAP);
    }
    v
}

impl std::fmt::Display for HostEnd {
    /// How the host ended, for people: `exited with code 2`, `killed by signal 9`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HostEnd::Exit(c) => write!(f, "exited with code {c}"),
            HostEnd::Signal(s) => write!(f, "was killed by signal {s}"),
            HostEnd::Hung(at) => write!(f, "hung ({at}) and was killed"),
            HostEnd::OverBudget(at) => write!(f, "ran over the run budget ({at}) and was killed"),
            HostEnd::Served => write!(f, "was served: no host process was run"),
        }
    }
}

/// Lines of the host's stderr an [`unreached`] message quotes, from its end.
const STDERR_TAIL_LINES: usize = 3;

/// Why a run judged nothing of the host, or `None` when the host opened the port and sent
/// the hand at least one byte. A host that never opened the port (a script that does not
/// exist, a command that ignores `{port}`), or opened it and sent nothing, exercised no
/// clause: what such a run shows is no verdict on the host. The message names `command`,
/// how it ended, and the last lines of its stderr (escaped: they are the host's bytes).
pub fn unreached(r: &RunResult, command: &[String]) -> Option<String> {
    let sent = r.exchanges.iter().any(|e| e.dir == Dir::Host && !e.bytes.is_empty());
    let what = match (r.port_opened, sent) {
        (_, true) => return None,
        (false, _) => "the host never opened the port",
        (true, false) => "the host opened the port but sent nothing",
    };
    let tail: Vec<String> = r
        .stderr
        .lines()
        .rev()
        .filter(|l| !l.trim().is_empty())
        .take(STDERR_TAIL_LINES)
        .map(|l| crate::report::truncate_note(&gcl_model::escape::escape(l.trim_end().as_bytes()), 200))
        .collect();
    let stderr = if tail.is_empty() {
        "it wrote nothing on stderr".to_string()
    } else {
        let tail: Vec<String> = tail.into_iter().rev().collect();
        format!("the last lines of its stderr: {}", tail.join(" | "))
    };
    let command = crate::report::truncate_note(&command.join(" "), 200);
    Some(format!("{what}: `{command}` {}; {stderr}", r.end))
}

/// Operators and their weights.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Weights(pub Vec<(Operator, u32)>);

impl Default for Weights {
    fn default() -> Weights {
        Weights(Operator::ALL.iter().map(|o| (*o, o.default_weight())).collect())
    }
}

impl Weights {
    /// Only these operators, at their default weights (`--ops a,b`), or `op=weight` pairs.
    pub fn parse(list: &str) -> Result<Weights, String> {
        let mut v = Vec::new();
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (name, weight) = item.split_once('=').map_or((item, None), |(n, w)| (n, Some(w)));
            let op: Operator = name.parse().map_err(|e: crate::sim::misbehave::UnknownOperator| e.to_string())?;
            let w = match weight {
                Some(w) => w.parse::<u32>().map_err(|_| format!("`{item}`: the weight must be a whole number"))?,
                None => op.default_weight(),
            };
            v.push((op, w));
        }
        if v.iter().all(|(_, w)| *w == 0) {
            return Err("no operator with a weight above 0".into());
        }
        Ok(Weights(v))
    }

    fn pick(&self, rng: &mut Pcg64Mcg) -> Operator {
        let total: u64 = self.0.iter().map(|(_, w)| u64::from(*w)).sum();
        let mut x = rng.next_u64() % total.max(1);
        for (op, w) in &self.0 {
            if x < u64::from(*w) {
                return *op;
            }
            x -= u64::from(*w);
        }
        self.0[0].0
    }
}

/// How a campaign runs.
#[derive(Debug, Clone)]
pub struct FuzzOptions {
    /// The run itself.
    pub run: HostRun,
    /// The campaign's seed.
    pub seed: u64,
    /// Stop after this many runs...
    pub runs: Option<u64>,
    /// ...or after this long.
    pub duration: Option<Duration>,
    /// Exit codes that are no finding.
    pub ok_exit_codes: Vec<i32>,
    /// Runs at once, each on its own line.
    pub jobs: usize,
    /// The operators and their weights.
    pub weights: Weights,
    /// Most misbehaviours in a fresh schedule.
    pub max_planned: usize,
    /// Minimize each new finding's schedule.
    pub minimize: bool,
    /// Mutate the schedules of runs that took a new path (off: every schedule is fresh).
    pub guided: bool,
    /// Measure the host's own give-up time first ([`calibrate`]) and call a hang only well
    /// past it (`run.timeout_hang` is then the least hang timeout).
    pub calibrate: bool,
    /// Run only this slice of the campaign's run indices (`--shard K/N`). A sharded campaign
    /// is unguided, its schedules drawn from the seed and the run index alone (guidance would
    /// need the other machines' runs), so the shards of a campaign together make exactly the
    /// runs of `--shard 1/1`, which are those of `guided: false` with one job.
    pub shard: Option<super::shard::Shard>,
}

impl FuzzOptions {
    /// How long the campaign may run: `duration`, or without `runs` either, a time budget
    /// ([`DEFAULT_DURATION`]); `None` with `runs` alone.
    pub fn campaign_duration(&self) -> Option<Duration> {
        self.duration.or(self.runs.is_none().then_some(DEFAULT_DURATION))
    }

    /// The campaign's run index of this campaign's `t`-th run (its shard's).
    fn run_index(&self, t: u64) -> u64 {
        self.shard.map_or(t, |s| s.global(t))
    }
}

/// The longest a calibration run waits for the host to act after the hand goes silent.
pub const CALIBRATION_CAP: Duration = Duration::from_secs(30);

/// The campaign a `gcl fuzz host` without `--runs` or `--duration` makes: a time budget that
/// fits a coffee break whatever the host's speed (a host that takes 9 s a run made 1000 runs
/// in 2 h 30 min).
pub const DEFAULT_DURATION: Duration = Duration::from_secs(5 * 60);

/// Calibration takes at most this fraction of a campaign's duration (a quarter); what it has
/// not measured by then it leaves, and the campaign goes on with what it measured.
pub const CALIBRATION_SHARE: u32 = 4;

/// A run found void (processes of two runs held its port) is made again up to this many
/// times; then it is left out, never a finding.
pub const VOID_RETRIES: usize = 3;

/// Most void runs described in [`Campaign::void`].
const VOID_KEPT: usize = 8;

/// A campaign's slots: at most `jobs` hosts alive at once, whatever runs them (the runs,
/// calibration, minimization, a hang's confirmation), each run in one slot, taken in the order
/// asked for. A run's `link` may name its slot (`{slot}`, from 1): each slot has its own link,
/// so a link never serves two live hosts. A run found void ([`RunError::Shared`]) is made again
/// ([`VOID_RETRIES`]), and counted, and from then on one host is alive at a time: a process of
/// another run can reach a port only while that run is alive or through what it left behind
/// (ended with its run, by its mark), so the rest of the campaign cannot share a port, whether
/// or not a look would have caught it (a process that opens and closes a port between two
/// looks is not seen; nothing on Linux names a pty's opener to an unprivileged watcher).
#[derive(Debug)]
pub struct Slots {
    state: Mutex<SlotState>,
    freed: Condvar,
    /// Void runs, and how the first few were void.
    void: Mutex<(u64, Vec<String>)>,
}

#[derive(Debug)]
struct SlotState {
    /// Each slot: taken or free.
    taken: Vec<bool>,
    /// The next ticket given, and the ticket served next.
    next: u64,
    serving: u64,
    /// Tickets given up (their run called off) before they were served.
    abandoned: BTreeSet<u64>,
    /// How many slots may be taken at once: all, or one after a void run.
    width: usize,
}

impl SlotState {
    /// The next ticket not given up is served next.
    fn advance(&mut self) {
        self.serving += 1;
        while self.abandoned.remove(&{ self.serving }) {
            self.serving += 1;
        }
    }
}

impl Slots {
    /// `jobs` slots (at least one).
    pub fn new(jobs: usize) -> Slots {
        Slots {
            state: Mutex::new(SlotState {
                taken: vec![false; jobs.max(1)],
                next: 0,
                serving: 0,
                abandoned: BTreeSet::new(),
                width: jobs.max(1),
            }),
            freed: Condvar::new(),
            void: Mutex::new((0, Vec::new())),
        }
    }

    /// Waits for a free slot, in turn; `None` when `stop` is set first.
    fn take(&self, stop: &AtomicBool) -> Option<usize> {
        let mut st = self.state.lock().ok()?;
        let ticket = st.next;
        st.next += 1;
        loop {
            if st.serving == ticket
                && st.taken.iter().filter(|t| **t).count() < st.width
                && let Some(k) = st.taken.iter().position(|t| !t)
            {
                st.taken[k] = true;
                st.advance();
                self.freed.notify_all();
                return Some(k);
            }
            if stop.load(Ordering::Relaxed) {
                if st.serving == ticket {
                    st.advance();
                } else {
                    st.abandoned.insert(ticket);
                }
                self.freed.notify_all();
                return None;
            }
            st = self.freed.wait_timeout(st, Duration::from_millis(50)).ok()?.0;
        }
    }

    fn give(&self, k: usize) {
        if let Ok(mut st) = self.state.lock() {
            st.taken[k] = false;
        }
        self.freed.notify_all();
    }

    /// Runs `schedule` in a slot (its link, when `run` has one, made for the slot): made again
    /// when void, up to [`VOID_RETRIES`] times, then [`RunError::Shared`].
    pub fn run(&self, run: &HostRun, schedule: &Schedule, stop: &AtomicBool) -> Result<RunResult, RunError> {
        let Some(k) = self.take(stop) else { return Err(RunError::Cancelled) };
        let mut spec = run.clone();
        if let Some(l) = &run.link {
            spec.link = Some(l.to_string_lossy().replace("{slot}", &(k + 1).to_string()).into());
        }
        let mut tries = 0;
        let r = loop {
            // A fresh coverage map for each try: a void try's edges are not the run's.
            let map = match coverage::map_for(spec.coverage, &mut spec.env) {
                Ok(m) => m,
                Err(e) => break Err(e.into()),
            };
            let r = run_once_until(&spec, schedule, stop).map(|mut r| {
                r.edges = map.as_ref().map(coverage::ShmMap::edges);
                r
            });
            match r {
                Err(RunError::Shared(why)) => {
                    self.found_void(&why);
                    tries += 1;
                    if tries > VOID_RETRIES {
                        break Err(RunError::Shared(why));
                    }
                }
                other => break other,
            }
        };
        self.give(k);
        r
    }

    /// Counts a void run and narrows the campaign to one host alive at a time.
    fn found_void(&self, why: &str) {
        if let Ok(mut v) = self.void.lock() {
            v.0 += 1;
            if v.1.len() < VOID_KEPT {
                v.1.push(why.to_string());
            }
        }
        self.narrow();
    }

    /// One host alive at a time from now on.
    fn narrow(&self) {
        if let Ok(mut st) = self.state.lock() {
            st.width = 1;
        }
    }

    /// Void runs so far, and how the first few were.
    fn voided(&self) -> (u64, Vec<String>) {
        self.void.lock().map(|v| v.clone()).unwrap_or_default()
    }
}

/// One kind of answer calibration silenced the hand at, and how long the host waited there.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct KindWait {
    /// The kind of answer (`banner, prompt`), as the systematic pass names it.
    pub kind: String,
    /// Its first answer in the run without misbehaviour, where the hand went silent.
    pub answer: u32,
    /// The protocol state of that answer (`answer to RESET`).
    pub state: String,
    /// The host's give-up time, milliseconds, or `None` when it neither sent nor exited while
    /// calibration waited ([`KindWait::waited_past_ms`]).
    pub gave_up_ms: Option<u64>,
    /// How long calibration waited for it there, milliseconds.
    pub waited_past_ms: u64,
    /// That wait was cut short by calibration's share of the campaign (a quarter of its
    /// duration), not by [`CALIBRATION_CAP`] or the run budget.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub cut_by_share: bool,
}

/// What calibration measured: how long the host waits for a hand that went silent, at each
/// kind of answer.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Calibration {
    /// For each answer the hand went silent at: the host's give-up time in milliseconds, or
    /// `None` when it neither sent nor exited while calibration waited (the same as
    /// `by_kind`, by answer).
    pub points: Vec<(u32, Option<u64>)>,
    /// The same by kind of answer (one silence at the first answer of each kind).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub by_kind: Vec<KindWait>,
    /// The longest give-up time measured, milliseconds: the host's own timeout.
    pub host_timeout_ms: Option<u64>,
    /// The hang timeout the campaign used, milliseconds.
    pub timeout_hang_ms: u64,
    /// Runs it took.
    pub runs: u64,
    /// Why nothing could be measured: the run without misbehaviour did not reach the host
    /// ([`unreached`]); the campaign ends there (its [`Campaign::untested`]).
    #[serde(skip)]
    pub untested: Option<String>,
    /// The most it could take, milliseconds (a quarter of the campaign's duration), if the
    /// campaign has a duration.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub share_ms: Option<u64>,
    /// Wall time it took, milliseconds.
    #[serde(default)]
    pub elapsed_ms: u64,
    /// The kinds of answer it did not measure: its share ran out first.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unmeasured: Vec<String>,
    /// Runs in which the host neither sent nor exited for longer than the hang timeout after
    /// the hand fell silent: hangs calibration saw, which the campaign confirms and reports.
    #[serde(skip)]
    pub suspects: Vec<(Schedule, RunResult)>,
    /// Runs found void (processes of two runs held one port) and made again.
    #[serde(skip)]
    pub void_runs: u64,
    /// How the first few of them were void.
    #[serde(skip)]
    pub void: Vec<String>,
}

/// The hang timeout for a host that gives up after `host_timeout` at most: twice as long plus
/// 2 s (a host may wait out two reads in a row before it sends or exits), at least `floor`,
/// at most `cap`.
pub fn hang_timeout(host_timeout: Option<Duration>, floor: Duration, cap: Duration) -> Duration {
    let t = host_timeout.map_or(floor, |h| (h * 2 + Duration::from_secs(2)).max(floor));
    t.min(cap)
}

/// Measures how long the host waits when the hand goes silent, at every kind of answer: a run
/// without misbehaviour (for the kinds of answer it gives, those the systematic pass covers),
/// then, for each kind, a run where the hand goes silent at its first answer, waiting up to
/// [`CALIBRATION_CAP`] (or the run budget) for the host to send or exit; `jobs` of them at once
/// at most (the campaign's slots: [`Slots`]). The hang timeout is [`hang_timeout`] of the longest wait seen. With `share`, it ends
/// within that time: each run's wait is cut to what is left of it, and kinds not reached are
/// left unmeasured ([`Calibration::unmeasured`]). A run where the host waited longer than
/// the hang timeout without acting is a hang calibration saw ([`Calibration::suspects`]).
pub fn calibrate(
    run: &HostRun,
    share: Option<Duration>,
    jobs: usize,
    stop: &AtomicBool,
) -> Result<Calibration, RunError> {
    let started = Instant::now();
    let deadline = share.map(|s| started + s);
    let left = || deadline.map_or(Duration::MAX, |d| d.saturating_duration_since(Instant::now()));
    let limited = |r: &mut HostRun| {
        r.timeout_hang = CALIBRATION_CAP.min(run.budget).min(left());
        r.budget = run.budget.min(left());
    };
    let slots = Slots::new(jobs);
    let mut quiet = run.clone();
    limited(&mut quiet);
    let clean = slots.run(&quiet, &Schedule::default(), stop)?;
    if let Some(why) = unreached(&clean, &run.command) {
        let timeout_hang_ms = run.timeout_hang.as_millis() as u64;
        let elapsed_ms = started.elapsed().as_millis() as u64;
        return Ok(Calibration { runs: 1, untested: Some(why), timeout_hang_ms, elapsed_ms, ..Default::default() });
    }
    let kinds: Vec<AnswerKindSeen> =
        clean.answer_kinds.iter().filter(|k| k.ops.contains(&Operator::Silence)).cloned().collect();
    let next = AtomicU64::new(0);
    type Measured = (usize, Option<(KindWait, Option<(Schedule, RunResult)>)>);
    let measured: Mutex<Vec<Measured>> = Mutex::new(Vec::new());
    let error: Mutex<Option<RunError>> = Mutex::new(None);
    let worker = || {
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed) as usize;
            let Some(k) = kinds.get(i) else { return };
            if stop.load(Ordering::Relaxed) || error.lock().map_or(true, |e| e.is_some()) {
                return;
            }
            let mut r = run.clone();
            limited(&mut r);
            let cut_by_share = r.timeout_hang < CALIBRATION_CAP.min(run.budget);
            if r.timeout_hang < LONG_WAIT {
                // The share has run out: this kind is left unmeasured.
                if let Ok(mut m) = measured.lock() {
                    m.push((i, None));
                }
                continue;
            }
            let silence = Schedule { planned: vec![Planned { answer: k.answer, op: Operator::Silence, arg: 0 }] };
            match slots.run(&r, &silence, stop) {
                Ok(result) => {
                    if result.fired.is_empty() {
                        continue;
                    }
                    let gave_up_ms = result.gave_up_after.map(|d| d.as_millis() as u64);
                    let still = result.waits.iter().rev().find(|w| !w.acted).map(|w| w.waited);
                    let waited_past_ms =
                        gave_up_ms.unwrap_or_else(|| still.unwrap_or(r.timeout_hang).as_millis() as u64);
                    let point = KindWait {
                        kind: k.kind.clone(),
                        answer: k.answer,
                        state: k.state.clone(),
                        gave_up_ms,
                        waited_past_ms,
                        cut_by_share: cut_by_share && gave_up_ms.is_none(),
                    };
                    let silent = gave_up_ms.is_none() && !result.talking_at_end && still.is_some();
                    let suspect = silent.then_some((silence, result));
                    if let Ok(mut m) = measured.lock() {
                        m.push((i, Some((point, suspect))));
                    }
                }
                // Void every time: left unmeasured.
                Err(RunError::Shared(_)) => {
                    if let Ok(mut m) = measured.lock() {
                        m.push((i, None));
                    }
                }
                Err(e) => {
                    if let Ok(mut slot) = error.lock() {
                        slot.get_or_insert(e);
                    }
                    return;
                }
            }
        }
    };
    std::thread::scope(|s| {
        for _ in 0..jobs.min(kinds.len()).max(1) {
            s.spawn(worker);
        }
    });
    if let Some(e) = error.into_inner().ok().flatten() {
        return Err(e);
    }
    if stop.load(Ordering::Relaxed) {
        return Err(RunError::Cancelled);
    }
    let mut measured = measured.into_inner().unwrap_or_default();
    measured.sort_by_key(|(i, _)| *i);
    let mut c = Calibration {
        runs: 1 + measured.iter().filter(|(_, m)| m.is_some()).count() as u64,
        share_ms: share.map(|s| s.as_millis() as u64),
        ..Default::default()
    };
    let mut silent = Vec::new();
    for (i, m) in measured {
        match m {
            Some((point, suspect)) => {
                c.points.push((point.answer, point.gave_up_ms));
                c.by_kind.push(point);
                silent.extend(suspect);
            }
            None => c.unmeasured.push(kinds[i].kind.clone()),
        }
    }
    c.host_timeout_ms = c.by_kind.iter().filter_map(|k| k.gave_up_ms).max();
    let t = hang_timeout(c.host_timeout_ms.map(Duration::from_millis), run.timeout_hang, run.budget);
    c.timeout_hang_ms = t.as_millis() as u64;
    // A host that waited past the hang timeout where the hand fell silent hangs there (to be
    // confirmed like any other hang).
    c.suspects = silent
        .into_iter()
        .filter(|(_, r)| r.waits.iter().any(|w| !w.acted && w.waited > t))
        .map(|(s, mut r)| {
            // Judged as the campaign's hang rule would: silent past its hang timeout.
            if let HostEnd::OverBudget(state) = &r.end {
                r.end = HostEnd::Hung(state.clone());
            }
            (s, r)
        })
        .collect();
    (c.void_runs, c.void) = slots.voided();
    c.elapsed_ms = started.elapsed().as_millis() as u64;
    Ok(c)
}

impl Finding {
    /// Takes the minimized schedule and the run it gave.
    fn shrunk(&mut self, schedule: Schedule, r: RunResult) {
        self.schedule = schedule;
        self.fired = r.fired;
        self.end = r.end;
        self.stderr = r.stderr;
        self.exchanges = r.exchanges;
    }
}

/// A distinct finding.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Finding {
    /// The verdict.
    pub verdict: Verdict,
    /// The run that first showed it (0 is the run without misbehaviour).
    pub run: u64,
    /// Wall time from the campaign's start to that run's end.
    pub found_after_ms: u64,
    /// How many runs showed it.
    pub hits: u64,
    /// The schedule that gave it, minimized.
    pub schedule: Schedule,
    /// The schedule as first found.
    pub original: Schedule,
    /// The misbehaviours that fired in the minimized run, with their states.
    pub fired: Vec<crate::sim::misbehave::Fired>,
    /// How the host ended in it.
    pub end: HostEnd,
    /// The hang timeout it was found with, milliseconds (calibrated or given).
    #[serde(default)]
    pub timeout_hang_ms: u64,
    /// A hang: how long a second run of its schedule waited, milliseconds, with the host still
    /// neither sending nor exiting (a hang is reported only so confirmed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub confirmed_after_ms: Option<u64>,
    /// Found by calibration (the hand silent at one answer, before the campaign's runs), not
    /// by a run of the campaign (`run` is then 0).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub by_calibration: bool,
    /// The host's stderr in it.
    #[serde(skip)]
    pub stderr: String,
    /// The bytes both ways in it.
    #[serde(skip)]
    pub exchanges: Vec<Exchange>,
    /// The edges of the host's code its first run reached before any earlier run of the
    /// campaign (empty without coverage): its minimized schedule must reach them too
    /// ([`minimize`]).
    #[serde(skip)]
    pub first_edges: Vec<u32>,
}

/// What a campaign tells its caller as it goes.
#[derive(Debug, Clone)]
pub enum Event {
    /// A run ended.
    Run {
        /// Its number.
        index: u64,
        /// Its length.
        elapsed: Duration,
    },
    /// A new distinct finding (after minimization).
    Found(Box<Finding>),
    /// Calibration ended, before the runs: what it measured.
    Calibrated(Box<Calibration>),
    /// A suspected hang's schedule runs again to confirm it, waiting up to `wait` for the host
    /// to act: said before the wait, which may be the whole run budget.
    Confirming {
        /// The hang's signature.
        signature: String,
        /// Where the host waited (`awaiting the answer after RESET`).
        state: String,
        /// The longest the confirmation waits.
        wait: Duration,
    },
}

/// A campaign's results.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Campaign {
    /// Runs made (minimization runs not counted).
    pub runs: u64,
    /// Runs made to minimize.
    pub minimize_runs: u64,
    /// Wall time, milliseconds.
    pub elapsed_ms: u64,
    /// Distinct findings, in the order found.
    pub findings: Vec<Finding>,
    /// How often each operator fired at each protocol state.
    pub fired_at: BTreeMap<String, BTreeMap<String, u64>>,
    /// Schedules kept by guidance.
    pub corpus: usize,
    /// Distinct paths seen (operator at state, then the host's next command).
    pub paths: usize,
    /// The host's own timeouts as calibration measured them, and the hang timeout used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<Calibration>,
    /// INFO notes (how the host reacted to the hand's misbehaviour, no finding), with the
    /// number of runs that showed each.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub notes: BTreeMap<String, u64>,
    /// The kinds of answer the run without misbehaviour showed, which the systematic pass
    /// covers (the module's notes).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub answer_kinds: Vec<AnswerKindSeen>,
    /// Runs of the systematic pass (made or not: a short campaign may end inside it).
    #[serde(default)]
    pub pass_runs: u64,
    /// How much of the systematic pass this campaign made, and what it did not reach
    /// ([`Campaign::pass_line`] says it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pass: Option<PassAccount>,
    /// What makes it (a shard of) a campaign: its `--shard`, seed and options, and for a
    /// merged folder the shards it holds. Set by the CLI, which knows the options as given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<crate::fuzz::shard::Provenance>,
    /// Runs in which the host opened the port and sent the hand at least one byte: the runs
    /// that judged anything of it.
    #[serde(default)]
    pub reached: u64,
    /// Why the campaign could not test: its run without misbehaviour (calibration's, or run
    /// 0) did not reach the host ([`unreached`]), and it ended there.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub untested: Option<String>,
    /// How a signal stopped the campaign (`stopped by SIGTERM after 3 of 1000 runs`), set by
    /// the caller that heard it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// Runs found void, calibration's included: processes of two runs held one port (a host
    /// that opens a fixed device path, linked to another run's port). Each was made again
    /// ([`VOID_RETRIES`] times at most), none judged.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub void_runs: u64,
    /// How the first few of them were void.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub void: Vec<String>,
    /// The host's code coverage, when the runs read it (`--coverage`): edges reached, over
    /// time, the schedules that added some; or why there was none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<coverage::CoverageAccount>,
    /// Schedules of an earlier campaign's corpus (`--corpus`) this one was given to run.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub seeds: u64,
    /// The schedules guidance kept, in the order kept, each with its run's edges (what
    /// `--corpus` saves).
    #[serde(skip)]
    pub kept: Vec<corpus::Entry>,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// A run of the systematic pass that a campaign was to make and did not (its runs or its
/// time ran out first, or a signal stopped it).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PassLeft {
    /// The misbehaviour.
    pub op: Operator,
    /// The answer it was planned at: the first of its kind.
    pub answer: u32,
    /// That kind of answer (`banner, prompt`).
    pub kind: String,
}

/// How much of its systematic pass a campaign made: the runs made, those not reached, and
/// about how long a campaign with the same `--jobs` needs to make them all.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct PassAccount {
    /// Runs of the pass made (each ran to its end, whatever it found).
    pub made: u64,
    /// The runs of the pass this campaign was to make and did not, in the pass's order (a
    /// shard's: those of its own run indices).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_reached: Vec<PassLeft>,
    /// About how long, milliseconds, a campaign with the same `--jobs` takes from its start to
    /// the end of the whole pass (calibration, the runs before the pass, the pass), estimated
    /// from the runs made (by misbehaviour) and calibration's waits; absent when the pass was
    /// complete or nothing was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub complete_ms: Option<u64>,
    /// The campaign's `--jobs`, which the estimate is for.
    pub jobs: u64,
}

impl PassAccount {
    /// Every run of the pass this campaign was to make was made.
    pub fn complete(&self) -> bool {
        self.not_reached.is_empty()
    }
}

/// A duration for people, rounded: `40 s` below two minutes, else whole minutes, up.
pub fn about(ms: u64) -> String {
    if ms < 120_000 { format!("{} s", ms.div_ceil(1000).max(1)) } else { format!("{} min", ms.div_ceil(60_000)) }
}

impl Campaign {
    /// What the summary says of the systematic pass: how many of its runs were made, and,
    /// only when all were, that every misbehaviour met every kind of answer; else what was not
    /// reached and about how long a complete pass needs. `None` without a pass (the campaign
    /// ended before run 0 was taken in, or no misbehaviour applies).
    pub fn pass_line(&self) -> Option<String> {
        if self.pass_runs == 0 {
            return None;
        }
        let kinds: Vec<&str> = self.answer_kinds.iter().map(|k| k.kind.as_str()).collect();
        let kinds = kinds.join("; ");
        let Some(p) = &self.pass else {
            return Some(format!(
                "systematic pass: {} runs planned (how many were made is not recorded) ({kinds})",
                self.pass_runs
            ));
        };
        let owned = p.made + p.not_reached.len() as u64;
        // A shard's share, or a merge of some shards: the other runs are other shards'.
        let others = self.pass_runs.saturating_sub(owned);
        let elsewhere = if others > 0 { format!(", {others} left to other shards") } else { String::new() };
        if p.complete() && others == 0 {
            return Some(format!(
                "systematic pass: {} of {} runs, every misbehaviour at every kind of answer ({kinds})",
                p.made, self.pass_runs
            ));
        }
        if p.complete() {
            return Some(format!(
                "systematic pass: {} of {} runs ({} made here, all of this campaign's share{elsewhere}) ({kinds})",
                p.made, self.pass_runs, p.made
            ));
        }
        // Not reached, by misbehaviour in the pass's order: `silence x4, hang-up x3`.
        let mut by_op: Vec<(Operator, usize)> = Vec::new();
        for l in &p.not_reached {
            match by_op.iter_mut().find(|(op, _)| *op == l.op) {
                Some((_, n)) => *n += 1,
                None => by_op.push((l.op, 1)),
            }
        }
        let left: Vec<String> = by_op.iter().map(|(op, n)| format!("{op} x{n}")).collect();
        let needs = match p.complete_ms {
            Some(ms) => format!("; a complete pass needs about {} at --jobs {}", about(ms), p.jobs),
            None => String::new(),
        };
        Some(format!(
            "systematic pass: {} of {} runs ({} not reached: {}{elsewhere}){needs}",
            p.made,
            self.pass_runs,
            p.not_reached.len(),
            left.join(", ")
        ))
    }
}

/// What a campaign's runs took, for the account of its systematic pass ([`pass_account`]).
#[derive(Debug, Default)]
struct RunTimes {
    /// Runs made.
    runs: u64,
    /// Their wall time together, milliseconds.
    total_ms: u64,
    /// Each entry of the pass made, with its run's wall time, milliseconds.
    pass: BTreeMap<usize, u64>,
}

impl RunTimes {
    /// A run ended (entry `entry` of the pass, if it is one) after `elapsed`.
    fn ran(&mut self, entry: Option<usize>, elapsed: Duration) {
        let ms = elapsed.as_millis() as u64;
        self.runs += 1;
        self.total_ms += ms;
        if let Some(k) = entry {
            self.pass.insert(k, ms);
        }
    }
}

/// How much of `pass` a campaign with `opts` made, given what its runs took; `None` without
/// a pass. A shard was to make the entries whose runs are its own; the estimate of a complete
/// pass takes each run made as it was, and each not made as the runs made with the same
/// misbehaviour took on average (a silence: a run's average plus the host's wait calibration
/// measured at that kind), else as all runs made took on average.
fn pass_account(
    pass: &[PassEntry],
    kinds: &[AnswerKindSeen],
    times: &RunTimes,
    opts: &FuzzOptions,
    calibration: Option<&Calibration>,
) -> Option<PassAccount> {
    if pass.is_empty() {
        return None;
    }
    let jobs = opts.jobs.max(1) as u64;
    // Pass entry k is run k + 1 (run 0 before it, in a shard only if it is its own).
    let before = opts.shard.map_or(1, |s| u64::from(s.owns(0)));
    let owned = |k: usize| opts.shard.is_none_or(|s| s.owns(k as u64 + 1));
    let kind_of = |answer: u32| kinds.iter().find(|k| k.answer == answer).map_or_else(String::new, |k| k.kind.clone());
    let not_reached: Vec<PassLeft> = pass
        .iter()
        .enumerate()
        .filter(|(k, _)| owned(*k) && !times.pass.contains_key(k))
        .map(|(_, e)| PassLeft { op: e.op, answer: e.answer, kind: kind_of(e.answer) })
        .collect();
    let made = times.pass.len() as u64;
    let mean = (times.runs > 0).then(|| times.total_ms / times.runs);
    let complete_ms = match mean {
        Some(mean) if !not_reached.is_empty() => {
            let mut by_op: BTreeMap<Operator, (u64, u64)> = BTreeMap::new();
            for (k, ms) in &times.pass {
                let e = by_op.entry(pass[*k].op).or_default();
                *e = (e.0 + 1, e.1 + ms);
            }
            let waited = |answer: u32| {
                calibration
                    .and_then(|c| c.by_kind.iter().find(|w| w.answer == answer))
                    .map(|w| w.gave_up_ms.unwrap_or(w.waited_past_ms))
            };
            let cost = |e: &PassEntry| match (by_op.get(&e.op), e.op) {
                (Some((n, total)), _) => total / n,
                (None, Operator::Silence) => mean + waited(e.answer).unwrap_or(0),
                (None, _) => mean,
            };
            let work: u64 = before * mean
                + pass
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| owned(*k))
                    .map(|(k, e)| times.pass.get(&k).copied().unwrap_or_else(|| cost(e)))
                    .sum::<u64>();
            Some(calibration.map_or(0, |c| c.elapsed_ms) + work.div_ceil(jobs))
        }
        _ => None,
    };
    Some(PassAccount { made, not_reached, complete_ms, jobs })
}

/// Shared state of a campaign's workers. Runs are taken into it (corpus, paths, findings) in
/// the order of their index, whatever order they end in, so that what guidance knows when
/// run `i` is scheduled does not depend on thread timing.
struct Shared {
    /// Kept schedules, each with the index of the run that kept it (increasing).
    corpus: Vec<(u64, Schedule)>,
    paths: BTreeSet<String>,
    findings: Vec<Finding>,
    by_sig: BTreeMap<String, usize>,
    fired_at: BTreeMap<String, BTreeMap<String, u64>>,
    /// Answers in the run without misbehaviour (run 0), once taken.
    answers: Option<u32>,
    /// The kinds of answer of run 0, and the systematic pass made of them, once taken.
    answer_kinds: Vec<AnswerKindSeen>,
    pass: Vec<PassEntry>,
    notes: BTreeMap<String, u64>,
    minimize_runs: u64,
    error: Option<String>,
    /// Why the run without misbehaviour judged nothing of the host (see [`unreached`]).
    untested: Option<String>,
    /// Runs 0..taken have been taken in.
    taken: u64,
    /// Runs that ended but wait for an earlier one to be taken in first.
    ended: BTreeMap<u64, (Schedule, RunResult)>,
    /// Suspected hangs by signature and protocol state: being confirmed, or what their
    /// confirmation said.
    suspects: BTreeMap<(String, String), Suspect>,
    /// What the runs took, and which entries of the pass were made.
    timing: RunTimes,
    /// Turns whose run was void every time it was made: passed over when runs are taken in.
    skipped: BTreeSet<u64>,
    /// The host's waits calibration measured, by answer, milliseconds (the pass's costs).
    waits: BTreeMap<u32, u64>,
    /// The host's code coverage, when the runs read it ([`coverage`]).
    coverage: coverage::Coverage,
    /// Schedules of an earlier campaign's corpus (`--corpus`), run right after the pass.
    seeds: Vec<Schedule>,
}

/// A hang a run showed (the host silent for the hang timeout), before it is reported: a
/// second run of its schedule waits as long as the run budget allows ([`confirm`]).
#[derive(Debug, Clone)]
enum Suspect {
    /// Waiting for its confirmation: the finding it would be (with the runs that showed it).
    Pending(Box<Finding>),
    /// Confirmed: a finding.
    Confirmed,
    /// Not confirmed: counted under this note.
    Dismissed(String),
}

/// What [`Shared::take`] found new in a run.
#[derive(Debug, Clone)]
enum New {
    /// A distinct finding (its index).
    Finding(usize),
    /// A suspected hang to confirm (its key in [`Shared::suspects`]).
    Suspect((String, String)),
}

impl Shared {
    /// Learns from the run without misbehaviour: the span of fresh schedules and the pass
    /// (ordered by cost from calibration's waits, unless sharded: every shard must make the
    /// same pass of its own run 0).
    fn learn(&mut self, r: &RunResult, opts: &FuzzOptions) {
        self.answers = Some(r.answers.max(1));
        self.pass = systematic_pass(&r.answer_kinds, &opts.weights, opts.run.pace == Pace::Unpaced);
        if opts.shard.is_none() {
            order_by_cost(&mut self.pass, &self.waits);
        }
        self.answer_kinds.clone_from(&r.answer_kinds);
    }

    /// Takes in run `i`: counts its operators, keeps its schedule when it took a new path,
    /// records its findings; returns the new findings and suspected hangs.
    fn take(&mut self, i: u64, schedule: Schedule, r: RunResult, opts: &FuzzOptions, started: Instant) -> Vec<New> {
        if i == 0 {
            self.learn(&r, opts);
        }
        for f in &r.fired {
            *self.fired_at.entry(f.op.name().to_string()).or_default().entry(f.state.clone()).or_default() += 1;
        }
        let mut fresh_path = false;
        for p in paths_of(&r) {
            fresh_path |= self.paths.insert(p);
        }
        let ms = started.elapsed().as_millis() as u64;
        let first_edges = self.coverage.take(i, r.edges.as_deref(), ms, self.taken + 1, &schedule);
        // A shard that reads the host's coverage keeps what reached new edges for the corpus it
        // writes (unguided, it does not run them).
        let keeps_edges = opts.run.coverage == coverage::CoverageUse::Guide
            || (opts.shard.is_some() && opts.run.coverage != coverage::CoverageUse::Off);
        let for_edges = keeps_edges && !first_edges.is_empty();
        if (fresh_path || for_edges) && !r.fired.is_empty() {
            self.corpus.push((i, schedule.clone()));
            self.coverage.kept(r.edges.as_deref(), for_edges);
        }
        for (sig, _) in notes(&r) {
            *self.notes.entry(sig).or_default() += 1;
        }
        let mut new = Vec::new();
        for v in judge(&r, &opts.ok_exit_codes) {
            if let Some(&k) = self.by_sig.get(&v.signature) {
                self.findings[k].hits += 1;
                continue;
            }
            let finding = Finding {
                verdict: v,
                run: i,
                found_after_ms: started.elapsed().as_millis() as u64,
                hits: 1,
                schedule: schedule.clone(),
                original: schedule.clone(),
                fired: r.fired.clone(),
                end: r.end.clone(),
                timeout_hang_ms: opts.run.timeout_hang.as_millis() as u64,
                confirmed_after_ms: None,
                by_calibration: false,
                stderr: r.stderr.clone(),
                exchanges: r.exchanges.clone(),
                first_edges: first_edges.clone(),
            };
            new.extend(self.add(finding));
        }
        new
    }

    /// A finding not seen before: a hang (the host silent for the hang timeout) becomes a
    /// suspect to confirm, once per signature and protocol state (a suspect already dismissed
    /// there counts under its note); anything else a finding.
    fn add(&mut self, f: Finding) -> Option<New> {
        if let (FindingKind::Hang, HostEnd::Hung(state)) = (f.verdict.kind, &f.end) {
            let key = (f.verdict.signature.clone(), state.clone());
            return match self.suspects.get_mut(&key) {
                Some(Suspect::Pending(p)) => {
                    p.hits += 1;
                    None
                }
                Some(Suspect::Dismissed(note)) => {
                    *self.notes.entry(note.clone()).or_default() += 1;
                    None
                }
                // Confirmed under this key (or its signature elsewhere): a hit of its finding.
                Some(Suspect::Confirmed) => {
                    if let Some(&k) = self.by_sig.get(&f.verdict.signature) {
                        self.findings[k].hits += 1;
                    }
                    None
                }
                None => {
                    self.suspects.insert(key.clone(), Suspect::Pending(Box::new(f)));
                    Some(New::Suspect(key))
                }
            };
        }
        let k = self.findings.len();
        self.by_sig.insert(f.verdict.signature.clone(), k);
        self.findings.push(f);
        Some(New::Finding(k))
    }

    /// What the confirmation of a suspected hang said: a finding (`Some` of its index when it
    /// is a new one), or a note.
    fn settle(&mut self, key: &(String, String), outcome: Confirmation) -> Option<usize> {
        let Some(Suspect::Pending(mut f)) = self.suspects.remove(key) else { return None };
        match outcome {
            Confirmation::Hung(waited) => {
                self.suspects.insert(key.clone(), Suspect::Confirmed);
                f.confirmed_after_ms = Some(waited.as_millis() as u64);
                f.verdict.message += &format!(
                    "; confirmed: a second run waited {:.1} s and it still neither sent nor exited",
                    waited.as_secs_f64()
                );
                // Runs of this signature whose hang did not come back elsewhere (another state)
                // are hits of the confirmed hang, not notes beside it.
                let sig = f.verdict.signature.clone();
                let earlier: Vec<String> =
                    self.notes.keys().filter(|n| Confirmation::is_note_of(n, &sig)).cloned().collect();
                let mut hits = f.hits;
                for n in earlier {
                    hits += self.notes.remove(&n).unwrap_or(0);
                }
                for s in self.suspects.values_mut() {
                    if let Suspect::Dismissed(n) = s
                        && Confirmation::is_note_of(n, &sig)
                    {
                        *s = Suspect::Confirmed;
                    }
                }
                match self.by_sig.get(&sig) {
                    Some(&k) => {
                        self.findings[k].hits += hits;
                        None
                    }
                    None => {
                        let k = self.findings.len();
                        self.by_sig.insert(sig, k);
                        f.hits = hits;
                        self.findings.push(*f);
                        Some(k)
                    }
                }
            }
            // The same hang confirmed at another state already: a hit of its finding.
            _ if self.by_sig.contains_key(&f.verdict.signature) => {
                let k = self.by_sig[&f.verdict.signature];
                self.findings[k].hits += f.hits;
                self.suspects.insert(key.clone(), Suspect::Confirmed);
                None
            }
            other => {
                let note = other.note(&f.verdict.signature, &key.1);
                *self.notes.entry(note.clone()).or_default() += f.hits;
                self.suspects.insert(key.clone(), Suspect::Dismissed(note));
                None
            }
        }
    }

    /// What a hang's confirmation run `r` showed besides the hang (a line it left unended
    /// when it exited, a crash, an exit code): findings like any run's, under the suspect's
    /// run and schedule, whatever the confirmation said of the hang (which its own verdicts of
    /// kind hang are not: the confirmation decides those). The indices of new findings.
    fn take_confirmation_run(
        &mut self,
        suspect: &Finding,
        r: &RunResult,
        opts: &FuzzOptions,
        started: Instant,
    ) -> Vec<usize> {
        let mut new = Vec::new();
        for v in judge(r, &opts.ok_exit_codes).into_iter().filter(|v| v.kind != FindingKind::Hang) {
            if let Some(&k) = self.by_sig.get(&v.signature) {
                self.findings[k].hits += 1;
                continue;
            }
            let k = self.findings.len();
            self.by_sig.insert(v.signature.clone(), k);
            self.findings.push(Finding {
                verdict: v,
                found_after_ms: started.elapsed().as_millis() as u64,
                hits: 1,
                fired: r.fired.clone(),
                end: r.end.clone(),
                confirmed_after_ms: None,
                stderr: r.stderr.clone(),
                exchanges: r.exchanges.clone(),
                ..suspect.clone()
            });
            new.push(k);
        }
        new
    }

    /// Takes in every ended run whose turn has come.
    fn take_ready(&mut self, opts: &FuzzOptions, started: Instant) -> Vec<New> {
        let mut new = Vec::new();
        loop {
            if let Some((s, r)) = self.ended.remove(&self.taken) {
                new.extend(self.take(opts.run_index(self.taken), s, r, opts, started));
            } else if !self.skipped.remove(&self.taken) {
                break;
            }
            self.taken += 1;
        }
        new
    }
}

/// The paths a run took that guidance counts: each misbehaviour at its state with the command
/// that followed, and the host's command sequence.
fn paths_of(r: &RunResult) -> Vec<String> {
    let mut v: Vec<String> = r.reactions.iter().map(|(op, st, next)| format!("{op}@{st}->{next}")).collect();
    v.push(format!("seq:{}", r.commands.join(" ")));
    v
}

/// Guided by the host's coverage: a mutation (one or two of [`mutate`]) of the kept schedule
/// the power schedule picks ([`coverage::Coverage::pick`]), or one time in eight a fresh
/// schedule.
fn next_covered(
    rng: &mut Pcg64Mcg,
    opts: &FuzzOptions,
    corpus: &[Schedule],
    cov: &coverage::Coverage,
    visible: u64,
    kinds: &[AnswerKindSeen],
    answers: u32,
) -> Schedule {
    if corpus.is_empty() || rng.next_u64().is_multiple_of(8) {
        return fresh_from(rng, &opts.weights, opts.max_planned, answers);
    }
    let k = cov.pick(corpus.len(), visible, rng.next_u64());
    let mut s = corpus[k].clone();
    // One change mostly (a second may undo what the first found), two one time in four.
    for _ in 0..1 + u64::from(rng.next_u64().is_multiple_of(4)) {
        mutate(rng, opts, &mut s, kinds, answers);
    }
    s
}

/// One change to a schedule: add a misbehaviour (anywhere, or, twice as often, within three
/// answers after the last one: a longer sequence of what the hand did), drop one, change one's
/// operator or its variant (`arg`), move one by an answer, or move it to the first answer of
/// another kind.
fn mutate(rng: &mut Pcg64Mcg, opts: &FuzzOptions, s: &mut Schedule, kinds: &[AnswerKindSeen], answers: u32) {
    let n = s.planned.len();
    let i = if n == 0 { 0 } else { rng.next_u64() as usize % n };
    match rng.next_u64() % 8 {
        6 | 7 if n > 0 && n < opts.max_planned + 2 => {
            let mut p = planned(rng, &opts.weights, answers);
            p.answer = s.planned[n - 1].answer + 1 + (rng.next_u64() % 3) as u32;
            s.planned.push(p);
        }
        1 if n > 1 => {
            s.planned.remove(i);
        }
        2 if n > 0 => s.planned[i].op = opts.weights.pick(rng),
        3 if n > 0 => s.planned[i].arg = rng.next_u64() as u32,
        4 if n > 0 => {
            let a = s.planned[i].answer;
            s.planned[i].answer = if rng.next_u64().is_multiple_of(2) { a.saturating_sub(1).max(1) } else { a + 1 };
        }
        5 if n > 0 && !kinds.is_empty() => {
            s.planned[i].answer = kinds[rng.next_u64() as usize % kinds.len()].answer;
        }
        _ if n < opts.max_planned + 2 => s.planned.push(planned(rng, &opts.weights, answers)),
        _ => s.planned[i].arg = rng.next_u64() as u32,
    }
    s.planned.sort_by_key(|p| p.answer);
}

/// A fresh schedule or a mutation of a kept one.
fn next_schedule(rng: &mut Pcg64Mcg, opts: &FuzzOptions, corpus: &[Schedule], answers: u32) -> Schedule {
    let fresh = |rng: &mut Pcg64Mcg| planned(rng, &opts.weights, answers);
    if corpus.is_empty() || rng.next_u64().is_multiple_of(2) {
        return fresh_from(rng, &opts.weights, opts.max_planned, answers);
    }
    let mut s = corpus[rng.next_u64() as usize % corpus.len()].clone();
    match rng.next_u64() % 4 {
        0 if s.planned.len() < opts.max_planned + 2 => s.planned.push(fresh(rng)),
        1 if s.planned.len() > 1 => {
            let i = rng.next_u64() as usize % s.planned.len();
            s.planned.remove(i);
        }
        2 if !s.planned.is_empty() => {
            let i = rng.next_u64() as usize % s.planned.len();
            s.planned[i].arg = rng.next_u64() as u32;
        }
        _ if !s.planned.is_empty() => {
            let i = rng.next_u64() as usize % s.planned.len();
            let a = s.planned[i].answer;
            s.planned[i].answer = if rng.next_u64().is_multiple_of(2) { a.saturating_sub(1).max(1) } else { a + 1 };
        }
        _ => s.planned.push(fresh(rng)),
    }
    s.planned.sort_by_key(|p| p.answer);
    s
}

/// A fresh schedule: up to `max_planned` misbehaviours drawn by `weights` over the first
/// `answers` + 2 answers.
fn fresh_from(rng: &mut Pcg64Mcg, weights: &Weights, max_planned: usize, answers: u32) -> Schedule {
    let n = 1 + (rng.next_u64() as usize % max_planned.max(1));
    let mut s = Schedule { planned: (0..n).map(|_| planned(rng, weights, answers)).collect() };
    s.planned.sort_by_key(|p| p.answer);
    s
}

/// One misbehaviour drawn by `weights`, planned for one of the first `answers` + 2 answers.
fn planned(rng: &mut Pcg64Mcg, weights: &Weights, answers: u32) -> Planned {
    let span = answers.max(1) + 2;
    Planned { answer: 1 + (rng.next_u64() % u64::from(span)) as u32, op: weights.pick(rng), arg: rng.next_u64() as u32 }
}

/// One run of the systematic pass: one misbehaviour at the first answer of one kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PassEntry {
    op: Operator,
    answer: u32,
    /// How many times the pass put `op` in before this one: its variant.
    visit: u32,
}

impl PassEntry {
    /// Its schedule. The variant a misbehaviour takes from its `arg` (which delay, which
    /// prompt, which bytes, short or long) is mostly `arg` modulo 2, 3, 4 or 6: an `arg` that
    /// is `visit` modulo 12 takes each op through its variants in turn, the first one at its
    /// first visit, while the rest of `arg` (where to cut, which bit) is drawn.
    fn schedule(self, rng: &mut Pcg64Mcg) -> Schedule {
        let arg = (rng.next_u32() >> 4) * 12 + self.visit % 12;
        Schedule { planned: vec![Planned { answer: self.answer, op: self.op, arg }] }
    }
}

/// The systematic pass of a campaign whose run without misbehaviour gave these kinds of
/// answer: every operator of `weights` (weight above 0) at every kind it applies to, one per
/// run, in rounds: each round gives every operator with a kind left to visit one run (the
/// heavier operators first), at the kind left to it that has had the fewest runs so far (a
/// round spreads over the kinds), so the first round tries every misbehaviour once. With `unpaced`, and `line-rate` among
/// `weights` (at any weight), it opens with a run at the hand's line rate.
fn systematic_pass(kinds: &[AnswerKindSeen], weights: &Weights, unpaced: bool) -> Vec<PassEntry> {
    let mut pass = Vec::new();
    if unpaced && weights.0.iter().any(|(op, _)| *op == Operator::LineRate) {
        pass.push(PassEntry { op: Operator::LineRate, answer: 1, visit: 0 });
    }
    // Each operator with the kinds (their first answers) it has still to visit, the heavier
    // first within a round (by default the slow ones, delays, hang-up and silence, come last).
    let mut by_weight: Vec<&(Operator, u32)> =
        weights.0.iter().filter(|(op, w)| *w > 0 && *op != Operator::LineRate).collect();
    by_weight.sort_by_key(|(_, w)| std::cmp::Reverse(*w));
    let mut left: Vec<(Operator, Vec<u32>)> = by_weight
        .into_iter()
        .map(|(op, _)| (*op, kinds.iter().filter(|k| k.ops.contains(op)).map(|k| k.answer).collect::<Vec<_>>()))
        .filter(|(_, a)| !a.is_empty())
        .collect();
    // Runs given to each kind so far: an operator goes to the kind it has not visited that
    // has had the fewest.
    let mut load: BTreeMap<u32, u32> = BTreeMap::new();
    let mut visit = 0;
    while left.iter().any(|(_, a)| !a.is_empty()) {
        for (op, answers) in &mut left {
            let Some(i) = (0..answers.len()).min_by_key(|&i| (load.get(&answers[i]).copied().unwrap_or(0), i)) else {
                continue;
            };
            let answer = answers.remove(i);
            *load.entry(answer).or_default() += 1;
            pass.push(PassEntry { op: *op, answer, visit });
        }
        visit += 1;
    }
    pass
}

/// The misbehaviours that make a host wait out its own timeout at the answer they hit: they
/// hold back, cut or spoil the prompt it waits for (or the rest of a feedback block).
fn waits_out_a_timeout(op: Operator) -> bool {
    use Operator::*;
    matches!(op, DelayBelow | DelayAbove | NoPrompt | BadPrompt | Truncate | Silence | RtBlockLength)
}

/// The least measured wait (milliseconds) that orders a pass by cost: below it, a run that
/// waits out the host's timeout costs about what any run does.
const COSTLY_WAIT_MS: u64 = 2_000;

/// Orders `pass` by cost, cheapest first, from the host's waits calibration measured (`waits`:
/// by answer, milliseconds, given up or waited past): a misbehaviour that makes the host wait
/// out its timeout ([`waits_out_a_timeout`]) at a kind where it waited [`COSTLY_WAIT_MS`] or
/// more costs that wait (in whole seconds, so that timing noise does not reorder it), any other
/// nothing. The order is kept among runs of one cost (the rounds, the line-rate run first); a
/// host without such waits keeps the pass as it is.
fn order_by_cost(pass: &mut [PassEntry], waits: &BTreeMap<u32, u64>) {
    let cost = |e: &PassEntry| match waits.get(&e.answer) {
        Some(&ms) if ms >= COSTLY_WAIT_MS && waits_out_a_timeout(e.op) => ms.div_ceil(1000),
        _ => 0,
    };
    pass.sort_by_key(cost);
}

/// The generator of run `i` of a campaign with this seed.
fn run_rng(seed: u64, i: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// The random schedule an unguided campaign of this seed gives run `i` (`i` >= 1) past its
/// systematic pass, when run 0 saw `answers` answers (`gcl check-host --serve --misbehave
/// SEED:I` plays it for 8; the pass depends on the host's answers, which it cannot know).
pub fn fresh_schedule(seed: u64, i: u64, weights: &Weights, max_planned: usize, answers: u32) -> Schedule {
    fresh_from(&mut run_rng(seed, i), weights, max_planned, answers)
}

/// Removes misbehaviours one at a time while the run still gives `signature` and reaches every
/// edge of `keep` (until `stop`): the smaller schedule and its run, or `None` when none could
/// go (the run that found it stands).
///
/// `keep` is what "keeps the finding's coverage" means: the edges of the host's code the
/// finding's run reached first in its campaign ([`Finding::first_edges`]; empty without
/// coverage, when the signature alone decides). Those are the code the finding's schedule led
/// the host into; a smaller schedule that gives the same signature by a shallower way (the
/// same signal from another bug) does not reach them, and is not taken. Not every edge of the
/// finding's run is asked for: a run's other edges differ with timing and with misbehaviours
/// that minimization is there to drop.
pub fn minimize(
    opts: &FuzzOptions,
    slots: &Slots,
    schedule: &Schedule,
    signature: &str,
    keep: &[u32],
    runs: &mut u64,
    stop: &AtomicBool,
) -> Result<Option<(Schedule, RunResult)>, RunError> {
    let gives = |s: &Schedule, runs: &mut u64| -> Result<Option<RunResult>, RunError> {
        *runs += 1;
        let r = slots.run(&opts.run, s, stop)?;
        let same = judge(&r, &opts.ok_exit_codes).iter().any(|v| v.signature == signature);
        // The map's edges are in order (`coverage::ShmMap::edges`).
        let reached = r.edges.as_deref().unwrap_or_default();
        let kept = keep.iter().all(|e| reached.binary_search(e).is_ok());
        Ok((same && kept).then_some(r))
    };
    // Keep only what fired: entries that never fired changed nothing.
    let mut best = schedule.clone();
    let mut best_run = None;
    let mut i = 0;
    while i < best.planned.len() {
        let mut trial = best.clone();
        trial.planned.remove(i);
        if let Some(r) = gives(&trial, runs)? {
            best = trial;
            best_run = Some(r);
        } else {
            i += 1;
        }
    }
    Ok(best_run.map(|r| (best, r)))
}

/// What a second run of a suspected hang's schedule said ([`confirm`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Confirmation {
    /// The host still neither sent nor exited, for this long: a hang.
    Hung(Duration),
    /// It acted after this long, in this protocol state: late, not hung (a note).
    Late(Duration, String),
    /// It did not wait past the hang timeout this time (a note).
    NotAgain,
    /// The campaign stopped (a signal), or its time ran out, before it could be confirmed (a
    /// note).
    Stopped,
}

impl Confirmation {
    /// Whether `note` is one a hang signed `signature` was counted under when it did not come
    /// back or the campaign ended first.
    fn is_note_of(note: &str, signature: &str) -> bool {
        ["note: hang not reproduced: ", "note: hang not confirmed (the campaign ended first): "]
            .iter()
            .any(|head| note.strip_prefix(head).is_some_and(|rest| rest.starts_with(&format!("{signature} ("))))
    }

    /// The INFO note a hang not confirmed is counted under.
    fn note(&self, signature: &str, state: &str) -> String {
        match self {
            Confirmation::Late(waited, at) => {
                format!("note: late, not hung: gave up after {:.1} s ({at})", waited.as_secs_f64())
            }
            Confirmation::NotAgain => format!("note: hang not reproduced: {signature} ({state})"),
            Confirmation::Stopped | Confirmation::Hung(_) => {
                format!("note: hang not confirmed (the campaign ended first): {signature} ({state})")
            }
        }
    }
}

/// Confirms a hang a run showed in `state` (the host silent for `hang`, the campaign's hang
/// timeout) before it is reported: runs `schedule` again waiting up to `window` (as long as
/// the run budget allows) for the host to send or exit. A hang is a host that still does
/// neither; one that acts later, after a wait longer than `hang`, is late, not hung: a note
/// ("gave up after 15.0 s").
///
/// The second run comes back too (`None` when it was called off): what else it shows (a
/// violation, a crash, an exit code) is the campaign's like any run's, whatever it says of
/// the hang.
pub fn confirm(
    run: &HostRun,
    slots: &Slots,
    schedule: &Schedule,
    state: &str,
    hang: Duration,
    window: Duration,
    stop: &AtomicBool,
) -> Result<(Confirmation, Option<RunResult>), RunError> {
    let mut patient = run.clone();
    patient.timeout_hang = window.max(hang);
    let r = match slots.run(&patient, schedule, stop) {
        Err(RunError::Cancelled) => return Ok((Confirmation::Stopped, None)),
        // Void every time: nothing confirmed.
        Err(RunError::Shared(_)) => return Ok((Confirmation::NotAgain, None)),
        other => other?,
    };
    let outcome = judge_confirmation(&r, state, hang);
    Ok((outcome, Some(r)))
}

/// What a confirmation run `r` says of a hang suspected in `state` with hang timeout `hang`.
fn judge_confirmation(r: &RunResult, state: &str, hang: Duration) -> Confirmation {
    let late = |same: bool| {
        r.waits.iter().filter(|w| w.acted && w.waited > hang && (!same || w.state == state)).max_by_key(|w| w.waited)
    };
    if let Some(w) = late(true) {
        return Confirmation::Late(w.waited, w.state.clone());
    }
    let still = r.waits.iter().find(|w| !w.acted).filter(|w| w.waited > hang && !r.talking_at_end);
    if let Some(w) = still {
        return Confirmation::Hung(w.waited);
    }
    match late(false) {
        Some(w) => Confirmation::Late(w.waited, w.state.clone()),
        None => Confirmation::NotAgain,
    }
}

/// Runs a campaign; `on_event` hears of each run and each new finding; `stop` ends it early.
///
/// The schedule of run `i` is a function of the seed, `i`, `jobs` and the results of run 0 and
/// runs `0..=i-jobs` (guidance sees those, taken in index order, and no others; a worker waits
/// for them when a slow run holds them up; every run waits for run 0, of which the systematic
/// pass is made, so the pass starts at run 1 whatever `jobs`). With a host that behaves the same given the same
/// bytes, a campaign with the same seed and `jobs` makes the same schedules and findings (first
/// run, hits, minimized schedule) run for run; wall times are not reproducible, nor is which
/// runs a `--duration` leaves room for. With `jobs` 1 every run sees all runs before it.
pub fn fuzz(opts: &FuzzOptions, stop: &AtomicBool, on_event: &(dyn Fn(Event) + Sync)) -> Result<Campaign, RunError> {
    fuzz_seeded(opts, Vec::new(), stop, on_event)
}

/// [`fuzz`], with the schedules of an earlier campaign's corpus ([`corpus`]) run right after the
/// systematic pass (a shard runs those whose run index is its own); the campaign's own kept
/// schedules are in [`Campaign::kept`].
pub fn fuzz_seeded(
    opts: &FuzzOptions,
    seeds: Vec<Schedule>,
    stop: &AtomicBool,
    on_event: &(dyn Fn(Event) + Sync),
) -> Result<Campaign, RunError> {
    let started = Instant::now();
    // With coverage: the host's edge count (an afl-cc binary says it), and a map that fits it.
    let reads = opts.run.coverage != coverage::CoverageUse::Off;
    let host_edges = reads.then(|| coverage::instrumented_edges(&opts.run.command)).flatten();
    let mapped;
    let opts = if reads {
        let mut o = opts.clone();
        o.run.env.retain(|(k, _)| k != coverage::MAP_SIZE_ENV);
        o.run.env.push((coverage::MAP_SIZE_ENV.to_string(), coverage::map_size_for(host_edges).to_string()));
        mapped = o;
        &mapped
    } else {
        opts
    };
    let duration = opts.campaign_duration();
    let calibration = match calibration_stage(opts, duration, stop, on_event, started)? {
        ControlFlow::Continue(c) => c,
        ControlFlow::Break(early) => return Ok(early),
    };
    let calibrated = calibrated_options(opts, calibration.as_ref());
    let opts = calibrated.as_ref().unwrap_or(opts);
    let w = Workers::new(opts, stop, on_event, started, duration);
    // Calibration shared a port: the campaign runs one host at a time (as [`Slots`] after a
    // void run of its own).
    if calibration.as_ref().is_some_and(|c| c.void_runs > 0) {
        w.slots.narrow();
    }
    if let ControlFlow::Break(early) = w.shard_answers()? {
        return Ok(early);
    }
    if let Ok(mut sh) = w.shared.lock() {
        sh.coverage = coverage::Coverage::new(coverage::map_size_in(&opts.run.env), host_edges);
        sh.seeds = seeds;
    }
    if let Some(c) = &calibration {
        if let Ok(mut sh) = w.shared.lock() {
            sh.waits = c.by_kind.iter().map(|k| (k.answer, k.gave_up_ms.unwrap_or(k.waited_past_ms))).collect();
        }
        w.take_calibration_suspects(c);
    }
    w.run_all();
    w.finish(calibration)
}

/// Calibration (when asked): the measured timeouts, told to `on_event`; or the campaign that
/// ends there (stopped, or the host unreached).
fn calibration_stage(
    opts: &FuzzOptions,
    duration: Option<Duration>,
    stop: &AtomicBool,
    on_event: &(dyn Fn(Event) + Sync),
    started: Instant,
) -> Result<ControlFlow<Campaign, Option<Calibration>>, RunError> {
    let calibration = if opts.calibrate {
        match calibrate(&opts.run, duration.map(|d| d / CALIBRATION_SHARE), opts.jobs, stop) {
            Ok(c) => {
                on_event(Event::Calibrated(Box::new(c.clone())));
                Some(c)
            }
            Err(RunError::Cancelled) => {
                return Ok(ControlFlow::Break(Campaign {
                    elapsed_ms: started.elapsed().as_millis() as u64,
                    ..Default::default()
                }));
            }
            Err(e) => return Err(e),
        }
    } else {
        None
    };
    if let Some(why) = calibration.as_ref().and_then(|c| c.untested.clone()) {
        return Ok(ControlFlow::Break(Campaign {
            elapsed_ms: started.elapsed().as_millis() as u64,
            calibration,
            untested: Some(why),
            ..Default::default()
        }));
    }
    Ok(ControlFlow::Continue(calibration))
}

/// The options with calibration's hang timeout, when calibration ran.
fn calibrated_options(opts: &FuzzOptions, calibration: Option<&Calibration>) -> Option<FuzzOptions> {
    calibration.map(|c| {
        let mut o = opts.clone();
        o.run.timeout_hang = Duration::from_millis(c.timeout_hang_ms);
        o
    })
}

/// A campaign's runs under way: its options and what its workers and confirmer share (the
/// state runs are taken into, the run counters, the channel of suspected hangs).
struct Workers<'a> {
    opts: &'a FuzzOptions,
    stop: &'a AtomicBool,
    on_event: &'a (dyn Fn(Event) + Sync),
    started: Instant,
    duration: Option<Duration>,
    jobs: u64,
    next: AtomicU64,
    completed: AtomicU64,
    reached: AtomicU64,
    shared: Mutex<Shared>,
    /// Told when a run is taken in (or run 0's answers learnt).
    turn: Condvar,
    /// The workers have ended.
    runs_over: AtomicBool,
    /// Suspected hangs go to the confirmer, which runs them again beside the campaign's runs.
    to_confirm: Mutex<Option<mpsc::Sender<(String, String)>>>,
    suspects: Mutex<mpsc::Receiver<(String, String)>>,
    /// Every run of the campaign takes one: `jobs` hosts alive at once at most.
    slots: Slots,
}

impl<'a> Workers<'a> {
    /// Nothing run yet.
    fn new(
        opts: &'a FuzzOptions,
        stop: &'a AtomicBool,
        on_event: &'a (dyn Fn(Event) + Sync),
        started: Instant,
        duration: Option<Duration>,
    ) -> Self {
        let (to_confirm, suspects) = mpsc::channel::<(String, String)>();
        Workers {
            opts,
            stop,
            on_event,
            started,
            duration,
            jobs: opts.jobs.max(1) as u64,
            next: AtomicU64::new(0),
            completed: AtomicU64::new(0),
            reached: AtomicU64::new(0),
            shared: Mutex::new(Shared {
                corpus: Vec::new(),
                paths: BTreeSet::new(),
                findings: Vec::new(),
                by_sig: BTreeMap::new(),
                fired_at: BTreeMap::new(),
                answers: None,
                answer_kinds: Vec::new(),
                pass: Vec::new(),
                notes: BTreeMap::new(),
                minimize_runs: 0,
                error: None,
                untested: None,
                taken: 0,
                ended: BTreeMap::new(),
                suspects: BTreeMap::new(),
                timing: RunTimes::default(),
                skipped: BTreeSet::new(),
                waits: BTreeMap::new(),
                coverage: coverage::Coverage::new(coverage::map_size_in(&opts.run.env), None),
                seeds: Vec::new(),
            }),
            turn: Condvar::new(),
            runs_over: AtomicBool::new(false),
            to_confirm: Mutex::new(Some(to_confirm)),
            suspects: Mutex::new(suspects),
            slots: Slots::new(opts.jobs),
        }
    }

    /// Whether the run at turn `t` is past the campaign's end (stopped, runs or time spent).
    fn done(&self, t: u64) -> bool {
        let i = self.opts.run_index(t);
        self.stop.load(Ordering::Relaxed)
            || self.opts.runs.is_some_and(|n| i >= n)
            || self.duration.is_some_and(|d| self.started.elapsed() >= d)
    }

    /// A confirmation waits as long as the run budget allows (a shorter wait would take a
    /// host that acts late for a hung one). Once the runs have ended, a campaign with a
    /// duration confirms for one run budget more at most: suspects still waiting then are
    /// notes.
    fn out_of_time(&self) -> bool {
        self.runs_over.load(Ordering::Relaxed)
            && self.duration.is_some_and(|d| self.started.elapsed() > d + self.opts.run.budget)
    }

    /// A shard without run 0 learns how many answers a run without misbehaviour has (the span
    /// of its schedules) from one run of its own, not counted; or the campaign ends there.
    fn shard_answers(&self) -> Result<ControlFlow<Campaign>, RunError> {
        let opts = self.opts;
        if let Some(s) = opts.shard
            && !s.owns(0)
            && !self.done(0)
        {
            let r = match self.slots.run(&opts.run, &Schedule::default(), self.stop) {
                Err(RunError::Cancelled) => {
                    return Ok(ControlFlow::Break(Campaign {
                        elapsed_ms: self.started.elapsed().as_millis() as u64,
                        ..Default::default()
                    }));
                }
                r => r?,
            };
            if let Some(why) = unreached(&r, &opts.run.command) {
                return Ok(ControlFlow::Break(Campaign {
                    elapsed_ms: self.started.elapsed().as_millis() as u64,
                    untested: Some(why),
                    ..Default::default()
                }));
            }
            if let Ok(mut sh) = self.shared.lock() {
                sh.learn(&r, opts);
            }
        }
        Ok(ControlFlow::Continue(()))
    }

    /// Minimizes the schedule that gave `sig` (`shrink`), keeping the edges `keep` its run
    /// reached first: the smaller schedule and its run.
    fn shrunk(&self, schedule: &Schedule, sig: &str, keep: &[u32], shrink: bool) -> Option<(Schedule, RunResult)> {
        if !(shrink && self.opts.minimize && schedule.planned.len() > 1) {
            return None;
        }
        let mut runs = 0;
        let m = minimize(self.opts, &self.slots, schedule, sig, keep, &mut runs, self.stop);
        if let Ok(mut sh) = self.shared.lock() {
            sh.minimize_runs += runs;
        }
        m.ok().flatten()
    }

    /// Tells `on_event` of finding `k`.
    fn found(&self, k: usize) {
        if let Ok(sh) = self.shared.lock() {
            (self.on_event)(Event::Found(Box::new(sh.findings[k].clone())));
        }
    }

    /// What a run brought that is new: findings minimized (`shrink`) and told, suspected hangs
    /// minimized and sent to the confirmer.
    fn announce(&self, new: Vec<New>, shrink: bool) {
        for n in new {
            match n {
                New::Finding(k) => {
                    let Ok(sh) = self.shared.lock() else { return };
                    let f = &sh.findings[k];
                    let (schedule, sig, keep) =
                        (f.original.clone(), f.verdict.signature.clone(), f.first_edges.clone());
                    drop(sh);
                    if let Some((s, mr)) = self.shrunk(&schedule, &sig, &keep, shrink)
                        && let Ok(mut sh) = self.shared.lock()
                    {
                        sh.findings[k].shrunk(s, mr);
                    }
                    self.found(k);
                }
                New::Suspect(key) => {
                    let Ok(sh) = self.shared.lock() else { return };
                    let Some(Suspect::Pending(f)) = sh.suspects.get(&key) else { continue };
                    let (schedule, keep) = (f.original.clone(), f.first_edges.clone());
                    drop(sh);
                    // Minimized first (with the campaign's hang timeout), then confirmed.
                    if let Some((s, mr)) = self.shrunk(&schedule, &key.0, &keep, shrink)
                        && let Ok(mut sh) = self.shared.lock()
                        && let Some(Suspect::Pending(f)) = sh.suspects.get_mut(&key)
                    {
                        f.shrunk(s, mr);
                    }
                    if let Some(tx) = self.to_confirm.lock().ok().as_ref().and_then(|t| t.as_ref()) {
                        let _ = tx.send(key);
                    }
                }
            }
        }
    }

    /// The confirmer: one suspect at a time until the channel closes; a signature already
    /// confirmed needs no second wait.
    fn confirmer(&self) {
        let opts = self.opts;
        let Ok(suspects) = self.suspects.lock() else { return };
        for key in suspects.iter() {
            let Ok(sh) = self.shared.lock() else { return };
            let Some(Suspect::Pending(f)) = sh.suspects.get(&key) else { continue };
            let pending = (**f).clone();
            let known = sh.by_sig.contains_key(&key.0);
            drop(sh);
            let (outcome, second) = if known {
                (Confirmation::Hung(Duration::ZERO), None)
            } else if self.stop.load(Ordering::Relaxed) || self.out_of_time() {
                (Confirmation::Stopped, None)
            } else {
                let wait = opts.run.budget.max(opts.run.timeout_hang);
                (self.on_event)(Event::Confirming {
                    signature: pending.verdict.signature.clone(),
                    state: key.1.clone(),
                    wait,
                });
                confirm(
                    &opts.run,
                    &self.slots,
                    &pending.schedule,
                    &key.1,
                    opts.run.timeout_hang,
                    opts.run.budget,
                    self.stop,
                )
                .unwrap_or((Confirmation::Stopped, None))
            };
            let mut new: Vec<usize> = Vec::new();
            if let Ok(mut sh) = self.shared.lock() {
                new.extend(sh.settle(&key, outcome));
                if let Some(r) = &second {
                    new.extend(sh.take_confirmation_run(&pending, r, opts, self.started));
                }
            }
            for k in new {
                self.found(k);
            }
        }
    }

    /// The hangs calibration saw, taken in as suspects: confirmed and reported like any other.
    fn take_calibration_suspects(&self, c: &Calibration) {
        let mut new = Vec::new();
        if let Ok(mut sh) = self.shared.lock() {
            for (schedule, r) in &c.suspects {
                for mut v in judge(r, &self.opts.ok_exit_codes).into_iter().filter(|v| v.kind == FindingKind::Hang) {
                    let at = r.fired.first().map(|f| format!("answer {} ({})", f.answer, f.state)).unwrap_or_default();
                    v.message += &format!("; found by calibration, the hand silent at {at}");
                    let f = Finding {
                        verdict: v,
                        run: 0,
                        found_after_ms: self.started.elapsed().as_millis() as u64,
                        hits: 1,
                        schedule: schedule.clone(),
                        original: schedule.clone(),
                        fired: r.fired.clone(),
                        end: r.end.clone(),
                        timeout_hang_ms: c.timeout_hang_ms,
                        confirmed_after_ms: None,
                        by_calibration: true,
                        stderr: r.stderr.clone(),
                        exchanges: r.exchanges.clone(),
                        first_edges: Vec::new(),
                    };
                    new.extend(sh.add(f));
                }
            }
        }
        self.announce(new, false);
    }

    /// One worker: takes turns until the campaign's end, each a schedule, a run, and the run
    /// taken in.
    fn worker(&self) {
        loop {
            let t = self.next.fetch_add(1, Ordering::Relaxed);
            if self.done(t) {
                break;
            }
            let i = self.opts.run_index(t);
            let (schedule, entry) = if i == 0 {
                (Schedule::default(), None)
            } else if self.opts.shard.is_some() {
                let Some(s) = self.unguided_schedule(t, i) else { return };
                s
            } else {
                let Some(s) = self.guided_schedule(t, i) else { return };
                s
            };
            if !self.run_and_take(t, i, schedule, entry) {
                break;
            }
        }
    }

    /// The schedule of run `i` (turn `t`) of a shard, with the entry of the systematic pass it
    /// is (if any): unguided, only run 0's answer count is needed (waited for); `None` when the
    /// campaign ends first.
    fn unguided_schedule(&self, t: u64, i: u64) -> Option<(Schedule, Option<usize>)> {
        let opts = self.opts;
        let mut sh = self.shared.lock().ok()?;
        while sh.answers.is_none() && !self.done(t) {
            sh = self.turn.wait_timeout(sh, Duration::from_millis(50)).ok()?.0;
        }
        let answers = sh.answers?;
        let k = i as usize - 1;
        let pass = sh.pass.get(k).copied();
        // After the pass, the corpus's base (every shard reads the same at its start).
        let seed = k.checked_sub(sh.pass.len()).and_then(|j| sh.seeds.get(j)).cloned();
        drop(sh);
        Some(match (pass, seed) {
            (Some(e), _) => (e.schedule(&mut run_rng(opts.seed, i)), Some(k)),
            (None, Some(s)) => (s, None),
            (None, None) => (fresh_from(&mut run_rng(opts.seed, i), &opts.weights, opts.max_planned, answers), None),
        })
    }

    /// The schedule of run `i` (turn `t`), with the entry of the systematic pass it is (if
    /// any): guidance sees runs 0..visible, whatever else has ended by now (waited for); `None`
    /// when the campaign ends first.
    fn guided_schedule(&self, t: u64, i: u64) -> Option<(Schedule, Option<usize>)> {
        let (opts, jobs) = (self.opts, self.jobs);
        // Every run sees run 0 (whose kinds of answer make the pass), and runs 0..=i-jobs.
        let visible = (t + 1).saturating_sub(jobs).max(1);
        let mut sh = self.shared.lock().ok()?;
        while sh.taken < visible && !self.done(t) {
            sh = self.turn.wait_timeout(sh, Duration::from_millis(50)).ok()?.0;
        }
        if sh.taken < visible {
            return None;
        }
        let kept = if opts.guided { sh.corpus.partition_point(|(j, _)| *j < visible) } else { 0 };
        let corpus: Vec<Schedule> = sh.corpus[..kept].iter().map(|(_, s)| s.clone()).collect();
        let answers = sh.answers.unwrap_or(8);
        // The pass starts at run 1, whatever the jobs (as in a shard).
        let k = i.checked_sub(1).map(|k| k as usize);
        let pass = k.and_then(|k| sh.pass.get(k)).copied();
        if let (Some(e), Some(k)) = (pass, k) {
            return Some((e.schedule(&mut run_rng(opts.seed, i)), Some(k)));
        }
        // Then an earlier campaign's corpus, each once (kept again if it brings anything new).
        if let Some(s) = k.and_then(|k| k.checked_sub(sh.pass.len())).and_then(|j| sh.seeds.get(j)) {
            return Some((s.clone(), None));
        }
        // Guided by coverage once the host showed it has some (run 0 is always seen).
        if opts.guided && opts.run.coverage == coverage::CoverageUse::Guide && sh.coverage.guiding() {
            let s = next_covered(
                &mut run_rng(opts.seed, i),
                opts,
                &corpus,
                &sh.coverage,
                visible,
                &sh.answer_kinds,
                answers,
            );
            return Some((s, None));
        }
        drop(sh);
        Some((next_schedule(&mut run_rng(opts.seed, i), opts, &corpus, answers), None))
    }

    /// Runs `schedule` as run `i` (turn `t`; entry `entry` of the systematic pass, if it is
    /// one), counts it and takes it in (in turn order), announcing what it brought; `false`
    /// when the worker is to end.
    fn run_and_take(&self, t: u64, i: u64, schedule: Schedule, entry: Option<usize>) -> bool {
        let opts = self.opts;
        let r = match self.slots.run(&opts.run, &schedule, self.stop) {
            Ok(r) => r,
            Err(RunError::Cancelled) => return false,
            // Void every time it was made: left out (counted, warned), never a finding.
            Err(RunError::Shared(_)) => {
                if let Ok(mut sh) = self.shared.lock() {
                    sh.skipped.insert(t);
                    let new = sh.take_ready(opts, self.started);
                    drop(sh);
                    self.turn.notify_all();
                    self.announce(new, true);
                }
                return true;
            }
            Err(e) => {
                if let Ok(mut sh) = self.shared.lock() {
                    sh.error.get_or_insert(e.to_string());
                }
                self.stop.store(true, Ordering::Relaxed);
                return false;
            }
        };
        self.completed.fetch_add(1, Ordering::Relaxed);
        if let Ok(mut sh) = self.shared.lock() {
            sh.timing.ran(entry, r.elapsed);
        }
        (self.on_event)(Event::Run { index: i, elapsed: r.elapsed });
        let missed = unreached(&r, &opts.run.command);
        if missed.is_none() {
            self.reached.fetch_add(1, Ordering::Relaxed);
        }
        // A host the hand without misbehaviour did not reach judges nothing in any run:
        // the campaign ends (its run taken in as no finding of the host's).
        if i == 0
            && let Some(why) = missed
        {
            if let Ok(mut sh) = self.shared.lock() {
                sh.untested.get_or_insert(why);
            }
            self.stop.store(true, Ordering::Relaxed);
            self.turn.notify_all();
            return false;
        }
        let new = match self.shared.lock() {
            Ok(mut sh) => {
                sh.ended.insert(t, (schedule, r));
                sh.take_ready(opts, self.started)
            }
            Err(_) => return false,
        };
        self.turn.notify_all();
        self.announce(new, true);
        true
    }

    /// The confirmer and `jobs` workers, until the workers end; then the runs left, and the
    /// confirmer until it has confirmed those it has.
    fn run_all(&self) {
        std::thread::scope(|s| {
            let confirming = s.spawn(|| self.confirmer());
            let workers: Vec<_> = (0..self.jobs).map(|_| s.spawn(|| self.worker())).collect();
            for w in workers {
                let _ = w.join();
            }
            self.runs_over.store(true, Ordering::Relaxed);
            let left = self.take_left();
            self.announce(left, false);
            // No more suspects: the confirmer ends once it has confirmed those it has.
            if let Ok(mut tx) = self.to_confirm.lock() {
                tx.take();
            }
            let _ = confirming.join();
        });
    }

    /// Runs that ended after one before them was called off: taken in (in order), to be
    /// announced unminimized. (None after an unreached run 0: a campaign that could not test
    /// reports no finding.)
    fn take_left(&self) -> Vec<New> {
        match self.shared.lock() {
            Ok(mut sh) if sh.untested.is_some() => {
                sh.ended.clear();
                Vec::new()
            }
            Ok(mut sh) => {
                let ended = std::mem::take(&mut sh.ended);
                let mut new = Vec::new();
                for (t, (s, r)) in ended {
                    new.extend(sh.take(self.opts.run_index(t), s, r, self.opts, self.started));
                }
                new
            }
            Err(_) => Vec::new(),
        }
    }

    /// The campaign's results, once every thread has ended; a run's I/O error is the
    /// campaign's.
    fn finish(self, calibration: Option<Calibration>) -> Result<Campaign, RunError> {
        let mut sh = self.shared.into_inner().map_err(|_| std::io::Error::other("a fuzzing thread panicked"))?;
        // In the order of the runs that found them (a hang is settled after its confirmation,
        // which may end after later runs' findings).
        sh.findings.sort_by_key(|f| f.run);
        if let Some(e) = sh.error {
            return Err(RunError::Io(std::io::Error::other(e)));
        }
        let runs = self.completed.load(Ordering::Relaxed);
        let (mut void_runs, mut void) = self.slots.voided();
        if let Some(c) = &calibration {
            void_runs += c.void_runs;
            void.splice(0..0, c.void.iter().cloned());
            void.truncate(VOID_KEPT);
        }
        let pass = pass_account(&sh.pass, &sh.answer_kinds, &sh.timing, self.opts, calibration.as_ref());
        // No run at all, and nobody stopped it: the budget went before the first run.
        let untested = sh.untested.or_else(|| {
            (runs == 0 && !self.stop.load(Ordering::Relaxed)).then(|| {
                let calibrating = calibration.as_ref().map_or(String::new(), |_| {
                    " (measuring the host's timeouts took it; a longer --duration, or --timeout-hang to skip the \
                     measure)"
                        .to_string()
                });
                format!("the budget ran out before the first run{calibrating}")
            })
        });
        Ok(Campaign {
            runs,
            minimize_runs: sh.minimize_runs,
            elapsed_ms: self.started.elapsed().as_millis() as u64,
            findings: sh.findings,
            fired_at: sh.fired_at,
            corpus: sh.corpus.len(),
            paths: sh.paths.len(),
            calibration,
            notes: sh.notes,
            pass_runs: sh.pass.len() as u64,
            pass,
            answer_kinds: sh.answer_kinds,
            provenance: None,
            reached: self.reached.load(Ordering::Relaxed),
            untested,
            stopped: None,
            void_runs,
            void,
            seeds: sh.seeds.len() as u64,
            kept: sh
                .corpus
                .iter()
                .enumerate()
                .map(|(k, (_, s))| corpus::Entry { schedule: s.clone(), edges: sh.coverage.entry_edges(k).to_vec() })
                .collect(),
            coverage: (self.opts.run.coverage != coverage::CoverageUse::Off)
                .then(|| sh.coverage.account(self.started.elapsed().as_millis() as u64, runs)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kind(kind: &str, answer: u32, ops: &[Operator]) -> AnswerKindSeen {
        AnswerKindSeen { kind: kind.into(), answer, state: format!("state of {answer}"), ops: ops.to_vec() }
    }

    /// After a void run no two hosts are alive at once: a second slot is not given while one is
    /// taken (before, the campaign went on at `--jobs` and a process of another run could
    /// again reach a port unseen, opening and closing it between two looks).
    #[test]
    fn after_a_void_run_one_host_is_alive_at_a_time() {
        let slots = Slots::new(3);
        let go = AtomicBool::new(false);
        let a = slots.take(&go).unwrap();
        let b = slots.take(&go).unwrap();
        assert_ne!(a, b, "two slots at --jobs 3 before any void run");
        slots.give(b);
        slots.found_void("process 1 (sh) of another run opened this run's port /dev/pts/9");
        // A slot is still taken: the next run waits (here it is called off instead).
        let stopped = AtomicBool::new(true);
        assert_eq!(slots.take(&stopped), None, "a second host alive after a void run");
        slots.give(a);
        assert!(slots.take(&go).is_some());
        assert_eq!(slots.voided().0, 1);
    }

    #[test]
    fn the_systematic_pass_puts_every_misbehaviour_at_every_kind_of_answer_each_once_first_round_first() {
        use Operator::*;
        let kinds = vec![
            kind("prompt", 1, &[Truncate, Garbage, NoPrompt, Silence]),
            kind("echo, values, prompt", 2, &[Truncate, Garbage, NoPrompt, WrongEcho, Silence]),
            kind("banner, prompt", 4, &[Truncate, BannerVariant, Silence]),
            kind("feedback block", 9, &[Truncate, RtErr, Silence]),
        ];
        let pass = systematic_pass(&kinds, &Weights::default(), true);
        // An unpaced campaign first meets the timing of a real line.
        assert_eq!((pass[0].op, pass[0].answer), (LineRate, 1));
        let rest = &pass[1..];
        // Every operator at every kind it applies to, once.
        let mut pairs: Vec<(Operator, u32)> = rest.iter().map(|e| (e.op, e.answer)).collect();
        let n = pairs.len();
        pairs.sort();
        pairs.dedup();
        assert_eq!(pairs.len(), n, "no pair twice: {rest:?}");
        let applicable: usize = kinds.iter().map(|k| k.ops.len()).sum();
        assert_eq!(n, applicable);
        // The first round tries each of the seven operators once, the heaviest first (silence,
        // weight 1, last).
        let first: BTreeSet<Operator> = rest[..7].iter().map(|e| e.op).collect();
        assert_eq!(first.len(), 7, "{:?}", &rest[..7]);
        assert_eq!(rest[6].op, Silence, "{:?}", &rest[..7]);
        assert!(rest[..7].iter().all(|e| e.visit == 0));
        // A round spreads over the kinds: the first reaches all four.
        let reached: BTreeSet<u32> = rest[..7].iter().map(|e| e.answer).collect();
        assert_eq!(reached.len(), 4, "{:?}", &rest[..7]);
        // Each visit of an operator takes its next variant: banner-variant's first is the
        // version suffix (arg 0 modulo 4), rt-err's three `ERR n` in turn.
        let mut rng = run_rng(1, 5);
        let banner = rest.iter().find(|e| e.op == BannerVariant).unwrap();
        assert_eq!(banner.schedule(&mut rng).planned[0].arg % 4, 0);
        let errs: Vec<u32> = rest
            .iter()
            .filter(|e| e.op == RtErr || e.op == Truncate)
            .map(|e| e.schedule(&mut rng).planned[0].arg % 4)
            .collect();
        assert_eq!(errs.len(), 5);
        // Only the operators of `--ops`, none at weight 0, and no line-rate run unless listed
        // and the campaign is unpaced.
        let only = systematic_pass(&kinds, &Weights::parse("truncate,garbage=0,line-rate,rt-err=2").unwrap(), true);
        let ops: BTreeSet<Operator> = only.iter().map(|e| e.op).collect();
        assert_eq!(ops, [LineRate, Truncate, RtErr].into_iter().collect());
        assert!(systematic_pass(&kinds, &Weights::default(), false).iter().all(|e| e.op != LineRate));
        assert!(systematic_pass(&[], &Weights::parse("truncate").unwrap(), true).is_empty());
    }

    /// A shard accounts for the runs of the pass that are its own: those it made, and those
    /// of its run indices it did not reach; the pass's claim is made only when all ran.
    #[test]
    fn the_pass_is_accounted_for_by_what_ran_and_a_shard_by_its_own_runs() {
        use Operator::*;
        let kinds = vec![kind("prompt", 1, &[Truncate, Garbage, Silence]), kind("echo, prompt", 2, &[Truncate])];
        let pass = systematic_pass(&kinds, &Weights::default(), false);
        assert_eq!(pass.len(), 4);
        let mut opts = a_campaign();
        let mut times = RunTimes::default();
        times.ran(None, Duration::from_millis(100));
        times.ran(Some(0), Duration::from_millis(100));
        let cal = Calibration {
            by_kind: vec![KindWait { answer: 1, gave_up_ms: Some(5_000), ..Default::default() }],
            elapsed_ms: 1_000,
            ..Default::default()
        };
        let a = pass_account(&pass, &kinds, &times, &opts, Some(&cal)).unwrap();
        assert_eq!((a.made, a.not_reached.len(), a.jobs), (1, 3, 1));
        // Calibration, run 0, the run made, two runs of 100 ms and a silence waited out.
        assert_eq!(a.complete_ms, Some(1_000 + 100 + 100 + 200 + 5_100));
        let c = Campaign { pass_runs: 4, pass: Some(a), answer_kinds: kinds.clone(), ..Default::default() };
        let line = c.pass_line().unwrap();
        assert!(line.starts_with("systematic pass: 1 of 4 runs (3 not reached: "), "{line}");
        assert!(line.ends_with("; a complete pass needs about 7 s at --jobs 1"), "{line}");
        assert!(!line.contains("every misbehaviour"), "{line}");
        // Shard 1/2 owns runs 0, 2, 4: entries 1 and 3.
        opts.shard = Some(crate::fuzz::shard::Shard { index: 1, count: 2 });
        let mut times = RunTimes::default();
        times.ran(Some(1), Duration::from_millis(100));
        times.ran(Some(3), Duration::from_millis(100));
        let a = pass_account(&pass, &kinds, &times, &opts, None).unwrap();
        assert_eq!((a.made, a.not_reached.len(), a.complete_ms), (2, 0, None));
        let c = Campaign { pass_runs: 4, pass: Some(a), answer_kinds: kinds.clone(), ..Default::default() };
        let line = c.pass_line().unwrap();
        assert!(line.contains("2 of 4 runs") && line.contains("2 left to other shards"), "{line}");
        assert!(!line.contains("every misbehaviour"), "{line}");
        // The whole pass made: the claim.
        let whole = PassAccount { made: 4, jobs: 1, ..Default::default() };
        let c = Campaign { pass_runs: 4, pass: Some(whole), answer_kinds: kinds, ..Default::default() };
        assert!(c.pass_line().unwrap().contains("4 of 4 runs, every misbehaviour at every kind of answer"));
    }

    /// A hang that did not come back at one state and was confirmed at another is one finding
    /// with every run that showed it, not a finding and a `hang not reproduced` note of the
    /// same signature beside it; a later miss of a confirmed signature is a hit too.
    #[test]
    fn a_confirmed_hang_takes_in_the_runs_where_it_did_not_come_back() {
        let opts = a_campaign();
        let stop = AtomicBool::new(false);
        let w = Workers::new(&opts, &stop, &|_| {}, Instant::now(), None);
        let mut sh = w.shared.lock().unwrap();
        let hang = |state: &str, run: u64| {
            let r = ended(HostEnd::Hung(state.into()), state);
            let v = judge(&r, &[0]).remove(0);
            Finding {
                verdict: v,
                run,
                found_after_ms: 0,
                hits: 1,
                schedule: Schedule::default(),
                original: Schedule::default(),
                fired: Vec::new(),
                end: r.end.clone(),
                timeout_hang_ms: 0,
                confirmed_after_ms: None,
                by_calibration: false,
                stderr: String::new(),
                exchanges: Vec::new(),
                first_edges: Vec::new(),
            }
        };
        let Some(New::Suspect(a)) = sh.add(hang("awaiting the answer after HI", 1)) else { panic!() };
        assert_eq!(sh.settle(&a, Confirmation::NotAgain), None);
        assert_eq!(sh.notes.len(), 1, "{:?}", sh.notes);
        let Some(New::Suspect(b)) = sh.add(hang("awaiting the answer after FGET", 2)) else { panic!() };
        let k = sh.settle(&b, Confirmation::Hung(Duration::from_secs(9))).expect("a finding");
        assert!(sh.notes.is_empty(), "{:?}", sh.notes);
        assert_eq!(sh.findings[k].hits, 2);
        let Some(New::Suspect(c)) = sh.add(hang("awaiting the answer after C", 3)) else { panic!() };
        assert_eq!(sh.settle(&c, Confirmation::NotAgain), None);
        assert!(sh.notes.is_empty(), "{:?}", sh.notes);
        assert_eq!(sh.findings[k].hits, 3);
        assert!(sh.add(hang("awaiting the answer after HI", 4)).is_none());
        assert_eq!(sh.findings[k].hits, 4);
    }

    /// With calibration's waits, the pass runs the misbehaviours that make the host wait out a
    /// long timeout last, the cheapest of them first; the rest keep their order (the rounds).
    /// A host whose waits are short keeps the pass as it is.
    #[test]
    fn the_pass_runs_what_waits_out_a_long_timeout_last() {
        use Operator::*;
        let kinds = vec![
            kind("prompt", 1, &[Truncate, Garbage, Silence]),
            kind("echo, values, prompt", 2, &[Truncate, Garbage, ErrBits, NoPrompt, Silence]),
        ];
        let pass = systematic_pass(&kinds, &Weights::default(), true);
        let mut ordered = pass.clone();
        let waits: BTreeMap<u32, u64> = [(1, 15_000), (2, 10_400)].into_iter().collect();
        order_by_cost(&mut ordered, &waits);
        assert_eq!(ordered.len(), pass.len());
        let cheap: Vec<PassEntry> = pass.iter().filter(|e| !waits_out_a_timeout(e.op)).copied().collect();
        assert_eq!(ordered[..cheap.len()], cheap[..], "the cheap ones first, in the pass's order");
        assert_eq!(ordered[0].op, LineRate);
        let costly: Vec<(Operator, u32)> = ordered[cheap.len()..].iter().map(|e| (e.op, e.answer)).collect();
        assert_eq!(costly.iter().filter(|(_, a)| *a == 2).count(), 3, "{costly:?}");
        assert!(costly[..3].iter().all(|(_, a)| *a == 2), "11 s before 15 s: {costly:?}");
        let mut short = pass.clone();
        order_by_cost(&mut short, &[(1, 1_000), (2, 1_500)].into_iter().collect());
        assert_eq!(short, pass);
    }

    /// A run that ended so, with nothing else to judge.
    fn ended(end: HostEnd, ended_in: &str) -> RunResult {
        RunResult {
            end,
            stack: None,
            leftovers: Vec::new(),
            gave_up_after: None,
            waits: Vec::new(),
            stderr: String::new(),
            observations: 0,
            wrong_values: Vec::new(),
            exchanges: Vec::new(),
            fired: Vec::new(),
            violations: Vec::new(),
            commands: Vec::new(),
            reactions: Vec::new(),
            ended_in: ended_in.into(),
            answers: 9,
            answer_kinds: Vec::new(),
            elapsed: Duration::ZERO,
            talking_at_end: false,
            port_opened: true,
            edges: None,
        }
    }

    /// A host whose exit code is the last status it read exits with another code for every
    /// status the hand gives: one habit, one finding, the code in the message. Leaving in
    /// RealTime is another place in its code; an accepted code is no finding.
    #[test]
    fn an_unexpected_exit_is_signed_by_its_class_and_mode_not_its_code() {
        let exit = |code: i32, state: &str| {
            let mut r = ended(HostEnd::Exit(code), state);
            r.stderr = format!("host: ERR {code}\n");
            judge(&r, &[0, 1])
        };
        let (a, b) = (exit(255, "at the prompt after FGET"), exit(16, "at the prompt after HI"));
        assert_eq!((a.len(), b.len()), (1, 1));
        assert_eq!(a[0].kind, FindingKind::ExitCode);
        assert_eq!(a[0].signature, "exit-code: not an accepted code, in supervisory mode");
        assert_eq!(b[0].signature, a[0].signature);
        assert!(a[0].message.contains("255") && b[0].message.contains("16"), "{:?} {:?}", a[0], b[0]);
        assert_ne!(exit(3, "RealTime loop after LOOP")[0].signature, a[0].signature);
        assert_eq!(exit(1, "at the prompt after HI"), Vec::new());
    }

    #[test]
    fn a_silent_wrong_value_is_named_by_the_hosts_code_else_by_the_answer_it_came_from() {
        let mut r = RunResult {
            observations: 3,
            wrong_values: vec![WrongValue {
                observed: "P 1 5120".into(),
                place: None,
                answer: "RealTime feedback".into(),
                after: Some("rt-block-length at answer 5".into()),
            }],
            ..ended(HostEnd::Exit(0), "")
        };
        let v = judge(&r, &[0]);
        assert_eq!(v[0].signature, "silent wrong value: P in RealTime feedback");
        assert!(v[0].message.contains("P 1 5120") && v[0].message.contains("after rt-block-length at answer 5"));
        r.wrong_values[0].place = Some("hostlib.py:212".into());
        assert_eq!(judge(&r, &[0])[0].signature, "silent wrong value: P at hostlib.py:212");
    }

    /// An exception nobody caught is one crash named by what was thrown (and where), not
    /// `crash: SIGABRT`; a host that died of another signal keeps that name.
    #[test]
    fn an_uncaught_exception_is_named_by_what_was_thrown_not_by_sigabrt() {
        let mut r = ended(HostEnd::Signal(6), "awaiting the answer after FGET");
        r.stderr =
            "terminate called after throwing an instance of 'std::system_error'\n  what():  read: Input/output error\n"
                .into();
        let v = judge(&r, &[0, 1]);
        assert_eq!(v.len(), 1, "{v:?}");
        assert_eq!(v[0].signature, "crash: uncaught C++ exception std::system_error");
        assert!(v[0].message.starts_with("the host died of SIGABRT: ") && v[0].message.contains("Input/output error"));
        r.stderr.clear();
        assert_eq!(judge(&r, &[0, 1])[0].signature, "crash: SIGABRT");
    }

    /// A host's own text in a signature (here a panic's path of 100 KB) is cut to
    /// [`SIGNATURE_CAP`], the same from run to run, and two such signatures stay apart; the
    /// message is bounded too.
    #[test]
    fn a_signature_of_the_hosts_text_is_bounded_and_stays_apart() {
        let panic = |c: char| {
            let mut r = ended(HostEnd::Exit(101), "at the prompt after HI");
            r.stderr =
                format!("thread 'main' panicked at {}:1:1:\n{}\n", c.to_string().repeat(100_000), "m".repeat(9000));
            judge(&r, &[0])
        };
        let (a, b) = (panic('a'), panic('b'));
        assert!(a[0].signature.len() <= SIGNATURE_CAP && a[0].message.len() <= MESSAGE_CAP + 64, "{:?}", a[0]);
        assert!(a[0].signature.starts_with("crash: panic at aaaa") && a[0].signature.contains("… #"));
        assert_eq!(panic('a')[0].signature, a[0].signature);
        assert_ne!(b[0].signature, a[0].signature);
        // A short one is as it was.
        let mut r = ended(HostEnd::Exit(101), "at the prompt after HI");
        r.stderr = "thread 'main' panicked at src/main.rs:10:5:\nboom\n".into();
        assert_eq!(judge(&r, &[0])[0].signature, "crash: panic at src/main.rs:10");
    }

    /// A default campaign (neither --runs nor --duration) is a time budget that, with its
    /// calibration inside it and a run budget's overrun, ends within 10 minutes whatever the
    /// host's speed (1000 runs of a host that takes 9 s a run took 2 h 30 min); --runs alone
    /// has no time budget.
    /// A one-job campaign's options (default ops, no budget given).
    fn a_campaign() -> FuzzOptions {
        FuzzOptions {
            run: HostRun {
                command: vec!["true".into()],
                transport: Transport::Pty,
                profile: gcl_model::Profile::builtin("seed").unwrap(),
                time: crate::sim::TimeMode::Fast,
                pace: Pace::Unpaced,
                hand_seed: 0,
                timeout_hang: Duration::from_secs(3),
                budget: Duration::from_secs(60),
                link: None,
                coverage: Default::default(),
                env: Vec::new(),
            },
            seed: 0,
            runs: None,
            duration: None,
            ok_exit_codes: vec![0, 1],
            jobs: 1,
            weights: Weights::default(),
            max_planned: 3,
            minimize: true,
            guided: true,
            calibrate: true,
            shard: None,
        }
    }

    #[test]
    fn a_default_campaign_is_a_time_budget_under_ten_minutes() {
        let mut o = a_campaign();
        let d = o.campaign_duration().expect("a time budget");
        assert!(d + o.run.budget * 2 <= Duration::from_secs(600), "{d:?}");
        o.runs = Some(1000);
        assert_eq!(o.campaign_duration(), None);
        o.duration = Some(Duration::from_secs(3600));
        assert_eq!(o.campaign_duration(), Some(Duration::from_secs(3600)));
    }

    #[test]
    fn weights_parse_names_and_pairs() {
        let w = Weights::parse("delay-above,truncate=7").unwrap();
        assert_eq!(w.0, vec![(Operator::DelayAbove, 1), (Operator::Truncate, 7)]);
        assert!(Weights::parse("truncate=0").is_err());
        assert!(Weights::parse("nonsense").unwrap_err().contains("unknown misbehaviour"));
    }
}
