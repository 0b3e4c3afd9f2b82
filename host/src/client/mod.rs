//! A host library that speaks GCL like Barrett's C-Function library (`BHand`), over any
//! [`Link`].
//!
//! [`core`] is the protocol as a sans-IO state machine; [`Hand`] drives it over a link with
//! timeouts: initialise, close, open, move, incremental moves, stop, get and set parameters,
//! error texts, and RealTime control (flags, start, update, read feedback, set velocity and
//! gain, abort). [`programs`] holds the seed document's two example programs.
//!
//! ```
//! use gcl_host::client::Hand;
//! use gcl_host::target::{self, OpenOptions};
//!
//! let mut hand = Hand::open(&"sim:seed".parse().unwrap(), &OpenOptions::default()).unwrap();
//! hand.initialize().unwrap();
//! hand.close("123").unwrap();
//! assert!(hand.get("1", "P").unwrap()[0] > 10_000);
//! ```
//!
//! Every wait is bounded by [`Timeouts`]; no bytes from a hand can make it panic or hang.
//! A [`ClientError`] says who is to blame: the hand refused ([`ClientError::Refused`], its
//! `ERR n`), the hand broke GCL ([`ClientError::Violation`]), it was too slow, the link failed,
//! or the caller asked for something no hand can be asked ([`ClientError::Misuse`], raised
//! before a byte is sent and never by bytes from a hand).
//!
//! `core` is the host side as a sans-IO state machine: echo, `\n\r` lines, `ERR n`, the prompt,
//! LOOP's `*`, RealTime blocks through the model's `BlockLayout`. Its outcomes are typed by who
//! broke the protocol: `poll` gives an `Answer` (done with lines, refused with a status, loop
//! started, feedback, ack, prompt; `ERR n` is data) or a `Violation` (the hand broke GCL; it keeps
//! the bytes and escapes them only when displayed); request builders give a `Misuse` for what the
//! caller cannot ask, before a byte goes out. `Misuse` is not a `poll` outcome at all, so no bytes
//! from a hand produce one (`harness/tests/it/client_props.rs` checks the client over a babbling
//! link).
//!
//! A RealTime block is requested as the model's typed `Control` and written by its `emit`, so a
//! control that lacks a field of the loop's layout, or does not fit one, is a `Misuse`, never a
//! block of the wrong shape.
//!
//! `ClientError` is `Refused | Violation | Timeout | Link | Misuse`. `client::ask` puts one
//! command to a borrowed link (`conform::firmware_version` asks `VERS` with it, so a refusal is
//! never taken for a version). `programs` is called by `harness/examples/`.
//!
//! There is one host-side notion of a GCL answer: the recorder does not parse answers (it writes
//! down whatever a hand says) but ends its supervisory steps with the core's
//! `Framing::prompt_end`.

pub mod core;
pub mod programs;

use std::sync::Arc;
use std::time::Duration;

use gcl_model::params::ParamStore;
use gcl_model::realtime::{Control, ControlHeader, Feedback, MotorFeedback, RtFlag};
use gcl_model::spec::Scope;
use gcl_model::{MotorSet, Profile, RtLayout, StatusBits};

use self::core::{Answer, Framing, HostCore, HostMode, Misuse, Refusal, Violation};
use crate::link::{Link, LinkError, byte_time, drain};
use crate::target::{self, OpenOptions, Target};

/// What went wrong talking to a hand, by who is to blame: the hand refused (`Refused`), the
/// hand broke GCL (`Violation`), the hand was too slow (`Timeout`), the link failed (`Link`),
/// or the caller asked for something that cannot be asked (`Misuse`).
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The hand answered `ERR n`: it kept to GCL and refused or failed.
    #[error("`{request}`: the hand answered ERR {code}{}", describe(*status))]
    Refused {
        /// The command or block that failed.
        request: String,
        /// The status bits (bits GCL does not define are dropped here, kept in `code`).
        status: StatusBits,
        /// The number on the wire.
        code: u32,
        /// Output lines before the `ERR` line.
        lines: Vec<String>,
    },
    /// The hand broke GCL.
    #[error("`{request}`: the hand broke GCL: {violation}")]
    Violation {
        /// The command or block whose answer was wrong.
        request: String,
        /// How.
        violation: Violation,
    },
    /// No complete answer within the timeout.
    #[error("`{waiting_for}`: no complete answer within {after:?}")]
    Timeout {
        /// What was awaited.
        waiting_for: String,
        /// The timeout.
        after: Duration,
    },
    /// The link failed (the hand disconnected, an I/O error, a target that does not open).
    #[error("link: {0}")]
    Link(#[from] LinkError),
    /// A request that cannot be made; no byte was sent for it.
    #[error(transparent)]
    Misuse(#[from] Misuse),
}

fn describe(s: StatusBits) -> String {
    let names: Vec<&str> = s.iter_names().map(|(n, _)| n).collect();
    if names.is_empty() { String::new() } else { format!(" ({})", names.join(" | ")) }
}

impl ClientError {
    /// The status bits, for a refusal.
    pub fn status(&self) -> Option<StatusBits> {
        match self {
            ClientError::Refused { status, .. } => Some(*status),
            _ => None,
        }
    }

    fn refused(request: &str, r: Refusal) -> ClientError {
        ClientError::Refused { request: request.to_string(), status: r.status, code: r.code, lines: r.lines }
    }

    fn violation(request: &str, violation: Violation) -> ClientError {
        ClientError::Violation { request: request.to_string(), violation }
    }
}

/// Sends one supervisory command over a borrowed link and returns its output lines: for
/// one-off questions (`VERS`) by tools that own the link. A refusal is
/// [`ClientError::Refused`], never lines.
pub fn ask(link: &mut dyn Link, framing: Framing, line: &str, timeout: Duration) -> Result<Vec<String>, ClientError> {
    let mut core = HostCore::new(framing);
    let bytes = core.command(line)?;
    link.send(&bytes)?;
    let start = link.elapsed();
    let mut buf = Vec::new();
    loop {
        match core.poll() {
            Ok(Some(Answer::Done(lines))) => return Ok(lines),
            Ok(Some(Answer::Refused(r))) => return Err(ClientError::refused(line, r)),
            // A command is answered by lines or a refusal: `poll` gives nothing else.
            Ok(Some(_)) | Ok(None) => {}
            Err(v) => return Err(ClientError::violation(line, v)),
        }
        let spent = link.elapsed().saturating_sub(start);
        if spent >= timeout {
            return Err(ClientError::Timeout { waiting_for: line.to_string(), after: timeout });
        }
        buf.clear();
        link.recv(&mut buf, timeout - spent)?;
        core.handle_input(&buf);
    }
}

/// How long to wait for each kind of answer (like `BHand::ComSetTimeouts`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timeouts {
    /// A command without motion.
    pub reply: Duration,
    /// A command that moves (HI, C, O, M, IC, IO, HOME...).
    pub motion: Duration,
    /// A RealTime block.
    pub block: Duration,
    /// Each attempt to resynchronise (bare CR, ^C) before `RESET`.
    pub sync: Duration,
}

impl Default for Timeouts {
    fn default() -> Timeouts {
        Timeouts {
            reply: Duration::from_secs(5),
            motion: Duration::from_secs(30),
            block: Duration::from_secs(2),
            sync: Duration::from_secs(1),
        }
    }
}

/// The RealTime flags and coefficients of `RTSetFlags`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RtFlags {
    /// Control blocks carry a velocity (LCV).
    pub lcv: bool,
    /// Control velocity coefficient (LCVC).
    pub lcvc: i64,
    /// Control blocks carry a proportional gain (LCPG).
    pub lcpg: bool,
    /// Feedback carries velocity (LFV).
    pub lfv: bool,
    /// Feedback velocity coefficient (LFVC).
    pub lfvc: i64,
    /// Feedback carries strain (LFS).
    pub lfs: bool,
    /// Feedback carries absolute position (LFAP).
    pub lfap: bool,
    /// Feedback carries delta position (LFDP).
    pub lfdp: bool,
    /// Delta position coefficient (LFDPC).
    pub lfdpc: i64,
}

impl RtFlags {
    /// The flags in `RTSetFlags`' argument order: LCV, LCVC, LCPG, LFV, LFVC, LFS, LFAP, LFDP,
    /// LFDPC. The seed's RealTime example is `RtFlags::barrett(1, 1, 0, 0, 1, 0, 1, 0, 1)`.
    #[allow(clippy::too_many_arguments)] // the argument list of Barrett's RTSetFlags
    pub fn barrett(
        lcv: i64,
        lcvc: i64,
        lcpg: i64,
        lfv: i64,
        lfvc: i64,
        lfs: i64,
        lfap: i64,
        lfdp: i64,
        lfdpc: i64,
    ) -> RtFlags {
        RtFlags {
            lcv: lcv != 0,
            lcvc,
            lcpg: lcpg != 0,
            lfv: lfv != 0,
            lfvc,
            lfs: lfs != 0,
            lfap: lfap != 0,
            lfdp: lfdp != 0,
            lfdpc,
        }
    }

    fn pairs(&self) -> [(&'static str, i64); 9] {
        [
            ("LCV", self.lcv.into()),
            ("LCVC", self.lcvc),
            ("LCPG", self.lcpg.into()),
            ("LFV", self.lfv.into()),
            ("LFVC", self.lfvc),
            ("LFS", self.lfs.into()),
            ("LFAP", self.lfap.into()),
            ("LFDP", self.lfdp.into()),
            ("LFDPC", self.lfdpc),
        ]
    }
}

/// Parses a motor string like Barrett's library takes: any of `1 2 3 4 G S` (`G` = 123,
/// `S` = 4); empty means no prefix (every enabled motor).
pub fn parse_motors(text: &str) -> Result<MotorSet, ClientError> {
    let mut set = MotorSet::EMPTY;
    for c in text.chars() {
        set = set
            | match c.to_ascii_uppercase() {
                '1'..='4' => MotorSet::single(c as u8 - b'0').unwrap_or_default(),
                'G' => MotorSet::FINGERS,
                'S' => MotorSet::SPREAD,
                _ => return Err(Misuse::BadMotors { text: text.to_string() }.into()),
            };
    }
    Ok(set)
}

/// ^C attempts of [`Hand::resync`]: more than the data bytes of the longest control block
/// (4 motors × LCV, LCPG and a 2-byte LCT).
const SYNC_ATTEMPTS: usize = 18;

/// How long the line must stay silent after a resynchronisation.
const QUIET: Duration = Duration::from_millis(50);

#[derive(Debug, Clone)]
struct RtSession {
    layout: RtLayout,
    /// The values of the next control block: every field of the layout, 0 until set.
    control: Control,
    feedback: Option<Feedback>,
    positions: [Option<i64>; 4],
    lfvc: [i64; 4],
    lfdpc: [i64; 4],
    updates: u64,
}

/// A hand at the end of a link: the blocking client.
pub struct Hand {
    link: Box<dyn Link>,
    core: HostCore,
    profile: Arc<Profile>,
    timeouts: Timeouts,
    rt: Option<RtSession>,
    sent: u64,
    received: u64,
    scratch: Vec<u8>,
    early: Option<Result<Answer, ClientError>>,
}

impl std::fmt::Debug for Hand {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Hand")
            .field("link", &self.link.describe())
            .field("profile", &self.profile.id)
            .field("mode", &self.core.mode())
            .finish_non_exhaustive()
    }
}

impl Hand {
    /// A client over `link` for a hand of `profile` (the profile gives the framing, the
    /// parameter names and the RealTime field sizes).
    pub fn new(link: Box<dyn Link>, profile: Arc<Profile>) -> Hand {
        Hand {
            link,
            core: HostCore::new(Framing::of(&profile)),
            profile,
            timeouts: Timeouts::default(),
            rt: None,
            sent: 0,
            received: 0,
            scratch: Vec::with_capacity(4096),
            early: None,
        }
    }

    /// Opens `target` and a client for it. The profile is the `sim` target's, else
    /// `opts.profile`, else `bh8-262`.
    pub fn open(target: &Target, opts: &OpenOptions) -> Result<Hand, ClientError> {
        let name = target
            .sim_profile(opts.profile.as_deref())
            .or(opts.profile.as_deref())
            .unwrap_or(target::DEFAULT_SIM_PROFILE);
        let profile = crate::profiles::load(name)
            .map_err(|e| Misuse::Profile { name: name.to_string(), detail: e.to_string() })?;
        let link = target::open(target, opts)?;
        Ok(Hand::new(link, profile))
    }

    /// The timeouts.
    pub fn timeouts(&self) -> Timeouts {
        self.timeouts
    }

    /// Changes the timeouts (`ComSetTimeouts`).
    pub fn set_timeouts(&mut self, t: Timeouts) {
        self.timeouts = t;
    }

    /// The profile.
    pub fn profile(&self) -> &Arc<Profile> {
        &self.profile
    }

    /// The link.
    pub fn link(&self) -> &dyn Link {
        self.link.as_ref()
    }

    /// The link, mutably (to pause, or to reach the simulator behind a `SimLink`).
    pub fn link_mut(&mut self) -> &mut dyn Link {
        self.link.as_mut()
    }

    /// Gives the link back.
    pub fn into_link(self) -> Box<dyn Link> {
        self.link
    }

    /// Time as the link sees it ([`Link::elapsed`]).
    pub fn elapsed(&self) -> Duration {
        self.link.elapsed()
    }

    /// Bytes sent and received so far.
    pub fn wire_bytes(&self) -> (u64, u64) {
        (self.sent, self.received)
    }

    /// Wire time of every byte so far at `baud` (8N1): what a simulator in fast time counts.
    pub fn wire_time(&self, baud: u32) -> Duration {
        byte_time(baud) * (self.sent + self.received).min(u64::from(u32::MAX)) as u32
    }

    /// Whether the client believes the hand is in RealTime mode.
    pub fn in_realtime(&self) -> bool {
        self.core.mode() == HostMode::RealTime
    }

    // ------------------------------------------------------------------ plumbing

    fn send(&mut self, bytes: &[u8]) -> Result<(), ClientError> {
        self.sent += bytes.len() as u64;
        self.link.send(bytes).map_err(|e| {
            self.core.give_up();
            e.into()
        })
    }

    /// Waits for the answer to `what`; a refusal is an error here.
    fn await_reply(&mut self, timeout: Duration, what: &str) -> Result<Answer, ClientError> {
        let answer = self.await_answer(timeout, what)?;
        self.accept(answer, what)
    }

    fn accept(&mut self, answer: Answer, what: &str) -> Result<Answer, ClientError> {
        if self.core.mode() == HostMode::Supervisory {
            self.rt = None;
        }
        match answer {
            Answer::Refused(r) => Err(ClientError::refused(what, r)),
            a => Ok(a),
        }
    }

    /// Waits for the answer to `what`, a refusal included.
    fn await_answer(&mut self, timeout: Duration, what: &str) -> Result<Answer, ClientError> {
        let start = self.link.elapsed();
        loop {
            match self.core.poll() {
                Ok(Some(a)) => return Ok(a),
                Ok(None) => {}
                Err(v) => {
                    if self.core.mode() == HostMode::Supervisory {
                        self.rt = None;
                    }
                    return Err(ClientError::violation(what, v));
                }
            }
            self.pump(start, timeout, || what.to_string())?;
        }
    }

    /// Waits for more bytes until `timeout` after `start` and feeds them to the core. Past the
    /// deadline, or if the link fails, the core gives up and the error says what was awaited.
    fn pump(&mut self, start: Duration, timeout: Duration, what: impl FnOnce() -> String) -> Result<(), ClientError> {
        let spent = self.link.elapsed().saturating_sub(start);
        if spent >= timeout {
            self.core.give_up();
            return Err(ClientError::Timeout { waiting_for: what(), after: timeout });
        }
        self.scratch.clear();
        match self.link.recv(&mut self.scratch, timeout - spent) {
            Ok(n) => {
                self.received += n as u64;
                self.core.handle_input(&self.scratch);
                Ok(())
            }
            Err(e) => {
                self.core.give_up();
                Err(e.into())
            }
        }
    }

    fn run(&mut self, line: &str, timeout: Duration) -> Result<Vec<String>, ClientError> {
        let bytes = self.core.command(line)?;
        self.send(&bytes)?;
        match self.await_reply(timeout, line)? {
            Answer::Done(l) => Ok(l),
            // A command is answered by lines or a refusal: `poll` gives nothing else.
            _ => Ok(Vec::new()),
        }
    }

    /// Sends a supervisory command and returns its output lines.
    pub fn command(&mut self, line: &str) -> Result<Vec<String>, ClientError> {
        self.run(line, self.timeouts.reply)
    }

    /// Sends a command that moves, with the motion timeout.
    pub fn motion(&mut self, line: &str) -> Result<Vec<String>, ClientError> {
        self.run(line, self.timeouts.motion)
    }

    fn prefixed(&self, motors: &str, command: &str) -> Result<String, ClientError> {
        Ok(format!("{}{command}", parse_motors(motors)?))
    }

    /// Brings the link and the hand to a known state: a bare CR (or, if no prompt comes back,
    /// ^C) and everything up to the prompt discarded.
    pub fn resync(&mut self) -> Result<(), ClientError> {
        self.rt = None;
        let cr = self.core.sync();
        self.send(&cr)?;
        match self.await_reply(self.timeouts.sync, "bare CR") {
            Ok(_) => return self.drain_until_quiet(),
            Err(ClientError::Timeout { .. } | ClientError::Violation { .. }) => {}
            Err(e) => return Err(e),
        }
        // In the middle of a RealTime block a CR or a ^C is data: as many ^C as the longest
        // control block can hold, until one ends the loop (or stops a motion).
        let mut last = None;
        for _ in 0..SYNC_ATTEMPTS {
            let abort = self.core.sync_abort();
            self.send(&abort)?;
            match self.await_reply(self.timeouts.sync, "^C") {
                Ok(_) => return self.drain_until_quiet(),
                Err(e @ (ClientError::Timeout { .. } | ClientError::Violation { .. })) => last = Some(e),
                Err(e) => return Err(e),
            }
        }
        Err(last.unwrap_or(ClientError::Timeout { waiting_for: "^C".into(), after: self.timeouts.sync }))
    }

    /// Discards input until the line has been quiet for a moment: prompts still in flight
    /// from before a resynchronisation (a banner, answers to garbage) must not be taken for
    /// the answer to the next command.
    fn drain_until_quiet(&mut self) -> Result<(), ClientError> {
        self.received += drain(self.link.as_mut(), self.timeouts.sync.min(QUIET), self.timeouts.sync)?;
        Ok(())
    }

    /// `RESET`: returns the banner lines, checked as Barrett's C++ API checks them: some line
    /// ends with `BarrettHand Firmware` (the text straight followed by the line ending).
    pub fn reset(&mut self) -> Result<Vec<String>, ClientError> {
        let banner = self.run("RESET", self.timeouts.motion)?;
        if !banner.iter().any(|l| l.ends_with("BarrettHand Firmware")) {
            return Err(ClientError::violation("RESET", Violation::NoBanner { lines: banner }));
        }
        Ok(banner)
    }

    /// Start-up like `BHand::InitHand("")` after `InitSoftware`: a bare CR, `RESET` (the
    /// banner must contain `BarrettHand Firmware`), then `HI`. Returns the banner.
    pub fn initialize(&mut self) -> Result<Vec<String>, ClientError> {
        self.resync()?;
        let banner = self.reset()?;
        self.motion("HI")?;
        Ok(banner)
    }

    /// `HI` for some motors (`InitHand("123S")`).
    pub fn init_hand(&mut self, motors: &str) -> Result<(), ClientError> {
        let l = self.prefixed(motors, "HI")?;
        self.motion(&l).map(drop)
    }

    /// `C`: close.
    pub fn close(&mut self, motors: &str) -> Result<(), ClientError> {
        let l = self.prefixed(motors, "C")?;
        self.motion(&l).map(drop)
    }

    /// `O`: open.
    pub fn open_fingers(&mut self, motors: &str) -> Result<(), ClientError> {
        let l = self.prefixed(motors, "O")?;
        self.motion(&l).map(drop)
    }

    /// `M [pos]`: move to `pos`, or to DP.
    pub fn move_to(&mut self, motors: &str, pos: Option<i64>) -> Result<(), ClientError> {
        let l = self.prefixed(motors, &pos.map_or("M".to_string(), |p| format!("M {p}")))?;
        self.motion(&l).map(drop)
    }

    /// `IC [step]`: incremental close by `step`, or by DS.
    pub fn incremental_close(&mut self, motors: &str, step: Option<i64>) -> Result<(), ClientError> {
        let l = self.prefixed(motors, &step.map_or("IC".to_string(), |s| format!("IC {s}")))?;
        self.motion(&l).map(drop)
    }

    /// `IO [step]`: incremental open by `step`, or by DS.
    pub fn incremental_open(&mut self, motors: &str, step: Option<i64>) -> Result<(), ClientError> {
        let l = self.prefixed(motors, &step.map_or("IO".to_string(), |s| format!("IO {s}")))?;
        self.motion(&l).map(drop)
    }

    /// `T`: stop the motors (terminate power).
    pub fn stop(&mut self, motors: &str) -> Result<(), ClientError> {
        let l = self.prefixed(motors, "T")?;
        self.command(&l).map(drop)
    }

    /// Sends a command and returns once the hand has echoed it, without waiting for it to
    /// finish: then [`Hand::finish`] waits for the end, or [`Hand::abort`] stops it.
    pub fn start(&mut self, line: &str) -> Result<(), ClientError> {
        self.early = None;
        let bytes = self.core.command(line)?;
        self.send(&bytes)?;
        let timeout = self.timeouts.reply;
        let start = self.link.elapsed();
        loop {
            if self.core.echo_received() {
                // Finished already (an error, or a command without motion)?
                return match self.core.poll() {
                    Ok(None) => Ok(()),
                    Ok(Some(a)) => {
                        self.early = Some(self.accept(a, line));
                        Ok(())
                    }
                    Err(v) => Err(ClientError::violation(line, v)),
                };
            }
            if let Err(v) = self.core.poll() {
                return Err(ClientError::violation(line, v));
            }
            self.pump(start, timeout, || format!("echo of `{line}`"))?;
        }
    }

    /// Waits (motion timeout) for the end of a command begun with [`Hand::start`]; its
    /// output lines.
    pub fn finish(&mut self) -> Result<Vec<String>, ClientError> {
        match self.early.take() {
            Some(Ok(Answer::Done(l))) => Ok(l),
            Some(Ok(_)) => Ok(Vec::new()),
            Some(Err(e)) => Err(e),
            None => match self.await_reply(self.timeouts.motion, "the command in progress")? {
                Answer::Done(l) => Ok(l),
                _ => Ok(Vec::new()),
            },
        }
    }

    /// ^C in supervisory mode: stops a motion in progress; returns the lines before the
    /// prompt (`ERR 16384` on bh8-262 when something was stopped).
    pub fn abort(&mut self) -> Result<Vec<String>, ClientError> {
        self.early = None;
        let b = self.core.abort();
        self.send(&b)?;
        self.rt = None;
        match self.await_reply(self.timeouts.reply, "^C")? {
            Answer::Prompt(lines) => Ok(lines),
            _ => Ok(Vec::new()),
        }
    }

    fn values(line: &str, what: &str) -> Result<Vec<i64>, ClientError> {
        line.split_whitespace()
            .map(|v| v.parse::<i64>())
            .collect::<Result<Vec<_>, _>>()
            .map_err(|_| ClientError::violation(what, Violation::NotANumber { line: line.to_string() }))
    }

    /// `FGET name`: one value per motor (motor order).
    pub fn get(&mut self, motors: &str, name: &str) -> Result<Vec<i64>, ClientError> {
        Ok(self.get_many(motors, &[name])?.pop().unwrap_or_default())
    }

    /// `FGET n1 n2 ...`: for each name, one value per motor.
    pub fn get_many(&mut self, motors: &str, names: &[&str]) -> Result<Vec<Vec<i64>>, ClientError> {
        let l = self.prefixed(motors, &format!("FGET {}", names.join(" ")))?;
        let lines = self.command(&l)?;
        if lines.len() != names.len() {
            return Err(ClientError::violation(&l, Violation::LineCount { expected: names.len(), lines }));
        }
        lines.iter().map(|line| Self::values(line, &l)).collect()
    }

    /// `FSET name value` for some motors.
    pub fn set(&mut self, motors: &str, name: &str, value: i64) -> Result<(), ClientError> {
        self.set_many(motors, &[(name, value)])
    }

    /// `FSET n1 v1 n2 v2 ...`, split over several lines if one would be too long for the hand.
    pub fn set_many(&mut self, motors: &str, pairs: &[(&str, i64)]) -> Result<(), ClientError> {
        let prefix = self.prefixed(motors, "FSET")?;
        let max = self.profile.framing.max_line;
        let mut line = prefix.clone();
        for (n, v) in pairs {
            let item = format!(" {n} {v}");
            if line.len() > prefix.len() && line.len() + item.len() > max {
                self.command(&line)?;
                line = prefix.clone();
            }
            line.push_str(&item);
        }
        if line.len() > prefix.len() {
            self.command(&line)?;
        }
        Ok(())
    }

    /// `PGET name`: a global parameter.
    pub fn pget(&mut self, name: &str) -> Result<i64, ClientError> {
        let l = format!("PGET {name}");
        let lines = self.command(&l)?;
        let v = lines.first().map(|line| Self::values(line, &l)).transpose()?.unwrap_or_default();
        v.first().copied().ok_or_else(|| ClientError::violation(&l, Violation::LineCount { expected: 1, lines }))
    }

    /// `PSET name value`: a global parameter.
    pub fn pset(&mut self, name: &str, value: i64) -> Result<(), ClientError> {
        self.command(&format!("PSET {name} {value}")).map(drop)
    }

    /// `ERR n`: the hand's description lines of a status number.
    pub fn error_text(&mut self, code: u32) -> Result<Vec<String>, ClientError> {
        self.command(&format!("ERR {code}"))
    }

    /// The description of a status from the profile, without asking the hand
    /// (`BHand::ErrorMessage`).
    pub fn error_message(&self, status: StatusBits) -> String {
        status.describe(&self.profile).join("; ")
    }

    // ------------------------------------------------------------------ RealTime

    /// `RTSetFlags`: one `FSET` of the RealTime flags and coefficients for `motors`.
    pub fn rt_set_flags(&mut self, motors: &str, flags: RtFlags) -> Result<(), ClientError> {
        self.set_many(motors, &flags.pairs())
    }

    /// `RTStart`: reads the RealTime flags of `motors` back from the hand (so that flags loaded
    /// from its EEPROM count too), computes the block layouts, reads the positions, and sends
    /// `LOOP`.
    pub fn rt_start(&mut self, motors: &str) -> Result<(), ClientError> {
        let set = parse_motors(motors)?;
        if set.is_empty() {
            return Err(Misuse::NoMotors.into());
        }
        let profile = self.profile.clone();
        let mut store = ParamStore::defaults(&profile);
        let mut motor_names = Vec::new();
        let mut global_names = Vec::new();
        for id in profile.param_ids() {
            let p = profile.param(id);
            let wanted = p.rt.is_some() || matches!(p.name.as_str(), "LCVC" | "LFVC" | "LFDPC");
            if !wanted || p.alias_of.is_some() {
                continue;
            }
            match p.scope {
                Scope::Motor => motor_names.push(p.name.clone()),
                Scope::Global => global_names.push(p.name.clone()),
            }
        }
        let digits = set.to_string();
        // Several FGET lines if one would be too long.
        let max = profile.framing.max_line;
        let mut chunk: Vec<&str> = Vec::new();
        let mut chunks: Vec<Vec<&str>> = Vec::new();
        for n in &motor_names {
            let len = digits.len() + 4 + chunk.iter().map(|c| c.len() + 1).sum::<usize>() + n.len() + 1;
            if !chunk.is_empty() && len > max {
                chunks.push(std::mem::take(&mut chunk));
            }
            chunk.push(n);
        }
        if !chunk.is_empty() {
            chunks.push(chunk);
        }
        for names in chunks {
            let values = self.get_many(&digits, &names)?;
            for (name, vals) in names.iter().zip(values) {
                let Some(id) = profile.param_id(name) else { continue };
                for (m, v) in set.iter().zip(vals) {
                    store.set_unchecked(&profile, id, MotorSet::single(m).unwrap_or_default(), v);
                }
            }
        }
        for name in &global_names {
            let Some(id) = profile.param_id(name) else { continue };
            let v = self.pget(name)?;
            store.set_unchecked(&profile, id, MotorSet::ALL, v);
        }
        let coeff = |name: &str| -> [i64; 4] {
            std::array::from_fn(|i| store.get_named(&profile, name, i as u8 + 1).unwrap_or(1).max(1))
        };
        let (lfvc, lfdpc) = (coeff("LFVC"), coeff("LFDPC"));
        // FGET P gives the starting positions (and restarts the hand's LFDP reckoning).
        let p = self.get(&digits, "P")?;
        let mut positions = [None; 4];
        for (m, v) in set.iter().zip(p) {
            positions[(m - 1) as usize] = Some(v);
        }
        let layout = RtLayout::compute(&profile, &store, set);
        let line = format!("{digits}LOOP");
        let bytes = self.core.start_loop(&line, layout.clone())?;
        self.send(&bytes)?;
        // `LOOP` is answered by `*` or a refusal: `poll` gives nothing else.
        self.await_reply(self.timeouts.reply, &line)?;
        let control = Control::zeroed(ControlHeader::DataFeedback, layout.control());
        self.rt = Some(RtSession { layout, control, feedback: None, positions, lfvc, lfdpc, updates: 0 });
        Ok(())
    }

    /// The loop's block layouts.
    pub fn rt_layout(&self) -> Option<&RtLayout> {
        self.rt.as_ref().map(|r| &r.layout)
    }

    fn session(&mut self) -> Result<&mut RtSession, ClientError> {
        self.rt.as_mut().ok_or(ClientError::Misuse(Misuse::NotInRealTime))
    }

    fn set_control(&mut self, motor: char, flag: RtFlag, value: i64) -> Result<(), ClientError> {
        let m = parse_motors(&motor.to_string())?;
        let Some(m) = m.iter().next().filter(|_| m.len() == 1) else {
            return Err(Misuse::NotOneMotor { motor }.into());
        };
        let s = self.session()?;
        let f = s
            .layout
            .control()
            .fields()
            .iter()
            .find(|f| f.motor() == Some(m) && f.flag() == flag)
            .ok_or_else(|| Misuse::NoSuchField { motor: m, name: flag.name().to_string() })?;
        s.control.set(f, value.clamp(f.min(), f.max()));
        Ok(())
    }

    /// `RTSetVelocity`: the LCV datum for a motor in the next control block (clamped to a
    /// signed byte).
    pub fn rt_set_velocity(&mut self, motor: char, velocity: i64) -> Result<(), ClientError> {
        self.set_control(motor, RtFlag::Lcv, velocity)
    }

    /// `RTSetGain`: the LCPG datum for a motor in the next control block.
    pub fn rt_set_gain(&mut self, motor: char, gain: i64) -> Result<(), ClientError> {
        self.set_control(motor, RtFlag::Lcpg, gain)
    }

    /// `RTSetTorque` (bh8-262-4.4): the LCT datum for a motor.
    pub fn rt_set_torque(&mut self, motor: char, torque: i64) -> Result<(), ClientError> {
        self.set_control(motor, RtFlag::Lct, torque)
    }

    /// `RTUpdate`: sends a `C` block with the control values (or `A` when the control block
    /// is empty) and reads the feedback.
    pub fn rt_update(&mut self) -> Result<(), ClientError> {
        let no_control = self.session()?.layout.control().fields().is_empty();
        self.rt_update_with(!no_control, true)
    }

    /// `RTUpdate(control, feedback)`: `C`, `c`, `A` or `a`.
    pub fn rt_update_with(&mut self, control: bool, feedback: bool) -> Result<(), ClientError> {
        let header = match (control, feedback) {
            (true, true) => ControlHeader::DataFeedback,
            (true, false) => ControlHeader::DataAck,
            (false, true) => ControlHeader::Feedback,
            (false, false) => ControlHeader::Ack,
        };
        let mut control = self.session()?.control;
        control.header = header;
        let what = format!("RealTime block {}", header.byte() as char);
        let bytes = self.core.block(&control)?;
        self.send(&bytes)?;
        match self.await_reply(self.timeouts.block, &what)? {
            Answer::Feedback(v) => {
                let s = self.session()?;
                s.updates += 1;
                for m in s.layout.motors().iter() {
                    let i = (m - 1) as usize;
                    let fb = v.motor(m);
                    if let Some(ap) = fb.absolute_position {
                        s.positions[i] = Some(ap);
                    } else if let Some(dp) = fb.delta_position {
                        s.positions[i] = Some(s.positions[i].unwrap_or(0) + dp * s.lfdpc[i]);
                    }
                }
                s.feedback = Some(*v);
                Ok(())
            }
            _ => {
                self.session()?.updates += 1;
                Ok(())
            }
        }
    }

    /// The last feedback of one motor.
    fn feedback(&self, motor: char) -> Option<MotorFeedback> {
        let s = self.rt.as_ref()?;
        let m = parse_motors(&motor.to_string()).ok()?.iter().next()?;
        Some(s.feedback.as_ref()?.motor(m))
    }

    /// `RTGetPosition`: from LFAP, or reckoned from LFDP × LFDPC since `rt_start`.
    pub fn rt_get_position(&self, motor: char) -> Option<i64> {
        let m = parse_motors(&motor.to_string()).ok()?.iter().next()?;
        self.rt.as_ref()?.positions[(m - 1) as usize]
    }

    /// `RTGetStrain`: LFS of the last feedback.
    pub fn rt_get_strain(&self, motor: char) -> Option<i64> {
        self.feedback(motor)?.strain
    }

    /// `RTGetVelocity`: LFV × LFVC of the last feedback.
    pub fn rt_get_velocity(&self, motor: char) -> Option<i64> {
        let m = parse_motors(&motor.to_string()).ok()?.iter().next()?;
        let c = self.rt.as_ref()?.lfvc[(m - 1) as usize];
        self.feedback(motor)?.velocity.map(|v| v * c)
    }

    /// `RTGetDeltaPos`: the raw LFDP of the last feedback.
    pub fn rt_get_delta_position(&self, motor: char) -> Option<i64> {
        self.feedback(motor)?.delta_position
    }

    /// LFT of the last feedback (bh8-262).
    pub fn rt_get_temperature(&self) -> Option<i64> {
        self.rt.as_ref()?.feedback.as_ref()?.temperature
    }

    /// Blocks exchanged since `rt_start`.
    pub fn rt_updates(&self) -> u64 {
        self.rt.as_ref().map_or(0, |s| s.updates)
    }

    /// `RTAbort`: ^C, and the prompt back.
    pub fn rt_abort(&mut self) -> Result<(), ClientError> {
        let b = self.core.abort();
        self.send(&b)?;
        self.rt = None;
        self.await_reply(self.timeouts.reply, "^C (leave RealTime)").map(drop)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hand(profile: &str) -> Hand {
        Hand::open(&format!("sim:{profile}").parse().unwrap(), &OpenOptions::default()).unwrap()
    }

    #[test]
    fn motors_parse_like_barretts() {
        assert_eq!(parse_motors("123").unwrap(), MotorSet::FINGERS);
        assert_eq!(parse_motors("GS").unwrap(), MotorSet::ALL);
        assert_eq!(parse_motors("").unwrap(), MotorSet::EMPTY);
        assert!(parse_motors("5").is_err());
    }

    #[test]
    fn supervisory_operations() {
        let mut h = hand("seed");
        let banner = h.initialize().unwrap();
        assert!(banner[0].contains("BarrettHand Firmware"));
        h.close("123").unwrap();
        let p = h.get("123", "P").unwrap();
        assert!(p.iter().all(|v| *v > 10_000), "{p:?}");
        h.open_fingers("G").unwrap();
        assert!(h.get("1", "P").unwrap()[0] < 100);
        h.set("1", "DP", 1234).unwrap();
        assert_eq!(h.get("1", "DP").unwrap(), vec![1234]);
        h.move_to("1", None).unwrap();
        assert!((h.get("1", "P").unwrap()[0] - 1234).abs() < 50);
        let e = h.set("1", "DP", 999_999).unwrap_err();
        assert_eq!(e.status(), Some(StatusBits::INVALID_VALUE));
        assert_eq!(e.to_string(), "`1FSET DP 999999`: the hand answered ERR 128 (INVALID_VALUE)");
        assert!(h.error_text(128).unwrap()[0].contains("128"));
        assert!(h.error_message(StatusBits::INVALID_VALUE).contains("128"));
        assert!(matches!(h.command("NONESUCH"), Err(ClientError::Refused { code: 32, .. })));
        assert!(h.pget("TEMP").unwrap() > 0);
    }

    #[test]
    fn a_misuse_sends_nothing() {
        let mut h = hand("seed");
        h.initialize().unwrap();
        let before = h.wire_bytes();
        assert!(matches!(h.command("FGET P\rHI"), Err(ClientError::Misuse(Misuse::ControlInLine { .. }))));
        assert!(matches!(h.close("5"), Err(ClientError::Misuse(Misuse::BadMotors { .. }))));
        assert!(matches!(h.rt_update(), Err(ClientError::Misuse(Misuse::NotInRealTime))));
        assert!(matches!(h.rt_start(""), Err(ClientError::Misuse(Misuse::NoMotors))));
        assert_eq!(h.wire_bytes(), before);
    }

    #[test]
    fn realtime_operations() {
        let mut h = hand("seed");
        h.initialize().unwrap();
        h.rt_set_flags("123", RtFlags::barrett(1, 1, 0, 0, 1, 0, 1, 0, 1)).unwrap();
        h.rt_start("123").unwrap();
        assert_eq!(h.rt_layout().unwrap().control().size(), 4);
        assert_eq!(h.rt_layout().unwrap().feedback().size(), 7);
        h.rt_set_velocity('1', 55).unwrap();
        assert!(h.rt_set_gain('1', 3).is_err());
        for _ in 0..100 {
            h.rt_update().unwrap();
        }
        assert!(h.rt_get_position('1').unwrap() > 1000);
        assert_eq!(h.rt_get_position('2'), Some(0));
        assert!(h.command("FGET P").is_err());
        h.rt_abort().unwrap();
        assert!(h.get("1", "P").unwrap()[0] > 1000);
    }

    #[test]
    fn realtime_on_bh8_262_reads_flags_back() {
        let mut h = hand("bh8-262");
        h.initialize().unwrap();
        h.rt_start("1234").unwrap();
        // bh8-262's default flags: LCV, LCPG in control; LFV, LFS, LFAP, LFDP in feedback.
        assert_eq!(h.rt_layout().unwrap().feedback().size(), 21);
        h.rt_update().unwrap();
        assert!(h.rt_get_strain('1').is_some());
        h.rt_abort().unwrap();
    }

    #[test]
    fn a_refused_loop_is_a_refusal() {
        let mut h = hand("seed");
        h.resync().unwrap();
        let e = h.rt_start("123").unwrap_err();
        assert_eq!(e.status(), Some(StatusBits::NOT_INITIALIZED));
        assert!(!h.in_realtime());
    }
}
