//! The host side of GCL as a sans-IO state machine: it builds the bytes of each request and
//! recognises the hand's answer in whatever pieces it arrives, like `httparse`: `Ok(None)`
//! means "need more bytes", an `Err` means the bytes cannot be a GCL answer.
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
use gcl_model::realtime::{ControlHeader, FEEDBACK_HEADER};
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
}

impl Default for Framing {
    fn default() -> Framing {
        Framing { terminator: b'\r', line_ending: b"\n\r".to_vec(), prompt: b"=> ".to_vec(), abort: 3 }
    }
}

/// A complete answer from the hand.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Reply {
    /// A supervisory command finished without a status; its output lines.
    Lines(Vec<String>),
    /// `LOOP` was answered with `*`: the hand is in RealTime mode.
    LoopStarted,
    /// A feedback block, one value per field of the feedback layout.
    Feedback(Vec<i64>),
    /// `*` alone (after `c` or `a`).
    Ack,
    /// A prompt after ^C or a bare CR, with the lines before it (such as `ERR 16384`).
    Prompt(Vec<String>),
}

/// Why bytes from the hand are not the answer expected, or why a request cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProtocolError {
    /// The hand answered `ERR n`: it understood the framing and refused or failed.
    #[error("the hand answered ERR {code}")]
    Status {
        /// The status bits (bits GCL does not define are dropped here, kept in `code`).
        status: StatusBits,
        /// The number on the wire.
        code: u32,
        /// Output lines before the `ERR` line.
        lines: Vec<String>,
    },
    /// The echo differs from the line sent.
    #[error("echo mismatch: sent \"{sent}\", the hand echoed \"{got}\"")]
    EchoMismatch {
        /// The line sent, escaped.
        sent: String,
        /// What came back, escaped.
        got: String,
    },
    /// The bytes fit no GCL framing.
    #[error("framing error: {detail}; received \"{got}\"")]
    Framing {
        /// What is wrong.
        detail: String,
        /// What was received, escaped.
        got: String,
    },
    /// The request does not fit the state (a command in RealTime mode, a block outside it,
    /// a value that does not fit its field, a line holding a CR).
    #[error("{0}")]
    Usage(String),
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
    Complete { lines: Vec<String>, used: usize },
    Bad(String),
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() || hay.len() < needle.len() {
        return None;
    }
    hay.windows(needle.len()).position(|w| w == needle)
}

/// `ERR n` → n. `Err(())` for an `ERR` line whose number does not parse.
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

    fn check_line(&self, line: &str) -> Result<(), ProtocolError> {
        let b = line.as_bytes();
        if b.contains(&self.framing.terminator) || b.contains(&self.framing.abort) {
            return Err(ProtocolError::Usage(format!(
                "a command line cannot hold a CR or ^C: \"{}\"",
                escape(line.as_bytes())
            )));
        }
        Ok(())
    }

    /// A supervisory command: returns the bytes to send (`line` + CR).
    pub fn command(&mut self, line: &str) -> Result<Vec<u8>, ProtocolError> {
        if self.mode == HostMode::RealTime {
            return Err(ProtocolError::Usage(format!("`{line}`: the hand is in RealTime mode; abort the loop first")));
        }
        self.check_line(line)?;
        self.begin(Await::Reply { echo: line.as_bytes().to_vec() });
        let mut out = line.as_bytes().to_vec();
        out.push(self.framing.terminator);
        Ok(out)
    }

    /// A `LOOP` command whose loop will have `layout`: the bytes to send.
    pub fn start_loop(&mut self, line: &str, layout: RtLayout) -> Result<Vec<u8>, ProtocolError> {
        let out = self.command(line)?;
        self.waiting = Await::Loop { echo: line.as_bytes().to_vec() };
        self.pending_layout = Some(layout);
        Ok(out)
    }

    /// A RealTime block: `header` and, for `C`/`c`, one value per control field. Use
    /// [`HostCore::abort`] for ^C.
    pub fn block(&mut self, header: ControlHeader, values: &[i64]) -> Result<Vec<u8>, ProtocolError> {
        let Some(layout) = &self.layout else {
            return Err(ProtocolError::Usage("not in RealTime mode: start a loop first".into()));
        };
        if self.mode != HostMode::RealTime {
            return Err(ProtocolError::Usage("not in RealTime mode: start a loop first".into()));
        }
        let mut out = Vec::with_capacity(layout.control.size);
        match header {
            ControlHeader::Abort => return Ok(self.abort()),
            h if h.has_data() => {
                layout.control.encode(h.byte(), values, &mut out).map_err(|e| ProtocolError::Usage(e.to_string()))?
            }
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

    fn fail(&mut self, e: ProtocolError) -> Result<Option<Reply>, ProtocolError> {
        self.waiting = Await::Nothing;
        self.pending_layout = None;
        self.rx.clear();
        Err(e)
    }

    fn framing_error(&mut self, detail: impl Into<String>) -> Result<Option<Reply>, ProtocolError> {
        let got = escape(&self.rx[..self.rx.len().min(200)]);
        self.fail(ProtocolError::Framing { detail: detail.into(), got })
    }

    /// The answer, if complete: `Ok(None)` while more bytes are needed.
    pub fn poll(&mut self) -> Result<Option<Reply>, ProtocolError> {
        if self.rx.len() > MAX_REPLY && self.waiting != Await::Nothing {
            return self.framing_error(format!("answer longer than {MAX_REPLY} bytes"));
        }
        match self.waiting.clone() {
            Await::Nothing => Ok(None),
            Await::Reply { echo } | Await::Loop { echo } => {
                let k = self.rx.len().min(echo.len());
                if self.rx[..k] != echo[..k] {
                    let got = escape(&self.rx[..self.rx.len().min(echo.len() + 16)]);
                    return self.fail(ProtocolError::EchoMismatch { sent: escape(&echo), got });
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
                    return Ok(Some(Reply::LoopStarted));
                }
                match self.lines(echo.len()) {
                    Lines::Partial => Ok(None),
                    Lines::Bad(d) => self.framing_error(d),
                    Lines::Complete { mut lines, used } => {
                        self.rx.drain(..used);
                        self.waiting = Await::Nothing;
                        self.pending_layout = None;
                        if let Some(last) = lines.last()
                            && let Some(code) = status_line(last)
                        {
                            let Ok(code) = code else {
                                return self.framing_error(format!("status line `{last}` has no number"));
                            };
                            lines.pop();
                            return self.fail(ProtocolError::Status {
                                status: StatusBits::from_bits_truncate(code),
                                code,
                                lines,
                            });
                        }
                        if is_loop {
                            return self.framing_error("LOOP was answered with lines but neither `*` nor ERR");
                        }
                        Ok(Some(Reply::Lines(lines)))
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
                        return Ok(Some(Reply::Prompt(Vec::new())));
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
                    Lines::Bad(d) => self.framing_error(d),
                    Lines::Complete { lines, used } => {
                        self.rx.drain(..used);
                        self.waiting = Await::Nothing;
                        self.mode = HostMode::Supervisory;
                        self.layout = None;
                        Ok(Some(Reply::Prompt(lines)))
                    }
                }
            }
            Await::Feedback | Await::Ack => {
                let Some(&first) = self.rx.first() else { return Ok(None) };
                if first == FEEDBACK_HEADER {
                    if self.waiting == Await::Ack {
                        self.rx.drain(..1);
                        self.waiting = Await::Nothing;
                        return Ok(Some(Reply::Ack));
                    }
                    let Some(layout) = &self.layout else {
                        return self.framing_error("feedback without a layout");
                    };
                    let size = layout.feedback.size;
                    if self.rx.len() < size {
                        return Ok(None);
                    }
                    return match layout.feedback.decode(&self.rx[..size]) {
                        Ok((_, values)) => {
                            self.rx.drain(..size);
                            self.waiting = Await::Nothing;
                            Ok(Some(Reply::Feedback(values)))
                        }
                        Err(e) => self.framing_error(format!("bad feedback block: {e}")),
                    };
                }
                if self.framing.line_ending.first() == Some(&first) {
                    return match self.lines(0) {
                        Lines::Partial => Ok(None),
                        Lines::Bad(d) => self.framing_error(d),
                        Lines::Complete { mut lines, used } => {
                            self.rx.drain(..used);
                            // Whatever it said, the hand is back in supervisory mode.
                            self.mode = HostMode::Supervisory;
                            self.layout = None;
                            match lines.last().and_then(|l| status_line(l)) {
                                Some(Ok(code)) => {
                                    lines.pop();
                                    self.fail(ProtocolError::Status {
                                        status: StatusBits::from_bits_truncate(code),
                                        code,
                                        lines,
                                    })
                                }
                                _ => self.framing_error("the loop ended without an ERR line"),
                            }
                        }
                    };
                }
                self.framing_error(format!("expected a feedback header `*`, got byte {first:#04x}"))
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
                return if eol.starts_with(rest) {
                    Lines::Partial
                } else {
                    Lines::Bad(format!("expected a line break \"{}\" at byte {}", escape(eol), from + pos))
                };
            }
            if !rest.starts_with(eol) {
                return Lines::Bad(format!("expected a line break \"{}\" at byte {}", escape(eol), from + pos));
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
    fn feed(c: &mut HostCore, bytes: &[u8]) -> Result<Option<Reply>, ProtocolError> {
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

    #[test]
    fn command_with_output_and_without() {
        let mut c = core();
        assert_eq!(c.command("FGET DP").unwrap(), b"FGET DP\r");
        assert_eq!(
            feed(&mut c, b"FGET DP\n\r1000 1000 1000 150\n\r=> ").unwrap(),
            Some(Reply::Lines(vec!["1000 1000 1000 150".into()]))
        );
        c.command("HI").unwrap();
        assert_eq!(feed(&mut c, b"HI\n\r=> ").unwrap(), Some(Reply::Lines(vec![])));
    }

    #[test]
    fn status_and_echo_errors() {
        let mut c = core();
        c.command("FSET DP 99999").unwrap();
        let e = feed(&mut c, b"FSET DP 99999\n\rERR 128\n\r=> ").unwrap_err();
        assert_eq!(e, ProtocolError::Status { status: StatusBits::INVALID_VALUE, code: 128, lines: vec![] });
        c.command("HI").unwrap();
        assert!(matches!(feed(&mut c, b"HX"), Err(ProtocolError::EchoMismatch { .. })));
        c.command("HI").unwrap();
        assert!(matches!(feed(&mut c, b"HI\r\n=> "), Err(ProtocolError::Framing { .. })));
        assert!(c.command("A\rB").is_err());
    }

    #[test]
    fn realtime_round() {
        let p = Profile::builtin("seed").unwrap();
        let mut store = ParamStore::defaults(&p);
        for (n, v) in [("LCV", 1), ("LCPG", 0), ("LFV", 0), ("LFS", 0), ("LFAP", 1), ("LFDP", 0)] {
            store.set_unchecked(&p, p.param_id(n).unwrap(), MotorSet::FINGERS, v);
        }
        let layout = RtLayout::compute(&p, &store, MotorSet::FINGERS);
        let mut c = core();
        assert!(c.block(ControlHeader::Feedback, &[]).is_err());
        c.start_loop("123LOOP", layout).unwrap();
        assert_eq!(feed(&mut c, b"123LOOP*").unwrap(), Some(Reply::LoopStarted));
        assert_eq!(c.mode(), HostMode::RealTime);
        assert!(c.command("FGET P").is_err());
        assert_eq!(c.block(ControlHeader::DataFeedback, &[55, 0, -1]).unwrap(), b"C\x37\x00\xff");
        assert!(c.block(ControlHeader::DataFeedback, &[500, 0, 0]).is_err());
        c.block(ControlHeader::DataFeedback, &[55, 0, 0]).unwrap();
        assert_eq!(feed(&mut c, b"*\x13\x88\x00\x01\xff\xff").unwrap(), Some(Reply::Feedback(vec![5000, 1, 65535])));
        c.block(ControlHeader::Ack, &[]).unwrap();
        assert_eq!(feed(&mut c, b"*").unwrap(), Some(Reply::Ack));
        c.block(ControlHeader::Feedback, &[]).unwrap();
        assert!(matches!(feed(&mut c, b"\n\rERR 2048\n\r=> "), Err(ProtocolError::Status { code: 2048, .. })));
        assert_eq!(c.mode(), HostMode::Supervisory);
    }

    #[test]
    fn abort_and_sync() {
        let mut c = core();
        assert_eq!(c.abort(), vec![3]);
        assert_eq!(feed(&mut c, b"\n\rERR 16384\n\r=> ").unwrap(), Some(Reply::Prompt(vec!["ERR 16384".into()])));
        c.sync();
        c.handle_input(b"junk\n\rBarrettHand\n\r=> \n\r=> ");
        assert_eq!(c.poll().unwrap(), Some(Reply::Prompt(vec![])));
        assert!(!c.is_waiting());
    }

    #[test]
    fn loop_refused() {
        let p = Profile::builtin("seed").unwrap();
        let layout = RtLayout::compute(&p, &ParamStore::defaults(&p), MotorSet::FINGERS);
        let mut c = core();
        c.start_loop("123LOOP", layout).unwrap();
        assert!(matches!(feed(&mut c, b"123LOOP\n\rERR 4\n\r=> "), Err(ProtocolError::Status { code: 4, .. })));
        assert_eq!(c.mode(), HostMode::Supervisory);
    }
}
