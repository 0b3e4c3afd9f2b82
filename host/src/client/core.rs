//! The host side of GCL as a sans-IO state machine: it builds the bytes of each request and
//! recognises the hand's answer in whatever pieces it arrives, like `httparse`: `Ok(None)`
//! means "need more bytes", `Ok(Some(answer))` is an [`Answer`] (a refusal, `ERR n`, is one),
//! and an `Err` is a [`Violation`]: the hand broke GCL. Requests the caller cannot make fail
//! with a [`Misuse`] before any byte goes out; no byte from a hand produces one.
//!
//! Framing it knows (from the profile's `[framing]`): a command goes out as `line\r`; the hand
//! echoes the line (not the CR), then sends each output line introduced by `\n\r`, then
//! `\n\r=> `; a failure is `\n\rERR n\n\r=> `. `LOOP` is answered by its echo and `*`. In
//! RealTime mode a control block (`C`/`c` + data, or `A`/`a`) is answered by a feedback block
//! (`*` + fields) or `*` alone, or by `\n\rERR n\n\r=> ` (back to supervisory mode); ^C leaves
//! the loop with a prompt. Block layouts are the model's [`RtLayout`], computed by the caller
//! from the flags.
//!
//! The core never blocks, never reads a clock and never panics, whatever bytes it is fed.

use gcl_model::escape::escape;
use gcl_model::realtime::{BlockError, Control, ControlHeader, FEEDBACK_HEADER, Feedback};
use gcl_model::{Profile, RtLayout, StatusBits};

/// Longest answer the core buffers before calling the bytes a framing error.
pub const MAX_REPLY: usize = 64 * 1024;

/// The framing bytes, from a profile.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Framing {
    /// Ends a command line (CR).
    pub terminator: u8,
    /// Starts every output line (LF CR).
    pub line_ending: Vec<u8>,
    /// The prompt (`=> `).
    pub prompt: Vec<u8>,
    /// ^C.
    pub abort: u8,
}

impl Framing {
    /// The framing of a profile.
    pub fn of(profile: &Profile) -> Framing {
        Framing {
            terminator: profile.framing.terminator,
            line_ending: profile.framing.line_ending.as_bytes().to_vec(),
            prompt: profile.framing.prompt.as_bytes().to_vec(),
            abort: profile.framing.abort,
        }
    }

    /// Where the first prompt (line break then `=> `) in `bytes` ends, if there is one: the end
    /// of every supervisory answer, and the only end a host that does not parse the answer
    /// (the recorder) can rely on.
    pub fn prompt_end(&self, bytes: &[u8]) -> Option<usize> {
        self.prompt_end_from(bytes, 0)
    }

    /// [`Framing::prompt_end`] for a prompt that begins at `from` or later: a reader that
    /// has looked for it in a shorter buffer looks again only where a prompt could have
    /// completed since ([`Framing::prompt_search_start`] of the length it looked in).
    pub fn prompt_end_from(&self, bytes: &[u8], from: usize) -> Option<usize> {
        let (le, p) = (self.line_ending.as_slice(), self.prompt.as_slice());
        let n = le.len() + p.len();
        if n == 0 || bytes.len() < n || from > bytes.len() - n {
            return None;
        }
        let first = le.first().or(p.first()).copied();
        bytes[from..]
            .windows(n)
            .position(|w| w.first().copied() == first && w.starts_with(le) && w.ends_with(p))
            .map(|i| from + i + n)
    }

    /// Where a search for a prompt must begin once a buffer of `len` bytes held none: a
    /// prompt that those bytes do not hold can only begin in its last `n - 1` (n the prompt's
    /// length with its line break).
    pub fn prompt_search_start(&self, len: usize) -> usize {
        len.saturating_sub((self.line_ending.len() + self.prompt.len()).saturating_sub(1))
    }
}

impl Default for Framing {
    fn default() -> Framing {
        Framing { terminator: b'\r', line_ending: b"\n\r".to_vec(), prompt: b"=> ".to_vec(), abort: 3 }
    }
}

/// A complete answer from the hand: everything a hand that keeps to GCL can say, including a
/// refusal (`ERR n` is data, as a 4xx is in httparse).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Answer {
    /// A supervisory command finished without a status; its output lines.
    Done(Vec<String>),
    /// The hand answered `ERR n` to a command, to `LOOP`, or to a RealTime block (which also
    /// ends the loop).
    Refused(Refusal),
    /// `LOOP` was answered with `*`: the hand is in RealTime mode.
    LoopStarted,
    /// A feedback block, typed per motor (`feedback.motor(m).strain`).
    Feedback(Box<Feedback>),
    /// `*` alone (after `c` or `a`).
    Ack,
    /// A prompt after ^C or a bare CR, with the lines before it (such as `ERR 16384`).
    Prompt(Vec<String>),
}

/// `ERR n`: the hand understood the framing and refused or failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    /// The status bits (bits GCL does not define are dropped here, kept in `code`).
    pub status: StatusBits,
    /// The number on the wire.
    pub code: u32,
    /// Output lines before the `ERR` line.
    pub lines: Vec<String>,
}

impl Refusal {
    fn of(code: u32, lines: Vec<String>) -> Refusal {
        Refusal { status: StatusBits::from_bits_truncate(code), code, lines }
    }
}

/// The hand broke GCL: its bytes fit no answer the request allows. Bytes are kept as they came;
/// they are escaped only when the violation is displayed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Violation {
    /// The echo differs from the line sent.
    #[error("echo mismatch: sent \"{}\", the hand echoed \"{}\"", escape(sent), escape(got))]
    EchoMismatch {
        /// The line sent.
        sent: Vec<u8>,
        /// What came back (at most 16 bytes past the echo's length).
        got: Vec<u8>,
    },
    /// Where a line break (`\n\r`) must start, something else came.
    #[error("expected a line break at byte {at}; received \"{}\"", escape(got))]
    MissingLineBreak {
        /// Offset in the answer.
        at: usize,
        /// The answer so far (at most 200 bytes).
        got: Vec<u8>,
    },
    /// An `ERR` line whose number does not parse.
    #[error("status line \"{}\" has no number", escape(line))]
    StatusWithoutNumber {
        /// The line.
        line: Vec<u8>,
    },
    /// A feedback block that does not decode with the loop's layout.
    #[error("bad feedback block ({error}): \"{}\"", escape(got))]
    BadFeedback {
        /// Why it does not decode.
        error: BlockError,
        /// The block.
        got: Vec<u8>,
    },
    /// In RealTime mode, a byte that starts neither a feedback block (`*`) nor a line break.
    #[error("expected a feedback header `*`, got byte {byte:#04x}")]
    NotABlock {
        /// The byte.
        byte: u8,
    },
    /// `LOOP` answered with lines and a prompt, but neither `*` nor `ERR`.
    #[error("LOOP was answered with lines but neither `*` nor ERR: {lines:?}")]
    LoopNotEntered {
        /// The lines.
        lines: Vec<String>,
    },
    /// In RealTime mode the hand went back to its prompt without an `ERR` line.
    #[error("the loop ended without an ERR line: {lines:?}")]
    LoopEndedWithoutStatus {
        /// The lines before the prompt.
        lines: Vec<String>,
    },
    /// More than [`MAX_REPLY`] bytes without a complete answer.
    #[error("answer longer than {limit} bytes")]
    TooLong {
        /// The limit.
        limit: usize,
    },
    /// An output line that should hold numbers does not.
    #[error("not a number: \"{}\"", escape(line.as_bytes()))]
    NotANumber {
        /// The line.
        line: String,
    },
    /// A different number of output lines than the command asks for (`FGET` gives one per
    /// parameter).
    #[error("{} lines for {expected} values: {lines:?}", lines.len())]
    LineCount {
        /// Lines expected.
        expected: usize,
        /// The lines received.
        lines: Vec<String>,
    },
    /// After `RESET` the banner lacks `BarrettHand Firmware`.
    #[error("no `BarrettHand Firmware` banner after RESET; got {lines:?}")]
    NoBanner {
        /// The lines received.
        lines: Vec<String>,
    },
}

/// The caller asked for something no hand could be asked: these come from the request
/// alone, never from bytes of a hand.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Misuse {
    /// A command line holding the terminator (CR) or ^C.
    #[error("a command line cannot hold a CR or ^C: \"{}\"", escape(line.as_bytes()))]
    ControlInLine {
        /// The line.
        line: String,
    },
    /// A supervisory command while the hand is in RealTime mode.
    #[error("`{}`: the hand is in RealTime mode; abort the loop first", escape(line.as_bytes()))]
    InRealTime {
        /// The line.
        line: String,
    },
    /// A RealTime block or setting outside a loop.
    #[error("not in RealTime mode: start a loop first")]
    NotInRealTime,
    /// A control value that does not fit its field, or the wrong number of values.
    #[error("control block: {0}")]
    Block(BlockError),
    /// A motor string other than `1 2 3 4 G S`.
    #[error("bad motor string `{text}`: use 1 2 3 4 G S")]
    BadMotors {
        /// The text.
        text: String,
    },
    /// A RealTime setting for something other than one motor.
    #[error("`{motor}` is not one motor")]
    NotOneMotor {
        /// The motor text.
        motor: char,
    },
    /// A loop without motors.
    #[error("RTStart needs motors, e.g. \"123\"")]
    NoMotors,
    /// A control datum the loop's control block does not carry.
    #[error("motor {motor} has no {name} in its control block: set the flag with rt_set_flags")]
    NoSuchField {
        /// The motor.
        motor: u8,
        /// The field.
        name: String,
    },
    /// A profile that does not load.
    #[error("profile `{name}`: {detail}")]
    Profile {
        /// The name given.
        name: String,
        /// Why it does not load.
        detail: String,
    },
}

/// Supervisory or RealTime, as far as the host knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostMode {
    /// Commands.
    Supervisory,
    /// Blocks.
    RealTime,
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Await {
    Nothing,
    Reply { echo: Vec<u8> },
    Loop { echo: Vec<u8> },
    Prompt { lenient: bool },
    Feedback,
    Ack,
}

/// The host's protocol state.
#[derive(Debug, Clone)]
pub struct HostCore {
    framing: Framing,
    mode: HostMode,
    layout: Option<RtLayout>,
    pending_layout: Option<RtLayout>,
    waiting: Await,
    rx: Vec<u8>,
    discarded: u64,
}

enum Lines {
    Partial,
    Complete {
        lines: Vec<String>,
        used: usize,
    },
    /// No line break at this offset.
    Bad(usize),
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() || hay.len() < needle.len() {
        return None;
    }
    hay.windows(needle.len()).position(|w| w == needle)
}

/// `ERR n` → n. `Err(())` for an `ERR` line whose number does not parse.
// A `Result` with a unit error keeps "not a status line" apart from "a status line without a
// number" without another type.
fn status_line(line: &str) -> Option<Result<u32, ()>> {
    let rest = line.strip_prefix("ERR ")?;
    Some(rest.trim().parse::<u32>().map_err(|_| ()))
}

impl HostCore {
    /// A host in supervisory mode, waiting for nothing.
    pub fn new(framing: Framing) -> HostCore {
        HostCore {
            framing,
            mode: HostMode::Supervisory,
            layout: None,
            pending_layout: None,
            waiting: Await::Nothing,
            rx: Vec::new(),
            discarded: 0,
        }
    }

    /// Supervisory or RealTime.
    pub fn mode(&self) -> HostMode {
        self.mode
    }

    /// The layouts of the loop, in RealTime mode.
    pub fn layout(&self) -> Option<&RtLayout> {
        self.layout.as_ref()
    }

    /// Whether an answer is awaited.
    pub fn is_waiting(&self) -> bool {
        self.waiting != Await::Nothing
    }

    /// Whether the echo of the command in progress has arrived whole (and matches): the
    /// hand has the line and is running it.
    pub fn echo_received(&self) -> bool {
        match &self.waiting {
            Await::Reply { echo } | Await::Loop { echo } => self.rx.starts_with(echo),
            _ => false,
        }
    }

    /// Unsolicited bytes thrown away so far (bytes left over when a new request started).
    pub fn discarded(&self) -> u64 {
        self.discarded
    }

    fn begin(&mut self, waiting: Await) {
        self.discarded += self.rx.len() as u64;
        self.rx.clear();
        self.waiting = waiting;
    }

    fn check_line(&self, line: &str) -> Result<(), Misuse> {
        let b = line.as_bytes();
        if b.contains(&self.framing.terminator) || b.contains(&self.framing.abort) {
            return Err(Misuse::ControlInLine { line: line.to_string() });
        }
        Ok(())
    }

    /// A supervisory command: returns the bytes to send (`line` + CR).
    pub fn command(&mut self, line: &str) -> Result<Vec<u8>, Misuse> {
        if self.mode == HostMode::RealTime {
            return Err(Misuse::InRealTime { line: line.to_string() });
        }
        self.check_line(line)?;
        self.begin(Await::Reply { echo: line.as_bytes().to_vec() });
        let mut out = line.as_bytes().to_vec();
        out.push(self.framing.terminator);
        Ok(out)
    }

    /// A `LOOP` command whose loop will have `layout`: the bytes to send.
    pub fn start_loop(&mut self, line: &str, layout: RtLayout) -> Result<Vec<u8>, Misuse> {
        let out = self.command(line)?;
        self.waiting = Await::Loop { echo: line.as_bytes().to_vec() };
        self.pending_layout = Some(layout);
        Ok(out)
    }

    /// A RealTime block: `control`'s header and, for `C`/`c`, its values, one for each field
    /// of the loop's control layout (a header without data sends no values). A control that
    /// lacks a field of the layout, or whose value does not fit its field, is a
    /// [`Misuse::Block`]. Use [`HostCore::abort`] for ^C.
    pub fn block(&mut self, control: &Control) -> Result<Vec<u8>, Misuse> {
        let Some(layout) = &self.layout else {
            return Err(Misuse::NotInRealTime);
        };
        if self.mode != HostMode::RealTime {
            return Err(Misuse::NotInRealTime);
        }
        let header = control.header;
        let mut out = Vec::with_capacity(layout.control().size());
        match header {
            ControlHeader::Abort => return Ok(self.abort()),
            h if h.has_data() => control.emit(layout.control(), &mut out).map_err(Misuse::Block)?,
            h => out.push(h.byte()),
        }
        self.begin(if header.wants_feedback() { Await::Feedback } else { Await::Ack });
        Ok(out)
    }

    /// ^C: stops motion or leaves the loop; the answer is a prompt. The echo of a command in
    /// progress is dropped first.
    pub fn abort(&mut self) -> Vec<u8> {
        if let Await::Reply { echo } | Await::Loop { echo } = &self.waiting
            && self.rx.starts_with(echo)
        {
            let n = echo.len();
            self.rx.drain(..n);
        }
        self.begin(Await::Prompt { lenient: false });
        vec![self.framing.abort]
    }

    /// A bare CR that resynchronises: everything up to the next prompt is discarded.
    pub fn sync(&mut self) -> Vec<u8> {
        self.begin(Await::Prompt { lenient: true });
        vec![self.framing.terminator]
    }

    /// ^C that resynchronises whatever the state: everything up to the next prompt is
    /// discarded.
    pub fn sync_abort(&mut self) -> Vec<u8> {
        self.begin(Await::Prompt { lenient: true });
        vec![self.framing.abort]
    }

    /// Waits for a prompt and discards everything before it, without sending anything.
    pub fn expect_prompt(&mut self) {
        self.begin(Await::Prompt { lenient: true });
    }

    /// Forgets the request in progress (after a timeout or a lost link). The mode is kept;
    /// call [`HostCore::sync_abort`] to be sure of it.
    pub fn give_up(&mut self) {
        self.waiting = Await::Nothing;
        self.pending_layout = None;
    }

    /// Bytes from the hand.
    pub fn handle_input(&mut self, bytes: &[u8]) {
        // Keep at most one byte past the limit: enough to report the overflow.
        let room = (MAX_REPLY + 1).saturating_sub(self.rx.len());
        self.rx.extend_from_slice(&bytes[..bytes.len().min(room)]);
    }

    fn fail(&mut self, v: Violation) -> Result<Option<Answer>, Violation> {
        self.waiting = Await::Nothing;
        self.pending_layout = None;
        self.rx.clear();
        Err(v)
    }

    fn no_line_break(&mut self, at: usize) -> Result<Option<Answer>, Violation> {
        let got = self.rx[..self.rx.len().min(200)].to_vec();
        self.fail(Violation::MissingLineBreak { at, got })
    }

    /// A finished request: nothing awaited any more.
    fn done(&mut self, answer: Answer) -> Result<Option<Answer>, Violation> {
        self.waiting = Await::Nothing;
        self.pending_layout = None;
        Ok(Some(answer))
    }

    /// The answer, if complete: `Ok(None)` while more bytes are needed, a [`Violation`] when
    /// the bytes cannot be a GCL answer to the request.
    pub fn poll(&mut self) -> Result<Option<Answer>, Violation> {
        if self.rx.len() > MAX_REPLY && self.waiting != Await::Nothing {
            return self.fail(Violation::TooLong { limit: MAX_REPLY });
        }
        match self.waiting.clone() {
            Await::Nothing => Ok(None),
            Await::Reply { echo } | Await::Loop { echo } => {
                let k = self.rx.len().min(echo.len());
                if self.rx[..k] != echo[..k] {
                    let got = self.rx[..self.rx.len().min(echo.len() + 16)].to_vec();
                    return self.fail(Violation::EchoMismatch { sent: echo, got });
                }
                if self.rx.len() < echo.len() {
                    return Ok(None);
                }
                let is_loop = matches!(self.waiting, Await::Loop { .. });
                if is_loop && self.rx.get(echo.len()) == Some(&FEEDBACK_HEADER) {
                    self.rx.drain(..echo.len() + 1);
                    self.waiting = Await::Nothing;
                    self.mode = HostMode::RealTime;
                    self.layout = self.pending_layout.take();
                    return Ok(Some(Answer::LoopStarted));
                }
                match self.lines(echo.len()) {
                    Lines::Partial => Ok(None),
                    Lines::Bad(at) => self.no_line_break(at),
                    Lines::Complete { mut lines, used } => {
                        self.rx.drain(..used);
                        if let Some(last) = lines.last()
                            && let Some(code) = status_line(last)
                        {
                            let Ok(code) = code else {
                                let line = last.as_bytes().to_vec();
                                return self.fail(Violation::StatusWithoutNumber { line });
                            };
                            lines.pop();
                            return self.done(Answer::Refused(Refusal::of(code, lines)));
                        }
                        if is_loop {
                            return self.fail(Violation::LoopNotEntered { lines });
                        }
                        self.done(Answer::Done(lines))
                    }
                }
            }
            Await::Prompt { lenient } => {
                if lenient {
                    let mut end = self.framing.line_ending.clone();
                    end.extend_from_slice(&self.framing.prompt);
                    if self.rx.ends_with(&end) {
                        self.rx.clear();
                        self.waiting = Await::Nothing;
                        self.mode = HostMode::Supervisory;
                        self.layout = None;
                        return Ok(Some(Answer::Prompt(Vec::new())));
                    }
                    // Only the tail can matter; keep the buffer small.
                    if self.rx.len() > 4096 {
                        let cut = self.rx.len() - end.len();
                        self.discarded += cut as u64;
                        self.rx.drain(..cut);
                    }
                    return Ok(None);
                }
                match self.lines(0) {
                    Lines::Partial => Ok(None),
                    Lines::Bad(at) => self.no_line_break(at),
                    Lines::Complete { lines, used } => {
                        self.rx.drain(..used);
                        self.waiting = Await::Nothing;
                        self.mode = HostMode::Supervisory;
                        self.layout = None;
                        Ok(Some(Answer::Prompt(lines)))
                    }
                }
            }
            Await::Feedback | Await::Ack => {
                let Some(&first) = self.rx.first() else { return Ok(None) };
                if first == FEEDBACK_HEADER {
                    if self.waiting == Await::Ack {
                        self.rx.drain(..1);
                        self.waiting = Await::Nothing;
                        return Ok(Some(Answer::Ack));
                    }
                    // `block` waits for feedback only with a layout; without one, wait on.
                    let Some(layout) = &self.layout else { return Ok(None) };
                    let size = layout.feedback().size();
                    if self.rx.len() < size {
                        return Ok(None);
                    }
                    return match Feedback::parse(layout.feedback(), &self.rx[..size]) {
                        Ok(feedback) => {
                            self.rx.drain(..size);
                            self.waiting = Await::Nothing;
                            Ok(Some(Answer::Feedback(Box::new(feedback))))
                        }
                        Err(error) => {
                            let got = self.rx[..size].to_vec();
                            self.fail(Violation::BadFeedback { error, got })
                        }
                    };
                }
                if self.framing.line_ending.first() == Some(&first) {
                    return match self.lines(0) {
                        Lines::Partial => Ok(None),
                        Lines::Bad(at) => self.no_line_break(at),
                        Lines::Complete { mut lines, used } => {
                            self.rx.drain(..used);
                            // Whatever it said, the hand is back in supervisory mode.
                            self.mode = HostMode::Supervisory;
                            self.layout = None;
                            match lines.last().map(|l| (status_line(l), l.as_bytes().to_vec())) {
                                Some((Some(Ok(code)), _)) => {
                                    lines.pop();
                                    self.done(Answer::Refused(Refusal::of(code, lines)))
                                }
                                Some((Some(Err(())), line)) => self.fail(Violation::StatusWithoutNumber { line }),
                                _ => self.fail(Violation::LoopEndedWithoutStatus { lines }),
                            }
                        }
                    };
                }
                self.fail(Violation::NotABlock { byte: first })
            }
        }
    }

    /// Parses `\n\r<line>`... `\n\r=> ` starting at `from`.
    fn lines(&self, from: usize) -> Lines {
        let eol = &self.framing.line_ending;
        let prompt = &self.framing.prompt;
        let bytes = &self.rx[from.min(self.rx.len())..];
        let mut pos = 0;
        let mut lines = Vec::new();
        loop {
            let rest = &bytes[pos..];
            if rest.len() < eol.len() {
                return if eol.starts_with(rest) { Lines::Partial } else { Lines::Bad(from + pos) };
            }
            if !rest.starts_with(eol) {
                return Lines::Bad(from + pos);
            }
            let body = &rest[eol.len()..];
            if body.starts_with(prompt) {
                return Lines::Complete { lines, used: from + pos + eol.len() + prompt.len() };
            }
            match find(body, eol) {
                Some(i) => {
                    lines.push(String::from_utf8_lossy(&body[..i]).into_owned());
                    pos += eol.len() + i;
                }
                None => return Lines::Partial,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gcl_model::params::ParamStore;
    use gcl_model::{MotorSet, Profile};

    fn core() -> HostCore {
        HostCore::new(Framing::default())
    }

    /// Feeds `bytes` one at a time and returns the first answer or error.
    fn feed(c: &mut HostCore, bytes: &[u8]) -> Result<Option<Answer>, Violation> {
        for (i, b) in bytes.iter().enumerate() {
            c.handle_input(&[*b]);
            let r = c.poll()?;
            if r.is_some() {
                assert_eq!(i + 1, bytes.len(), "complete before the end");
                return Ok(r);
            }
        }
        Ok(None)
    }

    /// Looking again only past [`Framing::prompt_search_start`] of a shorter buffer that held no
    /// prompt finds what a search of the whole buffer finds: every buffer of up to 7 bytes over
    /// the prompt's own bytes and one other, grown a byte at a time, as a recorder reads.
    #[test]
    fn a_search_for_the_prompt_resumed_finds_what_a_whole_search_finds() {
        let f = Framing::default();
        let alphabet = b"\n\r=> x";
        for len in 0..=7u32 {
            for code in 0..alphabet.len().pow(len) {
                let mut c = code;
                let bytes: Vec<u8> = (0..len)
                    .map(|_| {
                        let b = alphabet[c % alphabet.len()];
                        c /= alphabet.len();
                        b
                    })
                    .collect();
                assert_eq!(f.prompt_end(&bytes), find(&bytes, b"\n\r=> ").map(|i| i + 5), "{bytes:?}");
                let mut searched = 0;
                let mut found = None;
                for k in 0..=bytes.len() {
                    found = f.prompt_end_from(&bytes[..k], searched);
                    if found.is_some() {
                        assert_eq!(found, f.prompt_end(&bytes[..k]), "{bytes:?} at {k}");
                        break;
                    }
                    assert_eq!(f.prompt_end(&bytes[..k]), None, "{bytes:?} at {k}");
                    searched = f.prompt_search_start(k).max(searched);
                }
                if found.is_none() {
                    assert_eq!(f.prompt_end(&bytes), None, "{bytes:?}");
                }
            }
        }
    }

    #[test]
    fn command_with_output_and_without() {
        let mut c = core();
        assert_eq!(c.command("FGET DP").unwrap(), b"FGET DP\r");
        assert_eq!(
            feed(&mut c, b"FGET DP\n\r1000 1000 1000 150\n\r=> ").unwrap(),
            Some(Answer::Done(vec!["1000 1000 1000 150".into()]))
        );
        c.command("HI").unwrap();
        assert_eq!(feed(&mut c, b"HI\n\r=> ").unwrap(), Some(Answer::Done(vec![])));
    }

    #[test]
    fn status_and_echo_errors() {
        let mut c = core();
        c.command("FSET DP 99999").unwrap();
        assert_eq!(
            feed(&mut c, b"FSET DP 99999\n\rERR 128\n\r=> ").unwrap(),
            Some(Answer::Refused(Refusal { status: StatusBits::INVALID_VALUE, code: 128, lines: vec![] }))
        );
        c.command("HI").unwrap();
        let e = feed(&mut c, b"HX").unwrap_err();
        assert_eq!(e, Violation::EchoMismatch { sent: b"HI".to_vec(), got: b"HX".to_vec() });
        c.command("HI").unwrap();
        assert!(matches!(feed(&mut c, b"HI\r\n=> "), Err(Violation::MissingLineBreak { at: 2, .. })));
        c.command("HI").unwrap();
        let e = feed(&mut c, b"HI\n\rERR x\n\r=> ").unwrap_err();
        assert_eq!(e, Violation::StatusWithoutNumber { line: b"ERR x".to_vec() });
        assert_eq!(e.to_string(), "status line \"ERR x\" has no number");
        assert_eq!(c.command("A\rB"), Err(Misuse::ControlInLine { line: "A\rB".into() }));
        // Bytes are escaped only when shown.
        assert_eq!(
            Misuse::ControlInLine { line: "A\rB".into() }.to_string(),
            "a command line cannot hold a CR or ^C: \"A\\rB\""
        );
    }

    #[test]
    fn realtime_round() {
        let p = Profile::builtin("seed").unwrap();
        let mut store = ParamStore::defaults(&p);
        for (n, v) in [("LCV", 1), ("LCPG", 0), ("LFV", 0), ("LFS", 0), ("LFAP", 1), ("LFDP", 0)] {
            store.set_unchecked(&p, p.param_id(n).unwrap(), MotorSet::FINGERS, v);
        }
        let layout = RtLayout::compute(&p, &store, MotorSet::FINGERS);
        // A `C` block with LCV for motors 1, 2 and 3.
        let velocities = |v: [i64; 3]| {
            let mut control = Control::new(ControlHeader::DataFeedback);
            for (m, v) in (1..).zip(v) {
                control.motor_mut(m).unwrap().velocity = Some(v);
            }
            control
        };
        let mut c = core();
        assert_eq!(c.block(&Control::new(ControlHeader::Feedback)), Err(Misuse::NotInRealTime));
        c.start_loop("123LOOP", layout).unwrap();
        assert_eq!(feed(&mut c, b"123LOOP*").unwrap(), Some(Answer::LoopStarted));
        assert_eq!(c.mode(), HostMode::RealTime);
        assert!(c.command("FGET P").is_err());
        assert_eq!(c.block(&velocities([55, 0, -1])).unwrap(), b"C\x37\x00\xff");
        // A value that does not fit its field, or a field of the layout the control lacks, is
        // the caller's error: nothing to send.
        assert!(matches!(c.block(&velocities([500, 0, 0])), Err(Misuse::Block(BlockError::Range { value: 500, .. }))));
        let mut two = Control::new(ControlHeader::DataAck);
        two.motor_mut(1).unwrap().velocity = Some(1);
        two.motor_mut(2).unwrap().velocity = Some(1);
        assert!(matches!(c.block(&two), Err(Misuse::Block(BlockError::Missing { motor: Some(3), .. }))));
        // A value for a field the layout does not carry (LCPG is off) is not sent.
        let mut extra = velocities([55, 0, 0]);
        extra.motor_mut(1).unwrap().gain = Some(9);
        assert_eq!(c.block(&extra).unwrap(), b"C\x37\x00\x00");
        let Some(Answer::Feedback(fb)) = feed(&mut c, b"*\x13\x88\x00\x01\xff\xff").unwrap() else {
            panic!("a feedback block of three LFAP fields")
        };
        assert_eq!([1, 2, 3].map(|m| fb.motor(m).absolute_position), [Some(5000), Some(1), Some(65535)]);
        assert_eq!(fb.motor(1).strain, None, "LFS is off");
        c.block(&Control::new(ControlHeader::Ack)).unwrap();
        assert_eq!(feed(&mut c, b"*").unwrap(), Some(Answer::Ack));
        c.block(&Control::new(ControlHeader::Feedback)).unwrap();
        assert!(matches!(feed(&mut c, b"\n\rERR 2048\n\r=> "), Ok(Some(Answer::Refused(Refusal { code: 2048, .. })))));
        assert_eq!(c.mode(), HostMode::Supervisory);
    }

    #[test]
    fn abort_and_sync() {
        let mut c = core();
        assert_eq!(c.abort(), vec![3]);
        assert_eq!(feed(&mut c, b"\n\rERR 16384\n\r=> ").unwrap(), Some(Answer::Prompt(vec!["ERR 16384".into()])));
        c.sync();
        c.handle_input(b"junk\n\rBarrettHand\n\r=> \n\r=> ");
        assert_eq!(c.poll().unwrap(), Some(Answer::Prompt(vec![])));
        assert!(!c.is_waiting());
    }

    #[test]
    fn violations_name_what_the_hand_broke() {
        let p = Profile::builtin("seed").unwrap();
        let layout = RtLayout::compute(&p, &ParamStore::defaults(&p), MotorSet::FINGERS);
        let mut c = core();
        c.start_loop("123LOOP", layout.clone()).unwrap();
        let e = feed(&mut c, b"123LOOP\n\rOK\n\r=> ").unwrap_err();
        assert_eq!(e, Violation::LoopNotEntered { lines: vec!["OK".into()] });
        c.start_loop("123LOOP", layout).unwrap();
        feed(&mut c, b"123LOOP*").unwrap();
        c.block(&Control::new(ControlHeader::Feedback)).unwrap();
        assert_eq!(feed(&mut c, b"?").unwrap_err(), Violation::NotABlock { byte: b'?' });
        c.block(&Control::new(ControlHeader::Feedback)).unwrap();
        let e = feed(&mut c, b"\n\rbye\n\r=> ").unwrap_err();
        assert_eq!(e, Violation::LoopEndedWithoutStatus { lines: vec!["bye".into()] });
        assert_eq!(c.mode(), HostMode::Supervisory);
        c.command("FGET P").unwrap();
        c.handle_input(b"FGET P\n\r");
        c.handle_input(&vec![b'0'; MAX_REPLY]);
        assert_eq!(c.poll(), Err(Violation::TooLong { limit: MAX_REPLY }));
        assert!(!c.is_waiting());
    }

    #[test]
    fn loop_refused() {
        let p = Profile::builtin("seed").unwrap();
        let layout = RtLayout::compute(&p, &ParamStore::defaults(&p), MotorSet::FINGERS);
        let mut c = core();
        c.start_loop("123LOOP", layout).unwrap();
        assert!(matches!(feed(&mut c, b"123LOOP\n\rERR 4\n\r=> "), Ok(Some(Answer::Refused(Refusal { code: 4, .. })))));
        assert_eq!(c.mode(), HostMode::Supervisory);
    }
}
