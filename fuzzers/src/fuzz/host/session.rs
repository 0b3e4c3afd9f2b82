//! One run: a fresh simulated hand on a fresh pty (or loopback TCP port), a misbehaviour
//! schedule on its answers, the host command run to its end, and what came of it.
//!
//! The hand is the `gcl sim` engine and transport, in threads of this process; the host is a
//! child process in its own process group (so a hang is ended with the whole group). A hang
//! is the host, with the port open, neither sending nor exiting for the hang timeout after
//! the hand's last answer or its own (re)open (held-back output counts as an answer still
//! coming), or the run outliving its budget. Before a hung host is killed its stack is taken:
//! a Python host (run with `PYTHONFAULTHANDLER=1`) is watched for 300 ms (blocked in one call,
//! or waking) and sent SIGABRT, and its whole dump is read from stderr; a native one is
//! sampled with `eu-stack` or `gdb` when installed. Sanitizers write their reports to a file
//! per run (`ASAN_OPTIONS=log_path=`), read back after the run.
//!
//! Budgets hold whatever the host leaves behind: once it has ended (or been killed), its
//! process group is killed, stderr is read for a short grace only, and when the port or the
//! host's stderr is still held (the transport never heard the port's last close, or stderr
//! never ended) the process holding it (one that left the group with `setsid`) is found
//! through `/proc`, its command line and stack taken, killed and named in the result
//! ([`RunResult::leftovers`]). Then whatever still carries the run's `GCL_HOST_RUN` mark (a
//! daemon holding nothing of the run's) is ended, unnamed, so that no process of a finished run
//! can reach a later run's port: one read of `/proc` per run.
//!
//! What is kept of the traffic is capped ([`KEEP_CAP`] each way, stderr at [`STDERR_CAP`]);
//! the rest is counted and noted, so a host writing without end costs no memory.
//!
//! The host runs with a sanitizer `log_path` of the run's own. The hang timer is fed by the tap and
//! runs only while the host holds the port open (a host starting, ending or between a close and a
//! reopen is not waiting for the hand; its budget still holds). A native host's stack comes from
//! `gdb -batch` (it demangles Rust v0 symbols) or `eu-stack`, behind a shell or launcher, from the
//! newest Python interpreter or waited-for program of its group. A run called off (the campaign or
//! check stopping) sends SIGTERM to the host's group and SIGKILL after a short grace, and every
//! live
//! host group and run folder is registered (`end_all`) so a process that must exit at once leaves
//! none behind. Left-over processes are looked for only when the port or stderr is still held (or,
//! over TCP, a process still uses the write watch's filter, whose listener says so), by what holds
//! them or by the run's `GCL_HOST_RUN` mark.
//!
//! `gcl-observe:` lines on stderr or stdout (`GCL_OBSERVE_FD`) are checked against every value the
//! hand sent. What a crash left unsaid is completed with a second run of the same schedule (gdb's
//! stack at an uncaught exception's SIGABRT; an AddressSanitizer report that names none of the
//! host's frames, with the fast unwinder), and the host's long waits are recorded, which confirm a
//! hang. An unexpected exit code is signed by its class and the hand's mode, the code in the
//! message.

use std::io::Read;
use std::os::fd::AsFd;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};

use gcl_model::{Device, Profile};
use serde::{Deserialize, Serialize};

use super::check::{HostChecker, HostViolation};
use crate::sim::misbehave::{AnswerKindSeen, Fired, LineTap, Misbehave, Operator, Schedule, Shaped};
use crate::sim::{
    Engine, Pace, SimError, SimOptions, StopHandle, TimeMode, host_writes::WriteWatch, pty::Pty, stop_pair,
    tcp::TcpServer,
};

/// How the host reaches the hand.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Transport {
    /// A pseudo-terminal; the port is its slave's path.
    #[default]
    Pty,
    /// A loopback TCP port; the port is `127.0.0.1:N`.
    Tcp,
}

/// Everything one run is made of, but the schedule.
#[derive(Debug, Clone)]
pub struct HostRun {
    /// The host command and its arguments; `{port}` is replaced by the port (also in
    /// `GCL_PORT`), `{url}` by a pyserial URL for it.
    pub command: Vec<String>,
    /// Pty or TCP.
    pub transport: Transport,
    /// The hand's profile.
    pub profile: Arc<Profile>,
    /// Fast or real time.
    pub time: TimeMode,
    /// Line pacing.
    pub pace: Pace,
    /// The seed of the hand's noise.
    pub hand_seed: u64,
    /// Silence after the hand's last answer that makes a hang.
    pub timeout_hang: Duration,
    /// The longest a run may take.
    pub budget: Duration,
    /// Over a pty: a symbolic link to it made for the run, and given to the host as the port
    /// (`gcl fuzz host --link`, one per slot), removed when the run ends.
    pub link: Option<std::path::PathBuf>,
    /// Whether each run of a campaign reads the host's code coverage, and whether it guides
    /// (`--coverage`): [`super::Slots`] gives every run an AFL map ([`super::coverage`]).
    pub coverage: super::coverage::CoverageUse,
    /// More environment for the host (set per run: the coverage map's id).
    pub env: Vec<(String, String)>,
}

/// Which way bytes went.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dir {
    /// Host to hand.
    Host,
    /// Hand to host.
    Hand,
}

/// Bytes that crossed, in order.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Exchange {
    /// Which way.
    pub dir: Dir,
    /// The bytes (as they went: after misbehaviours).
    pub bytes: Vec<u8>,
    /// The misbehaviours that shaped them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub marks: Vec<String>,
}

/// How the host ended.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HostEnd {
    /// It exited with this code.
    Exit(i32),
    /// A signal killed it.
    Signal(i32),
    /// It went silent for the hang timeout; it was killed. The protocol state it hung in.
    Hung(String),
    /// It ran past the run budget; it was killed. The protocol state it was in.
    OverBudget(String),
    /// There was no host process to end: a session `gcl check-host --serve` served to whoever
    /// connected, ended when the hand was stopped. How the client ended is not the hand's to
    /// see, so nothing is judged of it.
    Served,
}

/// What one run gave.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// How the host ended.
    pub end: HostEnd,
    /// Where a hung host was stuck, when its stack could be taken.
    pub stack: Option<super::detect::HangStack>,
    /// Processes the host left behind holding the port or its stderr, or under the write watch
    /// (`--tcp`), killed after it ended.
    pub leftovers: Vec<Leftover>,
    /// How long the host took to send or exit once the hand went silent (a `silence` that
    /// fired), or `None` (no silence, or the host did neither before the run ended).
    pub gave_up_after: Option<Duration>,
    /// The host's long waits ([`Wait`]): each time it neither sent nor exited for more than
    /// [`LONG_WAIT`] with the port open, and, when it was killed (a hang, the budget), the
    /// wait it was in then. What confirms a hang or shows a host that acts late.
    pub waits: Vec<Wait>,
    /// Its stderr with its sanitizer logs after it (and what a second run added), at most
    /// [`STDERR_CAP`] bytes all told.
    pub stderr: String,
    /// Observations the host made (`gcl-observe:` lines, [`OBSERVE`]).
    pub observations: u64,
    /// Observations of values the hand never sent, before the host reported a problem: silent
    /// wrong values (the first few).
    pub wrong_values: Vec<WrongValue>,
    /// Bytes both ways.
    pub exchanges: Vec<Exchange>,
    /// The misbehaviours that fired.
    pub fired: Vec<Fired>,
    /// The host's protocol violations (those that are only notes included:
    /// [`HostViolation::is_note`]).
    pub violations: Vec<HostViolation>,
    /// Command words the host sent.
    pub commands: Vec<String>,
    /// Each fired misbehaviour with the command the host sent next (`-` if none): the paths
    /// guidance looks for.
    pub reactions: Vec<(String, String, String)>,
    /// The protocol state the host ended in ([`super::check::HostChecker::state`]).
    pub ended_in: String,
    /// Answers the hand gave.
    pub answers: u32,
    /// The kinds of answer the hand gave (as made, before any misbehaviour): what the
    /// systematic pass of a campaign covers.
    pub answer_kinds: Vec<AnswerKindSeen>,
    /// Wall time of the run.
    pub elapsed: Duration,
    /// Killed at the run budget while it was still sending (its last bytes came less than
    /// [`TALKING`] before, or it was in the middle of a line longer than any the hand takes,
    /// held up by the hand's line rate): it was acting, not hung, and its pending line is
    /// judged as it stood ([`super::check::HostChecker::cut_off`]).
    pub talking_at_end: bool,
    /// Whether a host opened the port (or connected) at all: a run in which none did, or in
    /// which the host sent nothing, judged nothing of it ([`super::unreached`]).
    pub port_opened: bool,
    /// The edges of the host's code the run reached, when a coverage map was read
    /// ([`super::coverage`]; set by [`super::Slots`]).
    pub edges: Option<Vec<u32>>,
}

/// A host whose last bytes came this recently is still talking.
pub const TALKING: Duration = Duration::from_millis(500);

/// A wait of the host longer than this is kept in [`RunResult::waits`].
pub const LONG_WAIT: Duration = Duration::from_secs(1);

/// Most long waits kept of a run.
const WAITS_CAP: usize = 32;

/// A long wait of the host: it neither sent nor exited, with the port open, after the hand's
/// last answer (or its own last bytes, or its (re)open).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Wait {
    /// How long.
    pub waited: Duration,
    /// The protocol state it waited in (`awaiting the answer after RESET`).
    pub state: String,
    /// It ended the wait by sending or exiting (`false`: it was killed still waiting).
    pub acted: bool,
}

/// A process the host left behind (it left the host's process group and still held the port
/// or the host's stderr after the host ended), as found before it was killed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Leftover {
    /// Its process id.
    pub pid: i32,
    /// Its name (`comm`).
    pub name: String,
    /// Its command line: the program's file name and its arguments, the port written
    /// `{port}` (the same from run to run), at most [`LEFTOVER_COMMAND_CAP`] characters.
    pub command: String,
    /// Where it was, when its stack could be taken (as for a hung host).
    pub stack: Option<super::detect::HangStack>,
}

impl std::fmt::Display for Leftover {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "pid {} ({}): {}", self.pid, self.name, self.command)?;
        if let Some(st) = &self.stack {
            write!(f, ", in {} ({})", st.frames, st.by)?;
        }
        Ok(())
    }
}

/// Longest command line kept of a leftover process.
pub const LEFTOVER_COMMAND_CAP: usize = 120;

/// A process's command line as a leftover's signature shows it: `argv[0]`'s file name and the
/// arguments, `port` replaced by `{port}`, cut at [`LEFTOVER_COMMAND_CAP`] characters.
fn command_line(pid: i32, port: &str) -> String {
    let raw = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
    let mut words = raw.split(|b| *b == 0).filter(|w| !w.is_empty()).map(|w| String::from_utf8_lossy(w).into_owned());
    let Some(first) = words.next() else { return String::new() };
    let program = first.rsplit('/').next().unwrap_or(&first).to_string();
    let line = std::iter::once(program).chain(words).collect::<Vec<_>>().join(" ");
    let line = if port.is_empty() { line } else { line.replace(port, "{port}") };
    match line.char_indices().nth(LEFTOVER_COMMAND_CAP) {
        Some((i, _)) => format!("{}…", &line[..i]),
        None => line,
    }
}

/// Why a run could not be made (not a finding: infrastructure).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The simulated hand could not start.
    #[error("simulated hand: {0}")]
    Sim(#[from] SimError),
    /// The host command could not be started.
    #[error("cannot start host command `{command}`: {source}")]
    Spawn {
        /// The program.
        command: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The command is empty.
    #[error("no host command given (put it after --)")]
    NoCommand,
    /// A thread or pipe could not be made.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The run was called off (the campaign is stopping); the host was killed.
    #[error("the run was called off")]
    Cancelled,
    /// Processes of two runs held the run's port: what it shows is no verdict on the host
    /// (void; the campaign runs it again).
    #[error("void run: {0}")]
    Shared(String),
}

/// Most bytes of the traffic kept each way; the rest is counted, not kept.
pub const KEEP_CAP: usize = 1 << 20;

/// The start of an observation line (on the host's stderr, or on its stdout, which
/// `GCL_OBSERVE_FD=1` names): `gcl-observe: NAME MOTOR VALUE [WHERE]` says what the host
/// believes the hand reported (`gcl-observe: P 1 5000`: motor 1's position is 5000), and,
/// optionally, where in the host that belief was formed (the rest of the line: a function,
/// `file:line`); `gcl-observe: error TEXT` says it saw the hand misbehave, after which its
/// observations are not judged. An observation of a value the hand never sent is a silent
/// wrong value.
pub const OBSERVE: &str = "gcl-observe:";

/// Longest `WHERE` of an observation kept.
const WHERE_CAP: usize = 100;

/// An observation line ([`OBSERVE`]), parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Observation {
    /// The host saw the hand misbehave.
    Error,
    /// A value the host believes the hand reported.
    Value {
        /// `NAME MOTOR VALUE` as written.
        what: String,
        /// The value.
        value: i64,
        /// Where in the host, when it said.
        place: Option<String>,
    },
}

impl Observation {
    /// The observation a line makes, if any (other lines, malformed ones included, make none).
    fn parse(line: &str) -> Option<Observation> {
        let rest = line.trim().strip_prefix(OBSERVE)?.trim_start();
        let mut words = rest.split_whitespace();
        let (name, motor, value) = (words.next()?, words.next()?, words.next()?);
        if name == "error" {
            return Some(Observation::Error);
        }
        let (Ok(_), Ok(v)) = (motor.parse::<u8>(), value.parse::<i64>()) else { return None };
        let place = words.collect::<Vec<_>>().join(" ");
        let place = (!place.is_empty()).then(|| place.chars().take(WHERE_CAP).collect());
        Some(Observation::Value { what: format!("{name} {motor} {value}"), value: v, place })
    }
}

/// A value the host observed that the hand never sent, before the host reported a problem.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct WrongValue {
    /// `NAME MOTOR VALUE` as the host wrote it (`P 1 5000`).
    pub observed: String,
    /// Where in the host, as the observation line said (`WHERE`), if it did.
    pub place: Option<String>,
    /// The protocol state of the hand's last answer before the observation (`RealTime
    /// feedback`, `answer to FGET`): the answer the value came from, as near as the order of
    /// the two streams tells.
    pub answer: String,
    /// The last misbehaviour that fired before it (`rt-block-length at answer 9`), if any.
    pub after: Option<String>,
}

impl WrongValue {
    /// The quantity's name (`P`).
    pub fn name(&self) -> &str {
        self.observed.split_whitespace().next().unwrap_or_default()
    }

    /// Where it happened, for a signature: the host's own `WHERE` when it gave one (its code),
    /// else the answer it came from.
    pub fn site(&self) -> String {
        match &self.place {
            Some(p) => format!("at {p}"),
            None => format!("in {}", self.answer),
        }
    }

    /// Where and after what, for people: `in RealTime feedback, at read_block, after
    /// rt-block-length at answer 5`.
    pub fn context(&self) -> String {
        let mut c = format!("in {}", self.answer);
        if let Some(p) = &self.place {
            c += &format!(", at {p}");
        }
        if let Some(a) = &self.after {
            c += &format!(", after {a}");
        }
        c
    }
}

/// Most distinct values remembered as sent by the hand.
const SENT_CAP: usize = 1 << 16;

/// What the tap of a graded hand keeps, shared between the tap (in the hand's thread) and
/// whoever runs the session: a `gcl fuzz host` or `gcl check-host` run, and the served hand
/// of `gcl check-host --serve` (which uses the misbehaviours, the checker and the traffic).
pub(crate) struct Log {
    pub(crate) misbehave: Misbehave,
    pub(crate) checker: HostChecker,
    exchanges: Vec<Exchange>,
    /// Bytes kept and bytes cut, host then hand.
    kept: [usize; 2],
    cut: [u64; 2],
    /// Every value the hand really sent so far (the model's answers before any
    /// misbehaviour: the numbers of its supervisory answers, the fields of its feedback).
    sent: std::collections::BTreeSet<i64>,
    observations: u64,
    wrong_values: Vec<WrongValue>,
    /// The protocol state of the hand's last answer.
    last_answer: String,
    /// The host said it saw the hand misbehave (`gcl-observe: error`).
    host_reported: bool,
    /// When a `silence` fired, and when the host first sent after it.
    silenced_at: Option<Instant>,
    acted_at: Option<Instant>,
    /// Where the hang clock starts: when the host last sent, or when the hand's last answer
    /// went out or is due to (an answer held back), whichever is later.
    last_activity: Instant,
    /// When the host last sent.
    last_sent: Option<Instant>,
    hang_up: Option<StopHandle>,
    pub(crate) hung_up: bool,
    /// A host has the port open, as the hand's transport last said.
    port_open: bool,
    /// A host opened the port at some time in the session.
    pub(crate) opened: bool,
    /// When the port was last opened or closed (a host's wait counts from then at the
    /// earliest).
    port_changed: Instant,
    /// The host's long waits that it ended by sending, closing the port or exiting.
    waits: Vec<Wait>,
    /// The host was killed (hung, over budget, called off): the port's close is not its act.
    killed: bool,
    reactions: Vec<(String, String, String)>,
    /// Reactions still waiting for the host's next command: (index into reactions, commands seen).
    awaiting: Vec<(usize, usize)>,
}

impl Log {
    /// A fresh log for a hand that follows `schedule`; `hang_up` ends its transport when a
    /// `hang-up` misbehaviour fires.
    pub(crate) fn new(
        schedule: &Schedule,
        device: &Device,
        profile: Arc<gcl_model::Profile>,
        hang_up: StopHandle,
    ) -> Log {
        Log {
            misbehave: Misbehave::new(schedule.clone(), device),
            checker: HostChecker::new(profile),
            exchanges: Vec::new(),
            kept: [0; 2],
            cut: [0; 2],
            sent: std::collections::BTreeSet::new(),
            observations: 0,
            wrong_values: Vec::new(),
            last_answer: "no answer yet".into(),
            host_reported: false,
            silenced_at: None,
            acted_at: None,
            last_activity: Instant::now(),
            last_sent: None,
            hang_up: Some(hang_up),
            hung_up: false,
            port_open: false,
            opened: false,
            port_changed: Instant::now(),
            waits: Vec::new(),
            killed: false,
            reactions: Vec::new(),
            awaiting: Vec::new(),
        }
    }

    /// The traffic both ways, with a note of what the caps cut, taken out of the log.
    pub(crate) fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.note_cuts();
        std::mem::take(&mut self.exchanges)
    }

    fn push(&mut self, dir: Dir, bytes: &[u8], marks: Vec<String>) {
        let k = usize::from(dir == Dir::Hand);
        let room = KEEP_CAP.saturating_sub(self.kept[k]);
        let (keep, cut) = bytes.split_at(bytes.len().min(room));
        self.cut[k] += cut.len() as u64;
        self.kept[k] += keep.len();
        if keep.is_empty() && marks.is_empty() {
            return;
        }
        match self.exchanges.last_mut() {
            Some(e) if e.dir == dir && marks.is_empty() => e.bytes.extend_from_slice(keep),
            _ => self.exchanges.push(Exchange { dir, bytes: keep.to_vec(), marks }),
        }
    }

    /// Takes the values of one answer: of the model's own (before any misbehaviour), or, with
    /// `blocks_only`, of a well-formed feedback block as it went out (a flipped bit or an
    /// extreme value in a block of the right size is what the hand sent as far as any host can
    /// tell).
    fn values_sent(&mut self, device: &Device, bytes: &[u8], blocks_only: bool) {
        if self.sent.len() >= SENT_CAP {
            return;
        }
        if let Some(layout) = device.rt_layout().map(|l| l.feedback()) {
            let n = layout.size();
            for block in [bytes, bytes.get(1..).unwrap_or_default()] {
                if block.len() == n
                    && let Ok((_, values)) = layout.decode(block)
                {
                    self.sent.extend(values);
                    return;
                }
            }
        }
        if blocks_only {
            return;
        }
        let text = String::from_utf8_lossy(bytes);
        let numbers = text.split(|c: char| !(c.is_ascii_digit() || c == '-')).filter_map(|w| w.parse::<i64>().ok());
        self.sent.extend(numbers);
    }

    /// One `gcl-observe:` line of the host.
    fn observe(&mut self, line: &str) {
        match Observation::parse(line) {
            Some(Observation::Error) => self.host_reported = true,
            Some(Observation::Value { what, value, place }) => {
                self.observations += 1;
                if !self.host_reported && !self.sent.contains(&value) && self.wrong_values.len() < 8 {
                    let after = self.misbehave.fired().last().map(|f| format!("{} at answer {}", f.op, f.answer));
                    self.wrong_values.push(WrongValue {
                        observed: what,
                        place,
                        answer: self.last_answer.clone(),
                        after,
                    });
                }
            }
            None => {}
        }
    }

    /// Notes what the caps cut, at the end of the kept traffic.
    fn note_cuts(&mut self) {
        let [host, hand] = self.cut;
        if host + hand == 0 {
            return;
        }
        let mark = format!(
            "not kept: {host} more byte(s) from the host and {hand} from the hand (only the first {} KiB each way are)",
            KEEP_CAP / 1024
        );
        self.exchanges.push(Exchange { dir: Dir::Hand, bytes: Vec::new(), marks: vec![mark] });
    }
}

/// The tap of a graded hand: it shapes the answers by the log's misbehaviours and feeds both
/// directions to its checker.
pub(crate) struct Tap(pub(crate) Arc<Mutex<Log>>);

impl LineTap for Tap {
    fn host_bytes(&mut self, device: &Device, bytes: &[u8]) {
        let Ok(mut log) = self.0.lock() else { return };
        let log = &mut *log;
        let now = Instant::now();
        // Never before an answer still held back: a host that writes on while its answer is
        // held soon blocks in its write (the hand takes no more input while the output it
        // queued behind the held answer is at its cap), and is waiting for the hand, not
        // hung, until that answer is out.
        // A long wait ends here (measured as the hang clock measures it).
        let waited = now.saturating_duration_since(log.last_activity.max(log.port_changed));
        if waited > LONG_WAIT && log.waits.len() < WAITS_CAP {
            let state = log.checker.state();
            log.waits.push(Wait { waited, state, acted: true });
        }
        log.last_activity = log.last_activity.max(now);
        log.last_sent = Some(now);
        if log.silenced_at.is_some() && log.acted_at.is_none() {
            log.acted_at = Some(now);
        }
        log.checker.host_bytes(device, bytes);
        // A reaction is the first command sent after its misbehaviour.
        let commands = log.checker.commands();
        log.awaiting.retain(|&(i, seen)| match commands.get(seen) {
            Some(c) => {
                log.reactions[i].2 = c.clone();
                false
            }
            None => true,
        });
        log.push(Dir::Host, bytes, Vec::new());
    }

    fn hand_bytes(&mut self, device: &Device, bytes: &[u8]) -> Shaped {
        let Ok(mut log) = self.0.lock() else { return Shaped::plain(bytes) };
        let log = &mut *log;
        let state = log.checker.answer_state(device, bytes);
        log.last_answer.clone_from(&state);
        let before = log.misbehave.fired().len();
        let shaped = log.misbehave.shape(device, bytes, &state);
        let new: Vec<Fired> = log.misbehave.fired()[before..].to_vec();
        log.values_sent(device, bytes, false);
        log.values_sent(device, &shaped.bytes, true);
        // Changed in any way (a silence drops every answer after it; a delay holds one).
        let misbehaved =
            new.iter().any(|f| f.op.misbehaves()) || shaped.bytes != bytes || shaped.hold.is_some() || shaped.hang_up;
        log.checker.hand_bytes(device, &shaped.bytes, misbehaved);
        if shaped.restart {
            log.checker.restarted();
        }
        if log.silenced_at.is_none() && new.iter().any(|f| f.op == crate::sim::misbehave::Operator::Silence) {
            log.silenced_at = Some(Instant::now());
        }
        let seen = log.checker.commands().len();
        for f in &new {
            log.reactions.push((f.op.name().to_string(), f.state.clone(), "-".to_string()));
            log.awaiting.push((log.reactions.len() - 1, seen));
        }
        let marks = new
            .iter()
            .map(|f| format!("misbehaviour {} at answer {} ({}): {}", f.op, f.answer, f.state, f.what))
            .collect();
        let mut quiet = Instant::now();
        if let Some((_, d)) = shaped.hold {
            quiet += d;
        }
        log.last_activity = log.last_activity.max(quiet);
        log.push(Dir::Hand, &shaped.bytes, marks);
        if shaped.hang_up {
            log.hung_up = true;
            if let Some(mut h) = log.hang_up.take() {
                h.stop();
            }
        }
        shaped
    }

    fn delivered(&mut self, _device: &Device) {
        if let Ok(mut log) = self.0.lock() {
            log.checker.delivered();
        }
    }

    fn discarded(&mut self, _device: &Device) {
        if let Ok(mut log) = self.0.lock() {
            log.checker.discarded();
        }
    }

    fn connection(&mut self, _device: &Device, open: bool) {
        if let Ok(mut log) = self.0.lock() {
            let now = Instant::now();
            // Closing the port after a long wait ends the wait: the host gave up.
            let waited = now.saturating_duration_since(log.last_activity.max(log.port_changed));
            if !open && log.port_open && !log.killed && waited > LONG_WAIT && log.waits.len() < WAITS_CAP {
                let state = log.checker.state();
                log.waits.push(Wait { waited, state, acted: true });
            }
            log.checker.connection(open);
            log.port_open = open;
            log.opened |= open;
            log.port_changed = now;
        }
    }

    fn host_unread(&mut self, unread: bool) {
        if let Ok(mut log) = self.0.lock() {
            log.checker.host_unread(unread);
        }
    }
}

/// Longest stderr kept, with the sanitizer logs read after it and what a second run adds.
pub const STDERR_CAP: usize = 256 * 1024;

/// How long stderr is read after the host ended: what a leftover holding it writes later is
/// not waited for.
const STDERR_GRACE: Duration = Duration::from_millis(500);

/// The environment variable that marks the host's processes with their run: a process left
/// behind under the write watch (`--tcp`) is found by it.
pub const RUN_MARK: &str = "GCL_HOST_RUN";

/// How long the processes of the host's group may take to be gone from the write watch after
/// the host ended (killed, then reaped by whoever their parent is).
const WATCH_GRACE: Duration = Duration::from_millis(300);

/// How long the port may still count as open after the host ended: the hand's transport hears
/// of the close and makes sure nobody else holds the port first.
const PORT_CLOSE_GRACE: Duration = Duration::from_millis(200);

/// What the stderr reader has read so far.
#[derive(Default)]
struct ErrBuf {
    kept: Vec<u8>,
    eof: bool,
}

/// Runs the host once against a hand that follows `schedule`.
pub fn run_once(spec: &HostRun, schedule: &Schedule) -> Result<RunResult, RunError> {
    run_once_until(spec, schedule, &AtomicBool::new(false))
}

/// A folder of this run's own (sanitizer logs), removed when dropped.
struct RunDir(std::path::PathBuf);

impl RunDir {
    fn new() -> std::io::Result<RunDir> {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let p = std::env::temp_dir().join(format!("gcl-host-run-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir(&p)?;
        live().dirs.insert(p.clone());
        Ok(RunDir(p))
    }

    /// The run's own name, which its host and what that starts carry in their environment as
    /// [`RUN_MARK`] (unique among runs at the same time).
    fn mark(&self) -> String {
        self.0.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
    }

    /// The sanitizer logs written into it (`asan.PID`, ...), each under a heading, in at most
    /// `room` bytes all told (a log cut short, and logs left out, are said).
    ///
    /// The folder is the host's to write into (its `log_path`), so what is there is data from
    /// the host: only entries named as a sanitizer names its logs are read, each as a regular
    /// file through `gcl_host::files` (a symbolic link is not followed, a FIFO is refused
    /// without blocking, and each is named under its heading); at most [`MAX_LOGS`] names are
    /// kept from the listing.
    fn sanitizer_logs(&self, room: usize) -> String {
        let mut out = String::new();
        // The folder itself may have been replaced (by a link elsewhere).
        if !std::fs::symlink_metadata(&self.0).is_ok_and(|m| m.is_dir()) {
            return out;
        }
        let Ok(entries) = std::fs::read_dir(&self.0) else { return out };
        let mut files = Vec::new();
        let mut unlisted = 0usize;
        for e in entries.flatten() {
            let name = e.file_name();
            let is_log = SANITIZERS
                .iter()
                .any(|(_, n)| name.as_encoded_bytes().strip_prefix(n.as_bytes()).is_some_and(|r| r.starts_with(b".")));
            if !is_log {
                continue;
            }
            if files.len() < MAX_LOGS {
                files.push(e.path());
            } else {
                unlisted += 1;
            }
        }
        files.sort();
        let mut left_out = unlisted;
        for f in &files {
            let name = f.file_name().map(|n| gcl_model::escape::escape(n.as_encoded_bytes())).unwrap_or_default();
            let heading = format!("\n--- sanitizer log {name} ---\n");
            let Some(body_room) = room.saturating_sub(out.len()).checked_sub(heading.len() + LOG_CUT_NOTE) else {
                left_out += 1;
                continue;
            };
            match gcl_host::files::read_head_no_follow(f, body_room as u64) {
                Ok((bytes, more)) => {
                    out.push_str(&heading);
                    let whole = String::from_utf8_lossy(&bytes);
                    let text = cut_at_char(&whole, body_room);
                    out.push_str(text);
                    if more || text.len() < whole.len() {
                        out.push_str("\n--- (cut: the rest of this log is not kept) ---\n");
                    }
                }
                Err(e) => {
                    let line = format!("\n--- sanitizer log {name}: not read: {e} ---\n");
                    if out.len() + line.len() + LOG_CUT_NOTE <= room {
                        out.push_str(&line);
                    } else {
                        left_out += 1;
                    }
                }
            }
        }
        if left_out > 0 {
            out.push_str(&format!(
                "\n--- {left_out} more sanitizer log(s) not kept: stderr is kept up to {STDERR_CAP} bytes ---\n"
            ));
        }
        out
    }
}

/// The sanitizers whose logs a run's folder gets: the variable of their options, and the name
/// their logs take there (`asan.PID`).
const SANITIZERS: [(&str, &str); 2] = [("ASAN_OPTIONS", "asan"), ("UBSAN_OPTIONS", "ubsan")];

/// Most sanitizer logs of one run that are read (a host has one or a few processes; a folder
/// of thousands is a host at play).
const MAX_LOGS: usize = 256;

/// Room kept for the note that a log was cut and for the line that logs were left out (each
/// under 100 bytes).
const LOG_CUT_NOTE: usize = 192;

/// The longest beginning of `text` of at most `limit` bytes that ends on a character.
fn cut_at_char(text: &str, limit: usize) -> &str {
    if text.len() <= limit {
        return text;
    }
    let mut end = limit;
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    &text[..end]
}

/// `head` (the host's stderr as kept) followed by `tail` (what is read after it: its sanitizer
/// logs, a second run's report), in at most [`STDERR_CAP`] bytes: each may have half, and what
/// one leaves unused the other may take.
fn join_capped(head: &str, tail: &str) -> String {
    let tail = cut_at_char(tail, STDERR_CAP - head.len().min(STDERR_CAP / 2));
    let head = cut_at_char(head, STDERR_CAP - tail.len());
    let mut s = String::with_capacity(head.len() + tail.len());
    s.push_str(head);
    s.push_str(tail);
    s
}

/// The room [`join_capped`] leaves for a tail after `head`.
fn tail_room(head: &str) -> usize {
    STDERR_CAP - head.len().min(STDERR_CAP / 2)
}

impl Drop for RunDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
        live().dirs.remove(&self.0);
    }
}

/// The hosts' process groups and run folders of this process's runs in flight.
#[derive(Default)]
struct Live {
    groups: std::collections::BTreeSet<i32>,
    dirs: std::collections::BTreeSet<std::path::PathBuf>,
}

fn live() -> std::sync::MutexGuard<'static, Live> {
    static LIVE: Mutex<Live> =
        Mutex::new(Live { groups: std::collections::BTreeSet::new(), dirs: std::collections::BTreeSet::new() });
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Kills the process group of every host running now and removes every run folder: for a
/// process about to exit without waiting for its runs to end (a second signal), so that it
/// leaves no host running and no `gcl-host-run-*` folder behind.
pub fn end_all() {
    let mut l = live();
    for g in std::mem::take(&mut l.groups) {
        let _ = nix::sys::signal::killpg(nix::unistd::Pid::from_raw(g), nix::sys::signal::Signal::SIGKILL);
    }
    for d in std::mem::take(&mut l.dirs) {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Whether `pgid` is the process group of a host running now.
pub fn is_host_group(pgid: i32) -> bool {
    live().groups.contains(&pgid)
}

/// How long a host whose run is called off has to end after SIGTERM before its group is
/// killed: time for its own clean-up, not for more work.
const CANCEL_GRACE: Duration = Duration::from_millis(500);

/// The host's sanitizer options with a log file per process in `dir` (the user's own
/// options kept; a `log_path` of theirs is replaced), then `forced` (which override theirs).
fn sanitizer_options(var: &str, dir: &std::path::Path, name: &str, forced: &[&str]) -> String {
    let mine = format!("log_path={}", dir.join(name).display());
    let theirs = std::env::var(var).unwrap_or_default();
    let mut all: Vec<&str> =
        theirs.split(':').filter(|o| !o.starts_with("log_path=") && !o.trim().is_empty()).collect();
    all.extend(forced);
    all.push(&mine);
    all.join(":")
}

/// How a run is made: as it is, or again to learn more of a crash.
#[derive(Debug, Clone, Copy)]
enum How<'a> {
    /// The host as given.
    Plain,
    /// Under `gdb`, which writes the stack at a SIGABRT into this file.
    UnderGdb(&'a std::path::Path),
    /// With AddressSanitizer's fast unwinder (`fast_unwind_on_fatal=1`).
    FastUnwind,
}

/// [`run_once`], called off ([`RunError::Cancelled`], the host killed) once `cancel` is set.
///
/// A native host that died of SIGABRT after its C++ runtime said an exception went uncaught
/// (`terminate called after throwing...`) has its stack taken as a hung host's is: the same
/// schedule is run once more under `gdb` (when installed), which stops at the signal and
/// prints the stack, and that stack is appended to the run's stderr (under
/// [`detect::ABORT_STACK`](super::detect::ABORT_STACK)), where the crash's signature finds the
/// frame that threw.
///
/// An AddressSanitizer report that names no frame of the host's own code (the default, slow,
/// unwinder crashed on a stack that a `sscanf` or `strcpy` smashed: `nested bug in the same
/// thread`) is completed the same way: a second run with the fast unwinder, which stops where
/// the frames are smashed and goes on to name the function whose variable overflowed (or, in
/// turn, one as the host runs); its report is appended under
/// [`detect::ASAN_SECOND_RUN`](super::detect::ASAN_SECOND_RUN).
pub fn run_once_until(spec: &HostRun, schedule: &Schedule, cancel: &AtomicBool) -> Result<RunResult, RunError> {
    let mut r = run_inner(spec, schedule, cancel, How::Plain)?;
    if super::detect::asan_without_frames(&r.stderr).is_some() {
        // A report that names the host's frame: with the fast unwinder (which stops where the
        // frames are smashed), else as the host runs (the fast one loses the caller of an
        // interceptor). A host that answers the same bytes differently may need another try,
        // and may then crash another way: the report it gives is the run's.
        for attempt in 0..SECOND_RUNS {
            let how = if attempt % 2 == 0 { How::FastUnwind } else { How::Plain };
            let Ok(second) = run_inner(spec, schedule, cancel, how) else { break };
            let report = second.stderr.find("ERROR: AddressSanitizer:").map(|at| &second.stderr[at..]);
            let trusted = |rep: &&str| match how {
                How::FastUnwind => super::detect::asan_fast_report_names_own(rep),
                _ => super::detect::asan_without_frames(rep).is_none(),
            };
            if let Some(report) = report.filter(trusted) {
                r.stderr = join_capped(&r.stderr, &format!("\n{}\n{report}", super::detect::ASAN_SECOND_RUN));
                break;
            }
        }
    }
    // An exception nobody caught ends in SIGABRT, though a wrapper that ran the host may have
    // exited by itself after it: what the C++ runtime wrote says so either way.
    if let Some(first) = super::detect::thrown(&r.stderr) {
        let added = match abort_stack(spec, schedule, cancel, &first) {
            Ok(stack) => format!("\n{}\n{stack}", super::detect::ABORT_STACK),
            Err(why) => format!("\n{}{why}", super::detect::ABORT_NO_STACK),
        };
        r.stderr = join_capped(&r.stderr, &added);
    }
    Ok(r)
}

/// Most second runs made to learn more of one crash (a host that answers the same bytes
/// differently may not crash the same way every time).
const SECOND_RUNS: usize = 4;

/// The stack at SIGABRT of a second run of `schedule` under `gdb` (see [`run_once_until`]),
/// as gdb prints it, or why there is none. A host whose failure depends on timing may throw
/// from another place in a second run: a run that threw what the first did (`first`: type and
/// `what()`) gives the stack; else one that threw the same type does, with the `what()` it
/// threw (the stack is then said to be that run's, [`detect::ABORT_OTHER`](super::detect::ABORT_OTHER)).
fn abort_stack(
    spec: &HostRun,
    schedule: &Schedule,
    cancel: &AtomicBool,
    first: &(String, Option<String>),
) -> Result<String, String> {
    let gdb = Command::new("gdb").arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status();
    if gdb.is_err() {
        return Err("gdb is not installed".into());
    }
    let dir = RunDir::new().map_err(|e| format!("no folder for gdb's log: {e}"))?;
    let log = dir.0.join("gdb.txt");
    let (mut made, mut aborted) = (0, 0);
    let mut other = None;
    for _ in 0..SECOND_RUNS {
        let _ = std::fs::remove_file(&log);
        let Ok(second) = run_inner(spec, schedule, cancel, How::UnderGdb(&log)) else { break };
        made += 1;
        let Some(threw) = super::detect::thrown(&second.stderr) else { continue };
        if threw.0 != first.0 {
            continue;
        }
        aborted += 1;
        // gdb's log is in a folder of this run's own, but read as the host's logs are.
        let Ok((text, _)) = gcl_host::files::read_head_no_follow(&log, STDERR_CAP as u64) else { continue };
        let text = String::from_utf8_lossy(&text);
        if !text.contains("SIGABRT") {
            continue;
        }
        if threw.1 == first.1 {
            return Ok(text.into_owned());
        }
        let said = threw.1.unwrap_or_default();
        other.get_or_insert(format!("{text}\n{}{said}", super::detect::ABORT_OTHER));
    }
    other.ok_or_else(|| {
        if aborted > 0 {
            format!("gdb took no stack in {aborted} second run(s) that threw it again")
        } else {
            format!("{made} second run(s) under gdb did not throw it again")
        }
    })
}

/// The host command run under `gdb`, which writes the stack at a SIGABRT into `log` (the
/// signals hosts use in their work pass through unremarked). A script (`#!`) runs under its
/// interpreter (gdb runs no script itself: it took no stack of a host behind a wrapper), and
/// every process it starts is followed (`detach-on-fork off`): the one that aborts has its
/// stack taken, and the others going first (a wrapper's `ln`) only resume the rest.
fn under_gdb(command: &[String], log: &std::path::Path) -> Vec<String> {
    let script = log.with_extension("gdb");
    let _ = std::fs::write(
        &script,
        "set detach-on-fork off\nset schedule-multiple on\ncatch signal SIGABRT\ncommands\nbt\nkill inferiors 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16\nquit\nend\n",
    );
    let mut v: Vec<String> = ["gdb", "-batch", "-nx", "-q"].map(String::from).to_vec();
    for ex in [
        format!("set logging file {}", log.display()),
        "set logging overwrite on".into(),
        "set logging redirect on".into(),
        "set logging enabled on".into(),
        "handle SIGPIPE SIGALRM SIGCHLD SIGUSR1 SIGUSR2 SIGHUP SIGWINCH SIGINT SIGTERM SIGURG SIGIO nostop noprint pass"
            .into(),
        format!("source {}", script.display()),
        "run".into(),
    ] {
        v.push("-ex".into());
        v.push(ex);
    }
    // A process that ended first (a wrapper's helper) stops the run: the wrapper goes on.
    for _ in 0..8 {
        for ex in ["inferior 1", "continue"] {
            v.push("-ex".into());
            v.push(ex.into());
        }
    }
    for ex in ["bt", "kill"] {
        v.push("-ex".into());
        v.push(ex.into());
    }
    v.push("--args".into());
    v.extend(interpreted(command));
    v
}

/// `command` with a script (a file that starts with `#!`, found as the shell would) preceded by
/// its interpreter and that line's argument, as the kernel runs it.
fn interpreted(command: &[String]) -> Vec<String> {
    let Some(program) = command.first() else { return Vec::new() };
    let path = if program.contains('/') {
        Some(std::path::PathBuf::from(program))
    } else {
        std::env::var_os("PATH").and_then(|p| std::env::split_paths(&p).map(|d| d.join(program)).find(|f| f.is_file()))
    };
    let mut head = [0u8; 256];
    let n = path
        .as_ref()
        .and_then(|p| std::fs::File::open(p).ok())
        .and_then(|mut f| std::io::Read::read(&mut f, &mut head).ok())
        .unwrap_or(0);
    let Some(line) = head[..n].strip_prefix(b"#!") else { return command.to_vec() };
    let line = String::from_utf8_lossy(line.split(|b| *b == b'\n').next().unwrap_or_default()).into_owned();
    let mut words = line.trim().splitn(2, char::is_whitespace);
    let Some(interpreter) = words.next().filter(|w| !w.is_empty()) else { return command.to_vec() };
    let mut v = vec![interpreter.to_string()];
    v.extend(words.next().map(|a| a.trim().to_string()).filter(|a| !a.is_empty()));
    v.extend(command.iter().cloned());
    v
}

/// [`run_once_until`], made as `how` says: start the hand → spawn the host → read its output →
/// watch it to its end → clear what it left behind → stop the hand → the result.
fn run_inner(spec: &HostRun, schedule: &Schedule, cancel: &AtomicBool, how: How) -> Result<RunResult, RunError> {
    let wrapped;
    let spec = match how {
        How::UnderGdb(log) => {
            let mut s = spec.clone();
            s.command = under_gdb(&spec.command, log);
            wrapped = s;
            &wrapped
        }
        How::Plain | How::FastUnwind => spec,
    };
    let asan_forced: &[&str] = if matches!(how, How::FastUnwind) { &["fast_unwind_on_fatal=1"] } else { &[] };
    let program = spec.command.first().ok_or(RunError::NoCommand)?;
    let started = Instant::now();
    let mut hand = start_hand(spec, schedule, started)?;
    let mut child = match spawn_host(spec, program, &mut hand, asan_forced) {
        Ok(c) => c,
        Err(source) => {
            hand.stop.stop();
            let _ = hand.thread.join();
            return Err(RunError::Spawn { command: program.clone(), source });
        }
    };
    let host = HostProc::of(&child);
    let out = read_host(&mut child, &hand.log);
    let (tx, rx) = mpsc::channel();
    let waiter = std::thread::spawn(move || {
        let _ = tx.send(child.wait());
    });
    let watched = match watch_host(spec, cancel, started, &host, &mut hand, &out.errbuf, &rx) {
        Ok(w) => w,
        Err(e) => {
            let _ = nix::sys::signal::killpg(host.pid, nix::sys::signal::Signal::SIGKILL);
            live().groups.remove(&host.pid.as_raw());
            hand.stop.stop();
            let _ = hand.thread.join();
            return Err(RunError::Io(e));
        }
    };
    // Whatever the host left behind in its group goes with it.
    let _ = nix::sys::signal::killpg(host.pid, nix::sys::signal::Signal::SIGKILL);
    let _ = waiter.join();
    live().groups.remove(&host.pid.as_raw());
    let leftovers = clear_leftovers(spec, &hand, &out, &host);
    end_marked(&hand.run_dir.mark(), host.start);
    let stderr = collect_stderr(out, &hand.run_dir);
    hand.stop.stop();
    if let Ok(Err(e)) = hand.thread.join() {
        return Err(RunError::Sim(e));
    }
    if watched.cancelled {
        return Err(RunError::Cancelled);
    }
    if let Some(other) = hand.shared.as_ref().and_then(|w| w.intruder.clone()) {
        return Err(RunError::Shared(other));
    }
    let mut log = hand.log.lock().map_err(|_| std::io::Error::other("the hand's thread panicked"))?;
    Ok(result_of_run(&mut log, watched, leftovers, stderr, started))
}

/// The hand of one run: its transport serving in a thread, the log its tap fills, and the
/// port the host is given.
struct HandSide {
    log: Arc<Mutex<Log>>,
    /// Ends the transport's thread.
    stop: StopHandle,
    /// The transport's thread; the line closes (hangs up) when it ends.
    thread: std::thread::JoinHandle<Result<(), SimError>>,
    /// The port as the host names it (a pty's path, `127.0.0.1:N`).
    port: String,
    /// The port as a pyserial URL.
    url: String,
    /// Over TCP, the host's writes as it makes them (`host_writes`).
    watch: Option<WriteWatch>,
    run_dir: RunDir,
    /// Over a pty: its slave's path (the port may be a link to it).
    pty_path: Option<String>,
    /// Over a pty: who opens it ([`SharedPortWatch`]).
    shared: Option<SharedPortWatch>,
}

/// Watches a run's pty for opens by a process of another run (another `GCL_HOST_RUN`): a
/// host of a campaign that opens a fixed device path, linked to whichever run's port, ends up
/// on another run's line. The processes holding the port are looked at when someone opens it
/// (inotify, read as the run is watched), so the run is known void ([`RunError::Shared`]),
/// never a finding. A process that opens and closes the port between two looks is missed.
struct SharedPortWatch {
    opens: nix::sys::inotify::Inotify,
    path: std::path::PathBuf,
    /// `GCL_HOST_RUN=` this run's mark.
    mark: String,
    /// The first process of another run seen holding the port.
    intruder: Option<String>,
}

impl SharedPortWatch {
    fn new(path: &str, mark: &str) -> Option<SharedPortWatch> {
        use nix::sys::inotify::{AddWatchFlags, InitFlags, Inotify};
        let opens = Inotify::init(InitFlags::IN_NONBLOCK | InitFlags::IN_CLOEXEC).ok()?;
        opens.add_watch(path, AddWatchFlags::IN_OPEN).ok()?;
        Some(SharedPortWatch { opens, path: path.into(), mark: format!("{RUN_MARK}={mark}"), intruder: None })
    }

    /// After opens of the port: whether a process of another run holds it now.
    fn look(&mut self) {
        let mut opened = false;
        while let Ok(events) = self.opens.read_events() {
            if events.is_empty() {
                break;
            }
            opened = true;
        }
        if !opened || self.intruder.is_some() {
            return;
        }
        let me = std::process::id() as i32;
        let Ok(procs) = std::fs::read_dir("/proc") else { return };
        for p in procs.flatten() {
            let Some(pid) = p.file_name().to_str().and_then(|n| n.parse::<i32>().ok()) else { continue };
            if pid == me {
                continue;
            }
            let Ok(fds) = std::fs::read_dir(p.path().join("fd")) else { continue };
            if !fds.flatten().any(|fd| std::fs::read_link(fd.path()).is_ok_and(|t| t == self.path)) {
                continue;
            }
            // Another run's mark: a process of another run. (No mark: not a run's; a child
            // of ours between fork and exec still has our own environment.)
            let env = std::fs::read(p.path().join("environ")).unwrap_or_default();
            let prefix = format!("{RUN_MARK}=");
            let other = env.split(|b| *b == 0).any(|v| v.starts_with(prefix.as_bytes()) && v != self.mark.as_bytes());
            if other {
                let name = std::fs::read_to_string(p.path().join("comm")).unwrap_or_default();
                self.intruder = Some(format!(
                    "process {pid} ({}) of another run opened this run's port {}",
                    name.trim(),
                    self.path.display()
                ));
                return;
            }
        }
    }
}

/// Takes the run and its schedule: starts the hand (engine, log, tap, run folder) on a fresh
/// pty or TCP port; gives it serving.
fn start_hand(spec: &HostRun, schedule: &Schedule, started: Instant) -> Result<HandSide, RunError> {
    let mut opts = SimOptions::new(spec.profile.clone());
    opts.seed = spec.hand_seed;
    opts.time = spec.time;
    opts.pace = spec.pace;
    // `line-rate`: an unpaced campaign's run at the hand's own line rate. It is about time
    // alone: the speed the host set on its port, judged in no unpaced run, is not in this one
    // either (no garbling).
    let line_rate = spec.pace == Pace::Unpaced && schedule.planned.iter().any(|p| p.op == Operator::LineRate);
    if line_rate {
        opts.pace = Pace::Hand;
    }
    let mut engine = Engine::new(&opts)?;
    let (stop, stop_rx) = stop_pair()?;
    let (hang_up, hang_rx) = stop_pair()?;
    let mut fresh = Log::new(schedule, engine.device(), spec.profile.clone(), hang_up);
    fresh.last_activity = started;
    let log = Arc::new(Mutex::new(fresh));
    engine.set_tap(Box::new(Tap(log.clone())));
    let run_dir = RunDir::new()?;

    // The hand: its transport in a thread; the line closes (hangs up) when the thread ends.
    // Over TCP, the host's writes are seen as it makes them (`host_writes`).
    let mut watch = None;
    let mut pty_path = None;
    let (port, url, thread) = match spec.transport {
        Transport::Pty => {
            let mut pty = Pty::open(spec.link.as_deref(), engine.line_baud())?;
            pty.set_speed_check(!line_rate);
            tell_garbling(&mut pty, &log);
            pty_path = Some(pty.path().display().to_string());
            // The link, when there is one, is the port the host is given.
            let port = pty.link().unwrap_or(pty.path()).display().to_string();
            let h = std::thread::spawn(move || pty.serve(&mut engine, &[stop_rx.as_fd(), hang_rx.as_fd()]));
            (port.clone(), port, h)
        }
        Transport::Tcp => {
            let mut server = TcpServer::bind("127.0.0.1:0", false)?;
            watch = WriteWatch::new(server.local_addr());
            if let Some(w) = &watch {
                server.watch_host_writes(w.marks());
            }
            let addr = server.local_addr().to_string();
            let h = std::thread::spawn(move || server.serve(&mut engine, &[stop_rx.as_fd(), hang_rx.as_fd()]));
            (addr.clone(), format!("socket://{addr}"), h)
        }
    };
    let shared = pty_path.as_deref().and_then(|p| SharedPortWatch::new(p, &run_dir.mark()));
    Ok(HandSide { log, stop, thread, port, url, watch, run_dir, pty_path, shared })
}

/// Takes the run and the serving hand: spawns the host command in its own process group,
/// with the port and the sanitizer options in its environment; gives the child.
fn spawn_host(
    spec: &HostRun,
    program: &str,
    hand: &mut HandSide,
    asan_forced: &[&str],
) -> std::io::Result<std::process::Child> {
    let (port, url, run_dir) = (&hand.port, &hand.url, &hand.run_dir);
    let args: Vec<String> = spec.command[1..].iter().map(|a| a.replace("{port}", port).replace("{url}", url)).collect();
    let mut command = Command::new(program);
    command
        .args(&args)
        .env("GCL_PORT", port)
        .env("GCL_PORT_URL", url)
        .env("PYTHONFAULTHANDLER", "1")
        .env("GCL_OBSERVE_FD", "1")
        .env(RUN_MARK, run_dir.mark())
        .env(SANITIZERS[0].0, sanitizer_options(SANITIZERS[0].0, &run_dir.0, SANITIZERS[0].1, asan_forced))
        .env(SANITIZERS[1].0, sanitizer_options(SANITIZERS[1].0, &run_dir.0, SANITIZERS[1].1, &[]))
        .envs(spec.env.iter().map(|(k, v)| (k, v)))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0);
    if let Some(w) = &hand.watch {
        w.prepare(&mut command);
    }
    let spawned = command.spawn();
    if let Some(w) = &mut hand.watch {
        w.spawned();
    }
    spawned
}

/// The host's process: its group (registered among the live ones) and when it started.
struct HostProc {
    pid: nix::unistd::Pid,
    /// When the host started (clock ticks since boot): what it leaves behind started later.
    start: Option<u64>,
}

impl HostProc {
    /// Takes the spawned host: registers its process group; gives its pid and start time.
    fn of(child: &std::process::Child) -> HostProc {
        let pid = nix::unistd::Pid::from_raw(child.id() as i32);
        live().groups.insert(pid.as_raw());
        HostProc { pid, start: start_time(pid.as_raw()) }
    }
}

/// The readers of the host's output: stdout (observations only) and stderr (kept, capped).
struct HostOutput {
    /// Set when stdout ended.
    out_done: Arc<AtomicBool>,
    /// Stderr as read so far.
    errbuf: Arc<Mutex<ErrBuf>>,
    err_reader: std::thread::JoinHandle<()>,
    /// The stderr pipe's inode, which names it while it is open.
    err_inode: Option<u64>,
}

/// Takes the spawned host: reads its stdout for observations and its stderr (observations
/// too, and kept up to [`STDERR_CAP`]) in threads; gives the readers.
fn read_host(child: &mut std::process::Child, log: &Arc<Mutex<Log>>) -> HostOutput {
    let err_pipe = child.stderr.take();
    // Stdout carries observations only (GCL_OBSERVE_FD=1); the rest of it is dropped.
    let out_done = Arc::new(AtomicBool::new(child.stdout.is_none()));
    if let Some(out) = child.stdout.take() {
        let log = log.clone();
        let done = out_done.clone();
        std::thread::spawn(move || {
            let mut lines = LineSplitter::default();
            let mut r = out;
            let mut buf = [0u8; 8192];
            while let Ok(n) = r.read(&mut buf) {
                if n == 0 {
                    break;
                }
                lines.feed(&buf[..n], |l| {
                    if let Ok(mut log) = log.lock() {
                        log.observe(l);
                    }
                });
            }
            done.store(true, Ordering::Relaxed);
        });
    }
    let err_inode = err_pipe
        .as_ref()
        .and_then(|p| std::fs::metadata(format!("/proc/self/fd/{}", std::os::fd::AsRawFd::as_raw_fd(p))).ok())
        .map(|m| std::os::unix::fs::MetadataExt::ino(&m));
    let errbuf = Arc::new(Mutex::new(ErrBuf::default()));
    let err_reader = {
        let errbuf = errbuf.clone();
        let log = log.clone();
        std::thread::spawn(move || {
            let mut lines = LineSplitter::default();
            let Some(mut p) = err_pipe else {
                if let Ok(mut b) = errbuf.lock() {
                    b.eof = true;
                }
                return;
            };
            let mut buf = [0u8; 8192];
            loop {
                let n = match p.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => n,
                };
                lines.feed(&buf[..n], |l| {
                    if let Ok(mut log) = log.lock() {
                        log.observe(l);
                    }
                });
                let Ok(mut b) = errbuf.lock() else { return };
                let room = STDERR_CAP.saturating_sub(b.kept.len());
                b.kept.extend_from_slice(&buf[..n.min(room)]);
            }
            if let Ok(mut b) = errbuf.lock() {
                b.eof = true;
            }
        })
    };
    HostOutput { out_done, errbuf, err_reader, err_inode }
}

/// The pty's speed-mismatch notice goes to the checker, so the violations the garbled bytes
/// make say why (as `gcl sim` says it on stderr).
pub(crate) fn tell_garbling(pty: &mut Pty, log: &Arc<Mutex<Log>>) {
    let log = log.clone();
    pty.on_speed_mismatch(move |why| {
        if let Ok(mut l) = log.lock() {
            l.checker.garbled_because(why);
        }
    });
}

/// How the host's run ended, as the watch saw it.
struct Watched {
    end: HostEnd,
    /// The run was called off.
    cancelled: bool,
    /// A hung host's stack.
    stack: Option<super::detect::HangStack>,
    /// When the host ended by itself.
    ended_at: Option<Instant>,
    /// Since when the host was quiet with the port open, at the end.
    quiet_since: Instant,
    /// The host was still sending when the budget ended it.
    talking_at_end: bool,
}

/// Takes the running host (`rx` hears its exit): watches it every 5 ms until it exits, hangs,
/// outlives the budget or is called off, killing it then (a hung one's stack taken first);
/// gives how it ended, or the error of waiting for it.
fn watch_host(
    spec: &HostRun,
    cancel: &AtomicBool,
    started: Instant,
    host: &HostProc,
    hand: &mut HandSide,
    errbuf: &Mutex<ErrBuf>,
    rx: &mpsc::Receiver<std::io::Result<std::process::ExitStatus>>,
) -> std::io::Result<Watched> {
    let log = &hand.log.clone();
    let state = |log: &Arc<Mutex<Log>>| log.lock().map(|l| l.checker.state()).unwrap_or_default();
    let mut w = Watched {
        end: HostEnd::Exit(-1),
        cancelled: false,
        stack: None,
        ended_at: None,
        quiet_since: started,
        talking_at_end: false,
    };
    let mut closed_until = started;
    w.end = loop {
        match rx.recv_timeout(Duration::from_millis(5)) {
            Ok(Ok(status)) => {
                w.ended_at = Some(Instant::now());
                break match (status.code(), status.signal()) {
                    (Some(c), _) => HostEnd::Exit(c),
                    (None, Some(s)) => HostEnd::Signal(s),
                    (None, None) => HostEnd::Exit(-1),
                };
            }
            Ok(Err(e)) => return Err(e),
            Err(mpsc::RecvTimeoutError::Disconnected) => break HostEnd::Exit(-1),
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        if let Some(w) = &mut hand.shared {
            w.look();
        }
        let now = Instant::now();
        let (last_activity, holds_port, last_sent, flooding) = log
            .lock()
            .map(|l| (l.last_activity, l.port_open, l.last_sent, l.checker.overlong_pending()))
            .unwrap_or((started, true, None, false));
        // A host without the port open is not waiting for the hand: it is starting, between a
        // close and a reopen, or ending. Its quiet counts from when it (re)opened; only the
        // run budget ends it meanwhile. (On a loaded machine an interpreter can take longer
        // than the hang timeout to start or to finish: killed then, it showed no frame of the
        // host's code, a "hang" with no stack that no host can avoid.)
        if !holds_port {
            closed_until = now;
        }
        w.quiet_since = last_activity.max(closed_until);
        w.cancelled = cancel.load(Ordering::Relaxed);
        let verdict = if w.cancelled {
            Some(HostEnd::Exit(-1))
        } else if now.duration_since(started) > spec.budget {
            w.talking_at_end = flooding || last_sent.is_some_and(|t| now.saturating_duration_since(t) < TALKING);
            Some(HostEnd::OverBudget(state(log)))
        } else if now > w.quiet_since && now.duration_since(w.quiet_since) > spec.timeout_hang {
            Some(HostEnd::Hung(state(log)))
        } else {
            None
        };
        if let Some(v) = verdict {
            if let Ok(mut l) = log.lock() {
                l.killed = true;
                if !w.cancelled {
                    let state = l.checker.state();
                    l.waits.push(Wait { waited: now.saturating_duration_since(w.quiet_since), state, acted: false });
                }
            }
            w.stack = kill_host(host, w.cancelled, errbuf, rx);
            break v;
        }
    };
    Ok(w)
}

/// Takes a host to end: a called-off one gets SIGTERM and a short grace, a hung one has its
/// stack taken; then its group is killed and reaped. Gives the stack, if taken.
fn kill_host(
    host: &HostProc,
    cancelled: bool,
    errbuf: &Mutex<ErrBuf>,
    rx: &mpsc::Receiver<std::io::Result<std::process::ExitStatus>>,
) -> Option<super::detect::HangStack> {
    let pid = host.pid;
    let mut stack = None;
    let mut reaped = false;
    if cancelled {
        // Called off (the campaign or check is stopping): SIGTERM to the host's group,
        // a short grace to end by itself, then the whole group is killed.
        let _ = nix::sys::signal::killpg(pid, nix::sys::signal::Signal::SIGTERM);
        reaped = rx.recv_timeout(CANCEL_GRACE).is_ok();
    } else {
        stack = take_stack(pid.as_raw(), errbuf, Some(rx), &mut reaped);
    }
    let _ = nix::sys::signal::killpg(pid, nix::sys::signal::Signal::SIGKILL);
    if !reaped {
        let _ = rx.recv_timeout(Duration::from_secs(5));
    }
    stack
}

/// Takes the ended host: reads stderr for a short grace; then finds whatever still holds the
/// port or stderr, or is under the write watch (it left the group), takes its command line
/// and stack, and kills it. Gives those leftovers.
fn clear_leftovers(spec: &HostRun, hand: &HandSide, out: &HostOutput, host: &HostProc) -> Vec<Leftover> {
    // A pty's number is ours only while its master is open, i.e. while the hand's thread
    // runs (a hang-up ends it early): after that, the path may name another program's
    // terminal, which must never be touched. So the port is looked for only while the thread
    // runs, and what a search found counts only if it still ran after the search.
    let pty_path = hand.pty_path.as_ref().filter(|_| spec.transport == Transport::Pty).map(std::path::PathBuf::from);
    let pty_alive = || !hand.thread.is_finished();
    let mut leftovers = Vec::new();
    // The pipe's inode names it only while it is open (a closed pipe's number is reused).
    let err_open = !wait_eof(&out.errbuf, STDERR_GRACE);
    let err_inode = out.err_inode.filter(|_| err_open);
    // Over TCP, a process still under the write watch (the host's daemon, holding nothing of
    // the run's) is found by the run's mark in its environment.
    let watched_left = hand.watch.as_ref().is_some_and(|w| w.outlived(WATCH_GRACE));
    let mark = watched_left.then(|| format!("{RUN_MARK}={}", hand.run_dir.mark()));
    let search = |err_inode: Option<u64>| {
        let path = pty_path.as_deref().filter(|_| pty_alive());
        let found = holders(path, err_inode, mark.as_deref(), host.start);
        if path.is_some() && !pty_alive() { holders(None, err_inode, mark.as_deref(), host.start) } else { found }
    };
    // The search reads all of /proc: only when something still holds stderr or the port (the
    // hand's transport says when the last holder of its port closed it, soon after the host
    // ended).
    let port_held = pty_path.is_some() && {
        let until = Instant::now() + PORT_CLOSE_GRACE;
        while hand.log.lock().is_ok_and(|l| l.port_open) && Instant::now() < until && pty_alive() {
            std::thread::sleep(Duration::from_millis(2));
        }
        hand.log.lock().map_or(true, |l| l.port_open)
    };
    let found = if err_open || port_held || watched_left { search(err_inode) } else { Vec::new() };
    if !found.is_empty() {
        for (p, name) in found {
            // What it is and where it is, before it goes: the signature names it.
            let command = command_line(p, &hand.port);
            let stack = take_stack(p, &out.errbuf, None, &mut false);
            let _ = nix::sys::signal::killpg(nix::unistd::Pid::from_raw(p), nix::sys::signal::Signal::SIGKILL);
            let _ = nix::sys::signal::kill(nix::unistd::Pid::from_raw(p), nix::sys::signal::Signal::SIGKILL);
            leftovers.push(Leftover { pid: p, name, command, stack });
        }
        wait_eof(&out.errbuf, STDERR_GRACE);
    }
    leftovers
}

/// Ends every process still carrying the run's mark (`mark`) that started with its host or
/// after (`host_start`): what a host left behind holding nothing of the run's (a daemon that
/// closed the port and stderr), which would outlive the run and could open a later run's port
/// (the same `--link`, a fixed device path) between two looks of its watcher. Such a process
/// is no finding (it holds nothing of the run's); it is ended, not named. One read of `/proc`
/// per run, so that no process of a finished run is alive when its slot is given again.
fn end_marked(mark: &str, host_start: Option<u64>) {
    for (p, _) in holders(None, None, Some(&format!("{RUN_MARK}={mark}")), host_start) {
        let _ = nix::sys::signal::killpg(nix::unistd::Pid::from_raw(p), nix::sys::signal::Signal::SIGKILL);
        let _ = nix::sys::signal::kill(nix::unistd::Pid::from_raw(p), nix::sys::signal::Signal::SIGKILL);
    }
}

/// Takes the readers once the host and its leftovers are gone: waits a short grace for the
/// last observations; gives stderr as kept, with the run's sanitizer logs after it.
fn collect_stderr(out: HostOutput, run_dir: &RunDir) -> String {
    if wait_eof(&out.errbuf, Duration::ZERO) {
        let _ = out.err_reader.join();
    }
    // The last observations on stdout, for the same grace.
    let grace = Instant::now() + STDERR_GRACE;
    while !out.out_done.load(Ordering::Relaxed) && Instant::now() < grace {
        std::thread::sleep(Duration::from_millis(5));
    }
    let stderr = out.errbuf.lock().map(|b| String::from_utf8_lossy(&b.kept).into_owned()).unwrap_or_default();
    let logs = run_dir.sanitizer_logs(tail_room(&stderr));
    join_capped(&stderr, &logs)
}

/// Takes the hand's log after the run and how the host ended: closes the checker's judgement
/// (how the host left, a long last wait, when it gave up); gives the run's result.
fn result_of_run(
    log: &mut Log,
    watched: Watched,
    leftovers: Vec<Leftover>,
    stderr: String,
    started: Instant,
) -> RunResult {
    let Watched { end, stack, ended_at, quiet_since, talking_at_end, .. } = watched;
    let ended_in = log.checker.state();
    // After a hang-up the host cannot leave cleanly; a host killed for hanging did not leave,
    // nor did one that crashed (its crash is the finding, not the loop or line it was in).
    if !log.hung_up {
        let crashed = matches!(end, HostEnd::Signal(_)) || super::detect::crash_report(&stderr).is_some();
        log.checker.finish(!crashed && !matches!(end, HostEnd::Hung(_) | HostEnd::OverBudget(_)));
        // A line already longer than any the hand takes is broken however the host was
        // stopped: killed at the budget or as hung, that violation is the run's, whatever a
        // second run says of the hang.
        match &end {
            HostEnd::OverBudget(_) => log.checker.cut_off("the run budget stopped the host"),
            HostEnd::Hung(_) => log.checker.cut_off("the host was killed as hung"),
            HostEnd::Exit(_) | HostEnd::Signal(_) | HostEnd::Served => {}
        }
    }
    let violations = log.checker.violations().to_vec();
    // A host that exited (or died) with the port still open after a long wait ended it so.
    if let Some(at) = ended_at.filter(|_| log.port_open && !log.killed) {
        let waited = at.saturating_duration_since(quiet_since);
        if waited > LONG_WAIT && log.waits.len() < WAITS_CAP {
            log.waits.push(Wait { waited, state: ended_in.clone(), acted: true });
        }
    }
    let gave_up_after = log.silenced_at.and_then(|s| {
        let acted = log.acted_at.or(ended_at.filter(|_| matches!(end, HostEnd::Exit(_) | HostEnd::Signal(_))))?;
        Some(acted.saturating_duration_since(s))
    });
    RunResult {
        end,
        stack,
        leftovers,
        gave_up_after,
        waits: log.waits.clone(),
        stderr,
        observations: log.observations,
        wrong_values: log.wrong_values.clone(),
        exchanges: log.take_exchanges(),
        fired: log.misbehave.fired().to_vec(),
        violations,
        commands: log.checker.commands().to_vec(),
        reactions: log.reactions.clone(),
        ended_in,
        answers: log.misbehave.answers(),
        answer_kinds: log.misbehave.kinds().to_vec(),
        elapsed: started.elapsed(),
        talking_at_end,
        port_opened: log.opened,
        edges: None,
    }
}

/// Waits up to `limit` for the stderr reader to reach the end; whether it did.
fn wait_eof(errbuf: &Mutex<ErrBuf>, limit: Duration) -> bool {
    let end = Instant::now() + limit;
    loop {
        if errbuf.lock().map_or(true, |b| b.eof) {
            return true;
        }
        if Instant::now() >= end {
            return false;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The stack of a hung host (`ended` hears of its end) or of a process it left behind
/// (`None`), taken before it is killed: a Python interpreter dumps its frames
/// (`faulthandler`, on SIGABRT) on stderr (a leftover's only when it still holds the host's
/// stderr); a native program is sampled.
fn take_stack(
    pid: i32,
    errbuf: &Mutex<ErrBuf>,
    ended: Option<&mpsc::Receiver<std::io::Result<std::process::ExitStatus>>>,
    reaped: &mut bool,
) -> Option<super::detect::HangStack> {
    let (target, python) = stack_target(pid);
    if python {
        // Whether it is blocked in one call (it does not wake while watched) or cycles (a
        // loop that polls a port with a timeout): only the first is signed by the call.
        let blocked = blocked_in_one_call(target);
        let from = errbuf.lock().ok()?.kept.len();
        nix::sys::signal::kill(nix::unistd::Pid::from_raw(target), nix::sys::signal::Signal::SIGABRT).ok()?;
        // It dumps, then dies of the signal; the dump is read once it is whole: the host's
        // stderr at its end, else (a wrapper or a process it left behind still holds it) the
        // dump's frames followed by the blank line that ends them. On a loaded machine either
        // can take a while (a dump cut short, read too early, left the hang with no stack).
        if let Some(ended) = ended.filter(|_| target == pid) {
            *reaped = ended.recv_timeout(DUMP_GRACE).is_ok();
        } else {
            let gone = Instant::now() + DUMP_GRACE;
            while running(target) && Instant::now() < gone {
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        let whole = Instant::now() + DUMP_GRACE;
        loop {
            let done = errbuf.lock().map_or(true, |b| {
                b.eof || b.kept.get(from..).is_some_and(|d| dump_is_whole(&String::from_utf8_lossy(d)))
            });
            if done || Instant::now() >= whole {
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        let mut b = errbuf.lock().ok()?;
        let dump = String::from_utf8_lossy(b.kept.get(from..)?).into_owned();
        // The dump is ours, not the host's: it leaves stderr (no crash is read into it).
        b.kept.truncate(from);
        let (frames, waits_in) = super::detect::faulthandler_frames(&dump)?;
        let blocked_in = if blocked { super::detect::faulthandler_port_call(&dump) } else { None };
        return Some(super::detect::HangStack { by: "faulthandler".into(), frames, waits_in, blocked_in });
    }
    super::detect::sample_native(target)
}

/// How long a Python host's `faulthandler` dump is waited for (its death, then the whole
/// dump on stderr).
const DUMP_GRACE: Duration = Duration::from_secs(5);

/// Whether a `faulthandler` dump is whole: its frames, then the blank line after them.
fn dump_is_whole(dump: &str) -> bool {
    let Some(start) = dump.find("(most recent call first):") else { return false };
    let mut frames = 0;
    for l in dump[start..].lines().skip(1) {
        if l.trim_start().starts_with("File \"") {
            frames += 1;
        } else {
            return frames > 0 && dump[start..].contains(&format!("{l}\n"));
        }
    }
    false
}

/// Whether a process stays asleep in one call while it is watched (300 ms): its context
/// switches do not move. A loop that polls a port with a timeout wakes at every timeout.
fn blocked_in_one_call(pid: i32) -> bool {
    let switches = || {
        let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
        let field =
            |name: &str| status.lines().find_map(|l| l.strip_prefix(name)).and_then(|v| v.trim().parse::<u64>().ok());
        Some(field("voluntary_ctxt_switches:")? + field("nonvoluntary_ctxt_switches:")?)
    };
    let Some(before) = switches() else { return false };
    std::thread::sleep(Duration::from_millis(300));
    switches() == Some(before)
}

/// Programs that start the host rather than being it: shells and launchers.
const WRAPPERS: &[&str] =
    &["sh", "bash", "dash", "zsh", "ksh", "busybox", "env", "timeout", "nice", "stdbuf", "setsid", "uv", "make"];

/// The process whose stack is the host's: the host itself, or, when it is a wrapper that still
/// runs ([`WRAPPERS`]: `sh -c '...; ...'`, a shell script that starts the real program), the
/// newest Python interpreter in its process group, else the newest process there with no
/// child in the group (what the wrapper waits for). With whether it is a Python interpreter.
fn stack_target(pid: i32) -> (i32, bool) {
    let is_python = |p: i32| {
        std::fs::read_link(format!("/proc/{p}/exe"))
            .ok()
            .and_then(|e| e.file_name().map(|n| n.to_string_lossy().starts_with("python")))
            .unwrap_or(false)
    };
    if is_python(pid) {
        return (pid, true);
    }
    let exe = std::fs::read_link(format!("/proc/{pid}/exe")).ok();
    let name = exe.as_ref().and_then(|e| e.file_name()).map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    if !WRAPPERS.contains(&name.as_str()) {
        return (pid, false);
    }
    // (pid, parent, start time) of every live process in the host's group.
    let mut group: Vec<(i32, i32, u64)> = Vec::new();
    if let Ok(procs) = std::fs::read_dir("/proc") {
        for p in procs.flatten() {
            let Some(q) = p.file_name().to_str().and_then(|n| n.parse::<i32>().ok()) else { continue };
            let stat = std::fs::read_to_string(p.path().join("stat")).unwrap_or_default();
            let f: Vec<&str> = stat.rsplit_once(')').map(|(_, r)| r.split_whitespace().collect()).unwrap_or_default();
            let field = |i: usize| f.get(i).and_then(|x| x.parse::<i64>().ok());
            if field(2) == Some(i64::from(pid)) && f.first() != Some(&"Z") {
                group.push((q, field(1).unwrap_or(0) as i32, field(19).unwrap_or(0) as u64));
            }
        }
    }
    let newest = |it: &mut dyn Iterator<Item = &(i32, i32, u64)>| it.max_by_key(|(_, _, t)| *t).map(|(p, _, _)| *p);
    if let Some(p) = newest(&mut group.iter().filter(|(p, _, _)| *p != pid && is_python(*p))) {
        return (p, true);
    }
    let leaf = newest(&mut group.iter().filter(|(p, _, _)| *p != pid && !group.iter().any(|(_, pp, _)| pp == p)));
    (leaf.unwrap_or(pid), false)
}

/// Whether a process still runs (not gone, not a zombie).
fn running(pid: i32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .ok()
        .and_then(|s| s.rsplit_once(')').map(|(_, r)| !r.trim_start().starts_with('Z')))
        .unwrap_or(false)
}

/// A process's start time (clock ticks since boot, field 22 of its stat).
fn start_time(pid: i32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat.rsplit_once(')')?.1.split_whitespace().nth(19)?.parse().ok()
}

/// Processes holding `path` (the pty's slave) or the pipe `pipe_inode` open, or with `mark`
/// (`NAME=VALUE`) in their environment, with their names, that started no earlier than the
/// host (`host_start`): what the host can have left behind. Not this process, nor its children: a child of ours is a host of another run, or
/// one being started (between fork and exec it holds copies of all our descriptors), never
/// what this run's host left behind (that was reparented away from us when the host died).
/// With no start time for the host, nothing is found: no process is killed on a guess.
fn holders(
    path: Option<&std::path::Path>,
    pipe_inode: Option<u64>,
    mark: Option<&str>,
    host_start: Option<u64>,
) -> Vec<(i32, String)> {
    let me = std::process::id() as i32;
    let pipe = pipe_inode.map(|i| format!("pipe:[{i}]"));
    let mut found = Vec::new();
    let Some(host_start) = host_start else { return found };
    if path.is_none() && pipe.is_none() && mark.is_none() {
        return found;
    }
    let Ok(procs) = std::fs::read_dir("/proc") else { return found };
    for p in procs.flatten() {
        let Some(pid) = p.file_name().to_str().and_then(|n| n.parse::<i32>().ok()) else { continue };
        if pid == me {
            continue;
        }
        // The parent is the 4th field of stat, after the name in parentheses.
        let stat = std::fs::read_to_string(p.path().join("stat")).unwrap_or_default();
        let fields: Vec<&str> = stat.rsplit_once(')').map(|(_, r)| r.split_whitespace().collect()).unwrap_or_default();
        let ppid = fields.get(1).and_then(|x| x.parse::<i32>().ok());
        let started = fields.get(19).and_then(|x| x.parse::<u64>().ok());
        if ppid == Some(me) || started.is_none_or(|t| t < host_start) {
            continue;
        }
        let marked = mark.is_some_and(|m| {
            std::fs::read(p.path().join("environ")).is_ok_and(|env| env.split(|b| *b == 0).any(|v| v == m.as_bytes()))
        });
        let Ok(fds) = std::fs::read_dir(p.path().join("fd")) else { continue };
        let holds = marked
            || fds.flatten().any(|fd| {
                std::fs::read_link(fd.path())
                    .is_ok_and(|t| path.is_some_and(|p| t == p) || pipe.as_deref().is_some_and(|x| t.as_os_str() == x))
            });
        if holds {
            let name = std::fs::read_to_string(p.path().join("comm")).unwrap_or_default().trim().to_string();
            found.push((pid, name));
        }
    }
    found
}

/// Splits a byte stream into lines for observations; a line longer than 4 KiB is dropped.
#[derive(Default)]
struct LineSplitter {
    line: Vec<u8>,
    overlong: bool,
}

impl LineSplitter {
    fn feed(&mut self, bytes: &[u8], mut each: impl FnMut(&str)) {
        for &b in bytes {
            if b == b'\n' {
                if !self.overlong {
                    each(&String::from_utf8_lossy(&self.line));
                }
                self.line.clear();
                self.overlong = false;
            } else if self.line.len() < 4096 {
                self.line.push(b);
            } else {
                self.overlong = true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What follows the host's stderr (its sanitizer logs, a second run's report) is kept
    /// with it within [`STDERR_CAP`] bytes all told, counted as kept (stderr that is not UTF-8
    /// grows when read): each may have half, and what one leaves the other may take.
    #[test]
    fn stderr_and_what_follows_it_are_kept_within_the_cap() {
        let tail = "\n--- sanitizer log asan.1 ---\n==1==ERROR: AddressSanitizer: x\n";
        let head = String::from_utf8_lossy(&[0xFF; STDERR_CAP]).into_owned();
        assert!(head.len() > STDERR_CAP);
        let s = join_capped(&head, tail);
        assert!(s.len() <= STDERR_CAP && s.ends_with(tail), "{}", s.len());
        let s = join_capped("short\n", &"A".repeat(2 * STDERR_CAP));
        assert!(s.len() == STDERR_CAP && s.starts_with("short\nAAA"), "{}", s.len());
        let s = join_capped(&"h".repeat(STDERR_CAP), &"t".repeat(STDERR_CAP));
        assert_eq!((s.matches('h').count(), s.matches('t').count()), (STDERR_CAP / 2, STDERR_CAP / 2));
        assert_eq!(join_capped("a", "b"), "ab");
    }

    /// A run's folder is the host's: only its sanitizer logs are read, a FIFO and a link
    /// are named and never opened or followed, and what is read (a log that grows when read as
    /// text included) keeps within its room, saying what it cut and what it left out.
    #[test]
    fn a_run_folders_logs_are_read_as_the_hosts_data_within_their_room() {
        let dir = RunDir::new().unwrap();
        let p = |n: &str| dir.0.join(n);
        let outside = tempfile::tempdir().unwrap();
        std::fs::write(outside.path().join("secret"), "SECRET OUTSIDE").unwrap();
        std::fs::write(p("asan.1"), "==1==ERROR: AddressSanitizer: heap-buffer-overflow\n").unwrap();
        nix::unistd::mkfifo(&p("asan.2"), nix::sys::stat::Mode::from_bits_truncate(0o600)).unwrap();
        std::os::unix::fs::symlink(outside.path().join("secret"), p("asan.3")).unwrap();
        std::fs::write(p("notes.txt"), "not a log").unwrap();
        std::fs::write(p("ubsan.4"), [0xFF; 100_000]).unwrap();
        for i in 0..20 {
            std::fs::write(p(&format!("asan.x{i:02}")), vec![b'A'; 256 * 1024]).unwrap();
        }
        let room = tail_room("");
        let logs = dir.sanitizer_logs(room);
        assert!(logs.len() <= room, "{}", logs.len());
        assert!(logs.contains("--- sanitizer log asan.1 ---\n==1==ERROR: AddressSanitizer"), "{logs:.300}");
        assert!(logs.contains("asan.2: not read: not a regular file (a named pipe)"), "{logs:.600}");
        assert!(logs.contains("asan.3: not read: a symbolic link, not followed"), "{logs:.600}");
        assert!(!logs.contains("SECRET") && !logs.contains("not a log"));
        assert!(logs.contains("(cut: the rest of this log is not kept)"));
        assert!(logs.contains("more sanitizer log(s) not kept"), "{}", &logs[logs.len() - 300..]);
        // A log too long for a small room is cut there; a file of \xFF grows threefold as
        // text and is cut as text.
        std::fs::remove_dir_all(&dir.0).unwrap();
        std::fs::create_dir(&dir.0).unwrap();
        std::fs::write(p("ubsan.4"), [0xFF; 3000]).unwrap();
        let logs = dir.sanitizer_logs(4000);
        assert!(logs.len() <= 4000 && logs.contains("(cut: the rest of this log is not kept)"), "{}", logs.len());
    }

    #[test]
    fn an_observation_may_say_where_in_the_host_it_was_made() {
        let value = |what: &str, value, place: Option<&str>| Observation::Value {
            what: what.into(),
            value,
            place: place.map(String::from),
        };
        assert_eq!(Observation::parse("gcl-observe: P 1 5000"), Some(value("P 1 5000", 5000, None)));
        assert_eq!(
            Observation::parse("  gcl-observe: P 2 -7 hostlib.py:212 read_block\n"),
            Some(value("P 2 -7", -7, Some("hostlib.py:212 read_block")))
        );
        assert_eq!(Observation::parse("gcl-observe: error short block"), Some(Observation::Error));
        for not in ["gcl-observe: P x 5", "gcl-observe: P 1", "gcl-observe: P 1 five", "P 1 5000", "gcl-observe:"] {
            assert_eq!(Observation::parse(not), None, "{not}");
        }
        let long = format!("gcl-observe: P 1 5 {}", "x".repeat(500));
        assert!(
            matches!(Observation::parse(&long), Some(Observation::Value { place: Some(p), .. }) if p.len() == WHERE_CAP)
        );
    }
}
