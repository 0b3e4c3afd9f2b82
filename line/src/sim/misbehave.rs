//! Misbehaviours a real hand or a real cable can produce, as a layer between the engine's
//! output and the transport (`gcl fuzz host`).
//!
//! A [`LineTap`] installed with [`super::Engine::set_tap`] sees every chunk of host bytes
//! before the model does and every answer before it is queued for the host; it may reshape an
//! answer and hold part of it back ([`Shaped`]). [`Misbehave`] is the tap's misbehaving half:
//! it runs a [`Schedule`] of named [`Operator`]s, each planned for the Nth answer of the
//! session (or the next answer after it that the operator applies to), and remembers what it
//! did ([`Fired`]). The model's state is never touched, except by a restart, which powers it
//! up afresh ([`Shaped::restart`]); every other operator changes only bytes on their way out.
//! Like the engine, this module does no I/O; the hang-up operator only says so
//! ([`Shaped::hang_up`]) and the transport's owner closes the line.
//!
//! The engine's only knowledge of the tap is that hold. The tap also hears when a host comes and
//! goes and, from the pty or TCP, whether the host wrote with output unread; the engine tells it
//! when
//! the transport takes an answer's last byte (`LineTap::delivered`), so "an answer is still coming"
//! means on the line, not in the model.
//!
//! The operators: delays around common timeouts, prompt, truncation, garbage, `ERR` bits, echo,
//! CR LF, overlong lines, banner, restart, RealTime block faults, hang-up, silence with the port
//! left
//! open; and `line-rate`, no misbehaviour: the session paced at the hand's BAUD, which the run's
//! owner reads from the schedule. `Misbehave` records each new kind of answer (its shape: `echo,
//! values, prompt`, `feedback block`...) with its first answer and the operators that apply to
//! it.

use std::time::Duration;

use gcl_model::{Device, Mode};
use serde::{Deserialize, Serialize};

/// What a tap sees and shapes. Implementations must never panic on any bytes.
pub trait LineTap: Send {
    /// Host bytes as the transport read them, before the model sees them.
    fn host_bytes(&mut self, device: &Device, bytes: &[u8]);
    /// Before the host bytes that follow: whether the host's side of the line still held
    /// bytes the host had not read (told only by transports that can see it, the pty).
    fn host_unread(&mut self, _unread: bool) {}
    /// One answer of the hand (whatever the model produced for one line, one block or one
    /// timer), before it is queued for the host: what actually goes out.
    fn hand_bytes(&mut self, device: &Device, bytes: &[u8]) -> Shaped;
    /// The transport took the last byte of the oldest answer not yet taken (as shaped, and
    /// only answers with bytes count): under pacing, when that byte's wire time has passed.
    fn delivered(&mut self, _device: &Device) {}
    /// The host went away and the answers it had not taken were discarded.
    fn discarded(&mut self, _device: &Device) {}
    /// A host opened the port or connected (`true`), or the last one went away (`false`).
    fn connection(&mut self, _device: &Device, _open: bool) {}
}

/// An answer as it goes out.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Shaped {
    /// The bytes to send.
    pub bytes: Vec<u8>,
    /// Hold the output from this offset of `bytes` on for this long.
    pub hold: Option<(usize, Duration)>,
    /// Send `bytes`, then hang up the line.
    pub hang_up: bool,
    /// The hand restarted: the model powers up afresh (its EEPROM kept); `bytes` already end
    /// with its power-up output.
    pub restart: bool,
}

impl Shaped {
    /// The answer unchanged.
    pub fn plain(bytes: &[u8]) -> Shaped {
        Shaped { bytes: bytes.to_vec(), hold: None, hang_up: false, restart: false }
    }
}

macro_rules! operators {
    ($($(#[doc = $doc:literal])* $v:ident => $name:literal, $weight:literal;)*) => {
        /// A named misbehaviour (serialized by its name).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Operator {
            $($(#[doc = $doc])* $v,)*
        }

        impl Operator {
            /// Every operator.
            pub const ALL: &'static [Operator] = &[$(Operator::$v),*];

            /// The operator's name (`--ops`, schedules, reports).
            pub fn name(self) -> &'static str {
                match self { $(Operator::$v => $name,)* }
            }

            /// What it does, one line.
            pub fn description(self) -> &'static str {
                match self { $(Operator::$v => concat!($($doc),*).trim_start(),)* }
            }

            /// Its default weight in a random schedule (relative).
            pub fn default_weight(self) -> u32 {
                match self { $(Operator::$v => $weight,)* }
            }
        }
    };
}

operators! {
    /// Holds the answer (or its prompt) back for 90 % of a common host timeout.
    DelayBelow => "delay-below", 1;
    /// Holds the answer (or its prompt) back for 110 % of a common host timeout.
    DelayAbove => "delay-above", 1;
    /// Leaves out the prompt that ends an answer.
    NoPrompt => "no-prompt", 3;
    /// Sends a malformed prompt (`=>`, `> `, `=>  `, `-> `).
    BadPrompt => "bad-prompt", 3;
    /// Cuts the answer short.
    Truncate => "truncate", 3;
    /// Inserts 1 to 8 random bytes somewhere in the answer.
    Garbage => "garbage", 3;
    /// Appends bytes after the answer (a second prompt, a line end, a NUL, random bytes).
    ExtraBytes => "extra-bytes", 3;
    /// Answers `ERR n` with bits no status table has (32768, 65535, 2^31, 2^32-1, -1, 20 digits).
    ErrBits => "err-bits", 3;
    /// Changes one byte of the echo.
    WrongEcho => "wrong-echo", 3;
    /// Ends lines with CR LF instead of LF CR.
    CrLf => "crlf", 3;
    /// Adds an answer line of 81, 256, 1024 or 4096 bytes.
    OverlongLine => "overlong-line", 3;
    /// Prints a variant of the banner (after RESET): a version suffix, an extra line, upper case, a line missing.
    BannerVariant => "banner-variant", 2;
    /// Restarts mid-answer: the answer is cut, the hand powers up afresh (motors no longer initialized, EEPROM kept) and its banner and prompt follow.
    Restart => "restart", 2;
    /// RealTime: a feedback block one or two bytes short or long.
    RtBlockLength => "rt-block-length", 3;
    /// RealTime: `\n\rERR n` in place of the feedback block.
    RtErr => "rt-err", 3;
    /// RealTime: one bit of the feedback block flipped.
    RtByteFlip => "rt-byte-flip", 3;
    /// RealTime: extreme feedback values (positions 65535, velocities -128, others at their limit).
    RtExtreme => "rt-extreme", 3;
    /// Hangs up the line part-way through an answer.
    HangUp => "hang-up", 1;
    /// Goes silent part-way through an answer, the port left open (a pulled cable, a hand powered off): nothing more is sent in the session.
    Silence => "silence", 1;
    /// No misbehaviour: the whole session at the hand's line rate (its BAUD), as on a real serial line, where the rest of an answer is still crossing when its echo has come (an unpaced campaign's systematic pass makes one such run; weight 0: never drawn at random).
    LineRate => "line-rate", 0;
}

impl Operator {
    /// Whether it changes what the hand says or when (every operator but `line-rate`, the
    /// timing of a real line): a host may give up on an answer it changed.
    pub fn misbehaves(self) -> bool {
        self != Operator::LineRate
    }
}

impl Serialize for Operator {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Operator {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Operator, D::Error> {
        let name = String::deserialize(d)?;
        // Schedules written before operators were serialized by name spelled crlf `cr-lf`.
        let name = if name == "cr-lf" { "crlf" } else { name.as_str() };
        name.parse().map_err(serde::de::Error::custom)
    }
}

impl std::fmt::Display for Operator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// An operator name that is not one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown misbehaviour `{0}` (known: {known})", known = Operator::ALL.iter().map(|o| o.name()).collect::<Vec<_>>().join(", "))]
pub struct UnknownOperator(pub String);

impl std::str::FromStr for Operator {
    type Err = UnknownOperator;
    fn from_str(s: &str) -> Result<Operator, UnknownOperator> {
        Operator::ALL.iter().copied().find(|o| o.name() == s).ok_or_else(|| UnknownOperator(s.to_string()))
    }
}

/// Read timeouts hosts commonly use; delays are placed just below and above them. 1 s is the
/// default of Arduino's `Serial.setTimeout` (arduino.cc reference); 2 s and 5 s are this
/// project's own client's RealTime-block and reply timeouts (`client::Timeouts::default`), 5 s
/// also the default of Ignition's `system.serial.readUntil` (docs.inductiveautomation.com);
/// 100 to 500 ms are what polling hosts pick for a 9600-baud line.
pub const COMMON_TIMEOUTS: [Duration; 6] = [
    Duration::from_millis(100),
    Duration::from_millis(250),
    Duration::from_millis(500),
    Duration::from_secs(1),
    Duration::from_secs(2),
    Duration::from_secs(5),
];

/// One planned misbehaviour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Planned {
    /// The answer it is planned for (1 is the first answer of the session); it fires there or
    /// at the first answer after it that it applies to.
    pub answer: u32,
    /// What it does.
    pub op: Operator,
    /// Its variant (which delay, where to cut, which bytes), any number.
    pub arg: u32,
}

/// What the fuzzer does to one session, in order of answers.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Schedule {
    /// The misbehaviours.
    pub planned: Vec<Planned>,
}

/// A misbehaviour that happened.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fired {
    /// Index of the planned entry in the schedule.
    pub index: usize,
    /// The answer it changed (1-based).
    pub answer: u32,
    /// The operator.
    pub op: Operator,
    /// The protocol state it hit: `answer to FGET`, `feedback block`, `banner`...
    pub state: String,
    /// One line saying what changed.
    pub what: String,
}

/// A kind of answer a session gave, as the systematic pass of `gcl fuzz host` covers them:
/// answers of one kind have the same shape (echo, value lines, `ERR n`, banner, prompt, or a
/// RealTime block), so the same misbehaviours apply to them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct AnswerKindSeen {
    /// The kind: `echo, values, prompt`, `banner, prompt`, `feedback block`...
    pub kind: String,
    /// The first answer of this kind (1-based).
    pub answer: u32,
    /// The protocol state of that answer (`answer to FGET`).
    pub state: String,
    /// The operators that apply to it.
    pub ops: Vec<Operator>,
}

/// Most kinds of answer recorded per session.
const KINDS_CAP: usize = 32;

/// What kind of answer a chunk of output is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AnswerKind {
    /// A supervisory answer (echo, lines, prompt), or a piece of one.
    Supervisory,
    /// A RealTime feedback block or `*`.
    Feedback,
}

/// Runs a schedule over a session's answers.
#[derive(Debug, Clone)]
pub struct Misbehave {
    schedule: Schedule,
    done: Vec<bool>,
    answers: u32,
    power_up: Vec<u8>,
    fired: Vec<Fired>,
    /// The `silence` operator fired: every answer from then on is dropped.
    silent: bool,
    /// The kinds of answer seen, in order of first appearance.
    kinds: Vec<AnswerKindSeen>,
    /// The last supervisory piece the hand sent did not end with its prompt: the answer it
    /// began (an echo sent as the host's bytes came, the line's CR still to come) is still open.
    open_answer: bool,
}

impl Misbehave {
    /// A runner of `schedule` for a hand of `device`'s profile.
    pub fn new(schedule: Schedule, device: &Device) -> Misbehave {
        let mut fresh = Device::with_profile(device.profile().clone());
        let power_up = fresh.take_output();
        let done = vec![false; schedule.planned.len()];
        Misbehave {
            schedule,
            done,
            answers: 0,
            power_up,
            fired: Vec::new(),
            silent: false,
            kinds: Vec::new(),
            open_answer: false,
        }
    }

    /// What fired so far.
    pub fn fired(&self) -> &[Fired] {
        &self.fired
    }

    /// Answers seen so far.
    pub fn answers(&self) -> u32 {
        self.answers
    }

    /// The kinds of answer the hand gave so far (as made, before any misbehaviour), each with
    /// its first answer and the operators that apply to it.
    pub fn kinds(&self) -> &[AnswerKindSeen] {
        &self.kinds
    }

    /// Records the kind of this answer when it is a new one.
    fn note_kind(&mut self, device: &Device, bytes: &[u8], kind: AnswerKind, echo_before: bool, state: &str) {
        if self.kinds.len() >= KINDS_CAP {
            return;
        }
        let name = kind_name(device, bytes, kind);
        if self.kinds.iter().any(|k| k.kind == name) {
            return;
        }
        let ops = Operator::ALL
            .iter()
            .copied()
            .filter(|&op| apply(op, 0, kind, echo_before, device, &self.power_up, &mut Shaped::plain(bytes)).is_some())
            .collect();
        self.kinds.push(AnswerKindSeen { kind: name, answer: self.answers, state: state.to_string(), ops });
    }

    /// Shapes one answer; `state` names the protocol state it answers (for [`Fired`]).
    pub fn shape(&mut self, device: &Device, bytes: &[u8], state: &str) -> Shaped {
        self.answers += 1;
        let kind = if device.mode() == Mode::Loop && bytes.first() == Some(&gcl_model::realtime::FEEDBACK_HEADER) {
            AnswerKind::Feedback
        } else {
            AnswerKind::Supervisory
        };
        // A host that writes a command and its CR apart gets the echo as one piece and the rest
        // of the answer as the next: that piece's echo came before it.
        let echo_before = kind == AnswerKind::Supervisory && self.open_answer;
        if !bytes.is_empty() {
            self.note_kind(device, bytes, kind, echo_before, state);
            let prompt = device.profile().framing.prompt.as_bytes();
            self.open_answer = kind == AnswerKind::Supervisory && !bytes.ends_with(prompt);
        }
        if self.silent {
            return Shaped::plain(&[]);
        }
        let mut out = Shaped::plain(bytes);
        for i in 0..self.schedule.planned.len() {
            let p = self.schedule.planned[i];
            if self.done[i] || p.answer > self.answers || out.hang_up || self.silent {
                continue;
            }
            if let Some(what) = apply(p.op, p.arg, kind, echo_before, device, &self.power_up, &mut out) {
                self.done[i] = true;
                self.silent |= p.op == Operator::Silence;
                self.fired.push(Fired { index: i, answer: self.answers, op: p.op, state: state.to_string(), what });
            }
        }
        out
    }
}

/// The shape of an answer: `feedback block`, or the parts of a supervisory one in order
/// (`echo`, `banner`, `values`, `ERR`, `prompt`; a piece of an answer has only some).
fn kind_name(device: &Device, bytes: &[u8], kind: AnswerKind) -> String {
    if kind == AnswerKind::Feedback {
        return "feedback block".into();
    }
    let framing = &device.profile().framing;
    let (eol, prompt) = (framing.line_ending.as_bytes(), framing.prompt.as_bytes());
    let banner = device.profile().banner.first().map(|b| b.as_bytes().to_vec()).unwrap_or_default();
    let mut parts: Vec<&str> = Vec::new();
    let body = bytes.strip_suffix(prompt).filter(|_| !prompt.is_empty());
    let text = body.unwrap_or(bytes);
    let mut lines: Vec<&[u8]> = if eol.is_empty() { vec![text] } else { split(text, eol) };
    // The first line is the echo when the answer starts with one (an answer to ^C or a timer
    // starts with the line ending).
    // A piece with no line ending and no prompt is an echo alone (a host that writes its CR
    // apart gets its command echoed as it comes; `wrong-echo` takes it so too).
    if lines.len() == 1 && body.is_none() && !text.is_empty() && !eol.is_empty() {
        return "echo".into();
    }
    if lines.len() > 1 && !lines[0].is_empty() {
        parts.push("echo");
    }
    if lines.len() > 1 {
        lines.remove(0);
    }
    if find(bytes, &banner).is_some() {
        parts.push("banner");
    } else if lines.iter().any(|l| l.starts_with(b"ERR")) {
        parts.push("ERR");
    } else if lines.iter().any(|l| !l.is_empty()) {
        parts.push("values");
    }
    if body.is_some() {
        parts.push("prompt");
    }
    if parts.is_empty() { "other".into() } else { parts.join(", ") }
}

/// `hay` split at every `sep` (non-empty).
fn split<'a>(hay: &'a [u8], sep: &[u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut rest = hay;
    while let Some(i) = find(rest, sep) {
        out.push(&rest[..i]);
        rest = &rest[i + sep.len()..];
    }
    out.push(rest);
    out
}

/// Where `needle` first occurs in `hay` (an empty needle, as a loaded profile's framing may
/// give, occurs nowhere).
fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() {
        return None;
    }
    hay.windows(needle.len()).position(|w| w == needle)
}

fn pick<T: Copy>(list: &[T], arg: u32) -> T {
    list[arg as usize % list.len()]
}

/// Bytes from a small generator seeded by `arg` (never the line's own framing bytes alone).
fn noise(arg: u32, n: usize) -> Vec<u8> {
    let mut x = u64::from(arg) ^ 0x9E37_79B9_7F4A_7C15;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect()
}

/// Applies one operator to `out` when it applies to this answer; says what it did. Each
/// operator is a function below, given the answer's parts.
fn apply(
    op: Operator,
    arg: u32,
    kind: AnswerKind,
    echo_before: bool,
    device: &Device,
    power_up: &[u8],
    out: &mut Shaped,
) -> Option<String> {
    let a = Parts::of(kind, echo_before, device, power_up, &out.bytes);
    match op {
        Operator::DelayBelow => delay(9, arg, &a, out),
        Operator::DelayAbove => delay(11, arg, &a, out),
        Operator::NoPrompt => no_prompt(&a, &mut out.bytes),
        Operator::BadPrompt => bad_prompt(arg, &a, &mut out.bytes),
        Operator::Truncate => truncate(arg, &mut out.bytes),
        Operator::Garbage => garbage(arg, &mut out.bytes),
        Operator::ExtraBytes => extra_bytes(arg, &a, &mut out.bytes),
        Operator::ErrBits => err_bits(arg, &a, &mut out.bytes),
        Operator::WrongEcho => wrong_echo(arg, &a, &mut out.bytes),
        Operator::CrLf => crlf(&a, &mut out.bytes),
        Operator::OverlongLine => overlong_line(arg, &a, &mut out.bytes),
        Operator::BannerVariant => banner_variant(arg, &a, &mut out.bytes),
        Operator::Restart => restart(arg, &a, out),
        Operator::RtBlockLength => rt_block_length(arg, &a, &mut out.bytes),
        Operator::RtErr => rt_err(arg, &a, &mut out.bytes),
        Operator::RtByteFlip => rt_byte_flip(arg, &a, &mut out.bytes),
        Operator::RtExtreme => rt_extreme(arg, &a, &mut out.bytes),
        Operator::Silence => silence(arg, out),
        Operator::HangUp => hang_up(arg, out),
        // The pace is the session's (the transport's owner reads the schedule); nothing changes.
        Operator::LineRate => Some("the session at the hand's line rate (its BAUD)".into()),
    }
}

/// An answer as an operator meets it: the hand's framing, and where the answer's parts are.
struct Parts<'a> {
    kind: AnswerKind,
    device: &'a Device,
    /// What the hand sends as it powers up.
    power_up: &'a [u8],
    eol: &'a [u8],
    prompt: &'a [u8],
    /// A supervisory answer (not a feedback block).
    sup: bool,
    /// The answer ends with the prompt.
    ends_prompt: bool,
    /// Where the echo ends (the first line ending), if anywhere.
    echo_end: Option<usize>,
    /// The echo came in an earlier piece (this one starts where the host's CR was answered).
    echo_before: bool,
}

impl<'a> Parts<'a> {
    /// Takes an answer and the hand it comes from; gives its parts.
    fn of(kind: AnswerKind, echo_before: bool, device: &'a Device, power_up: &'a [u8], b: &[u8]) -> Parts<'a> {
        let framing = &device.profile().framing;
        let (eol, prompt) = (framing.line_ending.as_bytes(), framing.prompt.as_bytes());
        Parts {
            kind,
            device,
            power_up,
            eol,
            prompt,
            sup: kind == AnswerKind::Supervisory,
            ends_prompt: b.ends_with(prompt),
            echo_end: find(b, eol),
            echo_before,
        }
    }
}

/// `delay-below`/`delay-above`: holds back the answer (or its prompt) for `tenths`/10 of a
/// common host timeout.
fn delay(tenths: u32, arg: u32, a: &Parts<'_>, out: &mut Shaped) -> Option<String> {
    let b = &out.bytes;
    if b.is_empty() || out.hold.is_some() {
        return None;
    }
    let t = pick(&COMMON_TIMEOUTS, arg);
    let d = t * tenths / 10;
    let at = if a.ends_prompt && arg / 8 % 2 == 1 { b.len() - a.prompt.len() } else { 0 };
    out.hold = Some((at, d));
    let whr = if at == 0 { "the answer" } else { "the prompt" };
    Some(format!("{whr} held back {} ms", d.as_millis()))
}

/// `no-prompt`: a supervisory answer without its prompt.
fn no_prompt(a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    if !a.sup || !a.ends_prompt {
        return None;
    }
    b.truncate(b.len() - a.prompt.len());
    Some("prompt left out".into())
}

/// `bad-prompt`: a supervisory answer's prompt sent wrong.
fn bad_prompt(arg: u32, a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    if !a.sup || !a.ends_prompt {
        return None;
    }
    let bad = pick::<&[u8]>(&[b"=>", b"> ", b"=>  ", b"-> "], arg);
    b.truncate(b.len() - a.prompt.len());
    b.extend_from_slice(bad);
    Some(format!("prompt sent as \"{}\"", gcl_model::escape::escape(bad)))
}

/// `truncate`: the answer's last bytes cut.
fn truncate(arg: u32, b: &mut Vec<u8>) -> Option<String> {
    if b.len() < 2 {
        return None;
    }
    let at = 1 + arg as usize % (b.len() - 1);
    let cut = b.len() - at;
    b.truncate(at);
    Some(format!("last {cut} bytes cut"))
}

/// `garbage`: noise inserted into the answer.
fn garbage(arg: u32, b: &mut Vec<u8>) -> Option<String> {
    if b.is_empty() {
        return None;
    }
    let at = arg as usize % b.len();
    let g = noise(arg, 1 + (arg as usize / 7) % 8);
    let what = format!("\"{}\" inserted at byte {at}", gcl_model::escape::escape(&g));
    b.splice(at..at, g);
    Some(what)
}

/// `extra-bytes`: a line ending, a prompt, a NUL or noise after the answer.
fn extra_bytes(arg: u32, a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    if b.is_empty() {
        return None;
    }
    let extra: Vec<u8> = match arg % 4 {
        0 => [a.eol, a.prompt].concat(),
        1 => a.eol.to_vec(),
        2 => vec![0],
        _ => noise(arg, 4),
    };
    let what = format!("\"{}\" appended", gcl_model::escape::escape(&extra));
    b.extend(extra);
    Some(what)
}

/// `err-bits`: a supervisory answer replaced, after its echo, by an ERR GCL does not define.
fn err_bits(arg: u32, a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    // After an echo: in this piece, or (a host that wrote its CR apart) in the one before.
    let e = a.echo_end.filter(|&e| a.sup && a.ends_prompt && (e > 0 || a.echo_before))?;
    let err = pick(
        &["ERR 32768", "ERR 65535", "ERR 2147483648", "ERR 4294967295", "ERR -1", "ERR 99999999999999999999"],
        arg,
    );
    b.truncate(e);
    b.extend_from_slice(a.eol);
    b.extend_from_slice(err.as_bytes());
    b.extend_from_slice(a.eol);
    b.extend_from_slice(a.prompt);
    Some(format!("answered {err}"))
}

/// `wrong-echo`: one byte of the echo sent otherwise.
fn wrong_echo(arg: u32, a: &Parts<'_>, b: &mut [u8]) -> Option<String> {
    // The echo ends at the first line ending; a piece with none and no prompt is an echo alone
    // (a host that writes its CR apart gets its command echoed as it comes).
    let e = match a.echo_end {
        Some(e) if a.sup && e > 0 => e,
        None if a.sup && !a.ends_prompt && !b.is_empty() => b.len(),
        _ => return None,
    };
    let i = arg as usize % e;
    let c = b[i];
    b[i] = if c.is_ascii_alphabetic() {
        c ^ 0x20
    } else if c == b'?' {
        b'!'
    } else {
        b'?'
    };
    Some(format!("echo byte {i} {} sent as {}", gcl_model::escape::escape(&[c]), gcl_model::escape::escape(&[b[i]])))
}

/// `crlf`: a supervisory answer's lines end in CR LF.
fn crlf(a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    if !a.sup || a.echo_end.is_none() {
        return None;
    }
    let mut v = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(a.eol) {
            v.extend_from_slice(b"\r\n");
            i += a.eol.len();
        } else {
            v.push(b[i]);
            i += 1;
        }
    }
    *b = v;
    Some("lines end in CR LF".into())
}

/// `overlong-line`: a line longer than a host's buffer added after the echo.
fn overlong_line(arg: u32, a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    let e = a.echo_end.filter(|_| a.sup && a.ends_prompt)?;
    let n = pick(&[81usize, 256, 1024, 4096], arg);
    let mut line = a.eol.to_vec();
    line.extend(b"1234567890".iter().cycle().take(n));
    b.splice(e..e, line);
    Some(format!("a {n}-byte line added"))
}

/// `banner-variant`: the banner's first line with a version suffix, a line after it, in
/// upper case, or missing.
fn banner_variant(arg: u32, a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    let first = a.device.profile().banner.first()?.clone();
    let at = find(b, first.as_bytes())?;
    let end = at + first.len();
    let what = match arg % 4 {
        0 => {
            b.splice(end..end, b" V9.99 (rev Z)".iter().copied());
            "version suffix on the banner"
        }
        1 => {
            b.splice(end..end, [a.eol, b"Copyright (c) 2026 nobody"].concat());
            "extra banner line"
        }
        2 => {
            b[at..end].make_ascii_uppercase();
            "banner in upper case"
        }
        _ => {
            let cut = if b[end..].starts_with(a.eol) { end + a.eol.len() } else { end };
            b.drain(at..cut);
            "first banner line missing"
        }
    };
    Some(what.into())
}

/// `restart`: the supervisory answer cut, then the hand powers up again.
fn restart(arg: u32, a: &Parts<'_>, out: &mut Shaped) -> Option<String> {
    let b = &mut out.bytes;
    if !a.sup || b.is_empty() {
        return None;
    }
    let at = arg as usize % b.len();
    b.truncate(at);
    b.extend_from_slice(a.power_up);
    out.restart = true;
    Some(format!("restart after {at} bytes: the hand powers up again (banner, prompt)"))
}

/// `rt-block-length`: a feedback block a byte or two short or long.
fn rt_block_length(arg: u32, a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    if a.kind != AnswerKind::Feedback || b.len() < 2 {
        return None;
    }
    let n = 1 + (arg as usize / 2) % 2;
    if arg.is_multiple_of(2) {
        b.truncate(b.len() - n.min(b.len() - 1));
        Some(format!("feedback block {n} bytes short"))
    } else {
        b.extend(noise(arg, n));
        Some(format!("feedback block {n} bytes long"))
    }
}

/// `rt-err`: an ERR line in place of a feedback block.
fn rt_err(arg: u32, a: &Parts<'_>, b: &mut Vec<u8>) -> Option<String> {
    if a.kind != AnswerKind::Feedback {
        return None;
    }
    let err = pick(&["ERR 2048", "ERR 1024", "ERR 32768"], arg);
    b.clear();
    b.extend_from_slice(a.eol);
    b.extend_from_slice(err.as_bytes());
    Some(format!("\\n\\r{err} in place of the feedback block"))
}

/// `rt-byte-flip`: one bit of a feedback block flipped.
fn rt_byte_flip(arg: u32, a: &Parts<'_>, b: &mut [u8]) -> Option<String> {
    if a.kind != AnswerKind::Feedback {
        return None;
    }
    let i = arg as usize % b.len();
    let bit = (arg / 16) % 8;
    b[i] ^= 1 << bit;
    Some(format!("bit {bit} of byte {i} flipped"))
}

/// `rt-extreme`: a feedback block's values at the extremes of their fields.
fn rt_extreme(arg: u32, a: &Parts<'_>, b: &mut [u8]) -> Option<String> {
    let layout = a.device.rt_layout().filter(|_| a.kind == AnswerKind::Feedback)?;
    let fb = layout.feedback();
    if b.len() != fb.size() || fb.fields().is_empty() {
        return None;
    }
    for f in fb.fields() {
        let v: i64 = match f.name() {
            "LFAP" | "LFBP" => 65535,
            "LFV" | "LFDP" => -128,
            _ if arg.is_multiple_of(2) => f.max(),
            _ => f.min(),
        };
        let v = v.clamp(f.min(), f.max());
        let bytes = if f.size() == 1 { vec![v as u8] } else { (v as u16).to_be_bytes().to_vec() };
        if let Some(slot) = b.get_mut(f.offset()..f.offset() + f.size()) {
            slot.copy_from_slice(&bytes[..f.size().min(bytes.len())]);
        }
    }
    Some("feedback values at their extremes".into())
}

/// `silence`: the answer cut, and nothing more sent (the line left open).
fn silence(arg: u32, out: &mut Shaped) -> Option<String> {
    let b = &mut out.bytes;
    let at = if b.is_empty() { 0 } else { arg as usize % b.len() };
    b.truncate(at);
    out.hold = None;
    Some(format!("silent after {at} bytes of the answer, the line left open"))
}

/// `hang-up`: the answer cut, then the line hung up.
fn hang_up(arg: u32, out: &mut Shaped) -> Option<String> {
    let b = &mut out.bytes;
    let at = if b.is_empty() { 0 } else { arg as usize % b.len() };
    b.truncate(at);
    out.hang_up = true;
    Some(format!("line hung up after {at} bytes of the answer"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use gcl_model::Profile;

    fn device() -> Device {
        Device::with_profile(Profile::builtin("seed").unwrap())
    }

    fn shape(op: Operator, arg: u32, answer: &[u8]) -> (Shaped, Vec<Fired>) {
        let d = device();
        let mut m = Misbehave::new(Schedule { planned: vec![Planned { answer: 1, op, arg }] }, &d);
        let s = m.shape(&d, answer, "answer to FGET");
        (s, m.fired().to_vec())
    }

    #[test]
    fn names_round_trip_and_every_operator_has_a_description() {
        for op in Operator::ALL {
            assert_eq!(op.name().parse::<Operator>().unwrap(), *op);
            // JSON (schedules, fuzz.json) spells it by its name too.
            assert_eq!(serde_json::to_value(op).unwrap(), serde_json::Value::from(op.name()));
            assert_eq!(serde_json::from_value::<Operator>(op.name().into()).unwrap(), *op);
            assert!(!op.description().is_empty(), "{op}");
        }
        assert!("nope".parse::<Operator>().unwrap_err().to_string().contains("truncate"));
        assert_eq!(serde_json::from_value::<Operator>("cr-lf".into()).unwrap(), Operator::CrLf);
    }

    #[test]
    fn supervisory_operators_change_what_they_say() {
        let a = b"FGET DP\n\r1000 1000 1000 150\n\r=> ";
        assert_eq!(shape(Operator::NoPrompt, 0, a).0.bytes, b"FGET DP\n\r1000 1000 1000 150\n\r");
        assert_eq!(shape(Operator::ErrBits, 0, a).0.bytes, b"FGET DP\n\rERR 32768\n\r=> ");
        assert_eq!(shape(Operator::CrLf, 0, a).0.bytes, b"FGET DP\r\n1000 1000 1000 150\r\n=> ");
        assert_eq!(shape(Operator::WrongEcho, 0, a).0.bytes[0], b'f');
        assert!(shape(Operator::OverlongLine, 3, a).0.bytes.len() > 4096);
        let (s, f) = shape(Operator::HangUp, 5, a);
        assert!(s.hang_up && s.bytes == b"FGET ");
        assert_eq!(f[0].state, "answer to FGET");
        let (s, _) = shape(Operator::DelayAbove, 3, a);
        assert_eq!(s.hold, Some((0, Duration::from_millis(1100))));
    }

    #[test]
    fn an_operator_that_does_not_apply_waits_for_an_answer_it_applies_to() {
        let d = device();
        let mut m =
            Misbehave::new(Schedule { planned: vec![Planned { answer: 1, op: Operator::ErrBits, arg: 1 }] }, &d);
        assert_eq!(m.shape(&d, b"\n\r=> ", "abort").bytes, b"\n\r=> ".to_vec(), "no echo line to answer after");
        assert!(m.fired().is_empty());
        assert_eq!(m.shape(&d, b"X\n\r=> ", "answer to X").bytes, b"X\n\rERR 65535\n\r=> ".to_vec());
        assert_eq!(m.fired()[0].answer, 2);
        // Fired once only.
        assert_eq!(m.shape(&d, b"X\n\r=> ", "answer to X").bytes, b"X\n\r=> ".to_vec());
        // A host that writes its CR apart gets the echo first and the answer's end after it:
        // the end is an answer after an echo (unlike ^C's, which follows a prompt).
        let mut m =
            Misbehave::new(Schedule { planned: vec![Planned { answer: 1, op: Operator::ErrBits, arg: 1 }] }, &d);
        assert_eq!(m.shape(&d, b"HI", "answer to HI").bytes, b"HI".to_vec());
        assert_eq!(m.shape(&d, b"\n\r=> ", "answer to HI").bytes, b"\n\rERR 65535\n\r=> ".to_vec());
        assert_eq!(m.fired()[0].answer, 2);
        // And its echo alone, in a piece of its own, is an echo still.
        let mut m =
            Misbehave::new(Schedule { planned: vec![Planned { answer: 1, op: Operator::WrongEcho, arg: 0 }] }, &d);
        assert_eq!(m.shape(&d, b"HI", "answer to HI").bytes, b"hI".to_vec());
        assert_eq!(m.kinds()[0].kind, "echo", "{:?}", m.kinds());
        // RealTime operators never touch a supervisory answer.
        for op in [Operator::RtErr, Operator::RtByteFlip, Operator::RtExtreme, Operator::RtBlockLength] {
            assert!(shape(op, 0, b"FGET DP\n\r1\n\r=> ").1.is_empty(), "{op}");
        }
    }

    #[test]
    fn silence_cuts_the_answer_and_drops_every_later_one() {
        let d = device();
        let planned = vec![
            Planned { answer: 1, op: Operator::Silence, arg: 5 },
            Planned { answer: 2, op: Operator::Garbage, arg: 1 },
        ];
        let mut m = Misbehave::new(Schedule { planned }, &d);
        assert_eq!(m.shape(&d, b"FGET DP\n\r1\n\r=> ", "answer to FGET").bytes, b"FGET ".to_vec());
        assert!(m.shape(&d, b"HI\n\r=> ", "answer to HI").bytes.is_empty());
        assert!(m.shape(&d, b"*\x01\x02", "RealTime feedback").bytes.is_empty());
        assert_eq!(m.fired().len(), 1, "nothing fires on a silent line: {:?}", m.fired());
        assert_eq!(m.answers(), 3);
    }

    /// A tap that records the host's bytes and holds every answer back 10 s.
    struct Holding(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

    impl LineTap for Holding {
        fn host_bytes(&mut self, _: &Device, bytes: &[u8]) {
            self.0.lock().unwrap().extend_from_slice(bytes);
        }
        fn hand_bytes(&mut self, _: &Device, bytes: &[u8]) -> Shaped {
            Shaped { bytes: bytes.to_vec(), hold: Some((0, Duration::from_secs(10))), hang_up: false, restart: false }
        }
    }

    #[test]
    fn the_engine_holds_back_what_a_tap_holds_and_shows_it_the_host_bytes() {
        use std::time::Instant;
        let mut e = crate::sim::Engine::new(&crate::sim::SimOptions::new(Profile::builtin("seed").unwrap())).unwrap();
        let banner = e.ready_output(Instant::now()).len();
        e.consumed(banner);
        let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        e.set_tap(Box::new(Holding(seen.clone())));
        e.input(b"FGET DP\r");
        assert_eq!(*seen.lock().unwrap(), b"FGET DP\r");
        assert!(e.has_output());
        assert!(e.ready_output(Instant::now()).is_empty(), "held back");
        assert!(e.deadline().is_some_and(|d| d > Instant::now() + Duration::from_secs(5)));
        let later = Instant::now() + Duration::from_secs(11);
        assert_eq!(e.ready_output(later), b"FGET DP\n\r1000 1000 1000 150\n\r=> ");
    }

    /// A tap that restarts the hand on its first answer.
    struct Restarting(bool);

    impl LineTap for Restarting {
        fn host_bytes(&mut self, _: &Device, _: &[u8]) {}
        fn hand_bytes(&mut self, _: &Device, bytes: &[u8]) -> Shaped {
            let restart = !std::mem::replace(&mut self.0, true);
            Shaped { bytes: bytes.to_vec(), hold: None, hang_up: false, restart }
        }
    }

    #[test]
    fn a_restart_powers_the_model_up_again() {
        use std::time::Instant;
        let mut e = crate::sim::Engine::new(&crate::sim::SimOptions::new(Profile::builtin("seed").unwrap())).unwrap();
        e.set_tap(Box::new(Restarting(false)));
        e.input(b"HI\r");
        e.input(b"1M 100\r");
        let out = e.ready_output(Instant::now()).to_vec();
        let text = String::from_utf8_lossy(&out);
        assert!(text.ends_with("1M 100\n\rERR 4\n\r=> "), "the motors are no longer initialized: {text}");
    }

    #[test]
    fn never_panics_on_odd_answers() {
        let d = device();
        for op in Operator::ALL {
            for arg in 0..40 {
                for a in [&b""[..], b"=> ", b"\n\r", b"*", b"x", b"\n\r=> \n\r=> "] {
                    let mut m = Misbehave::new(Schedule { planned: vec![Planned { answer: 1, op: *op, arg }] }, &d);
                    let _ = m.shape(&d, a, "s");
                }
            }
        }
    }
}
