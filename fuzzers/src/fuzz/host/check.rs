//! The host's side of the protocol, graded clause by clause from the bytes it sends (`gcl
//! check-host`, and every run of `gcl fuzz host`).
//!
//! [`HostChecker`] is fed the host's bytes as the hand reads them and the hand's answers as
//! they go out, and keeps the host-side protocol state: the line being typed, whether an
//! answer is still coming, the RealTime block being sent. It never panics on any bytes and
//! never reads a clock.
//!
//! It follows restarts, takes a lone CR after an answer or a reopen as a resync, and hears from
//! the pty whether the host wrote with answer bytes unread. Violations that follow a misbehaviour
//! are
//! INFO notes unless they are sending before a whole answer (an answer queued behind a held one is
//! not whole either); once the hand sent a prompt or block the host had not asked for (an extra
//! one,
//! a late one it had given up on, or one inside its half-sent line), sending one answer early is an
//! "out of step" note.

use std::collections::VecDeque;
use std::sync::Arc;

use gcl_model::grammar::Line;
use gcl_model::{ControlHeader, Device, Mode, Profile};
use serde::{Deserialize, Serialize};

/// A clause of host conformance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HostClause {
    /// Lines end in a single CR, never LF.
    LineEnding,
    /// Command words, prefixes and values are valid for the profile.
    ValidCommands,
    /// Nothing is sent while an answer is still coming, except ^C.
    WaitsForAnswer,
    /// RealTime blocks have the size the layout demands and a valid header.
    RealtimeBlocks,
    /// The host leaves the RealTime loop before it goes.
    LeavesCleanly,
    /// The host program ends by itself with an accepted exit code, without crashing.
    ExitsCleanly,
}

impl HostClause {
    /// Every clause, in report order.
    pub const ALL: [HostClause; 6] = [
        HostClause::LineEnding,
        HostClause::ValidCommands,
        HostClause::WaitsForAnswer,
        HostClause::RealtimeBlocks,
        HostClause::LeavesCleanly,
        HostClause::ExitsCleanly,
    ];

    /// Its stable id (report case ids are `host-<id>`).
    pub fn id(self) -> &'static str {
        match self {
            HostClause::LineEnding => "line-ending",
            HostClause::ValidCommands => "valid-commands",
            HostClause::WaitsForAnswer => "waits-for-answer",
            HostClause::RealtimeBlocks => "realtime-blocks",
            HostClause::LeavesCleanly => "leaves-cleanly",
            HostClause::ExitsCleanly => "exits-cleanly",
        }
    }

    /// What it demands, one line.
    pub fn title(self) -> &'static str {
        match self {
            HostClause::LineEnding => "command lines end in a single CR, never LF",
            HostClause::ValidCommands => "command words, prefixes and values are valid for the profile",
            HostClause::WaitsForAnswer => "nothing is sent while an answer is still coming, except ^C",
            HostClause::RealtimeBlocks => "RealTime control blocks have the layout's size and a valid header",
            HostClause::LeavesCleanly => "the host leaves the RealTime loop before it goes",
            HostClause::ExitsCleanly => "the host exits by itself with an accepted code, without a crash",
        }
    }

    /// The spec clause it rests on (report `clauses`).
    pub fn spec_clause(self) -> &'static str {
        match self {
            HostClause::LineEnding => "decision:framing-line-ending",
            HostClause::ValidCommands => "seed: Command reference",
            HostClause::WaitsForAnswer => "decision:framing-prompt",
            HostClause::RealtimeBlocks => "seed: RealTime Control",
            HostClause::LeavesCleanly => "seed: RealTime Control",
            HostClause::ExitsCleanly => "host: process",
        }
    }
}

/// One thing the host did wrong.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct HostViolation {
    /// The clause broken.
    pub clause: HostClause,
    /// A short, stable description (used in signatures: no byte counts or values that vary).
    pub kind: String,
    /// What exactly, with the bytes escaped.
    pub detail: String,
    /// The hand had misbehaved before it (a fuzzing run): how the host reacted to the hand's
    /// own fault. Only a host that pipelines on regardless is a finding then; the rest is a
    /// note ([`HostViolation::is_note`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub after_misbehaviour: bool,
    /// An early send made after the hand put the host out of step: it had sent a prompt (or
    /// a feedback block) the host had not asked for, an extra one or a late one the host had
    /// given up on, which a host waiting for its answer takes for that answer. Each line the
    /// host sends then comes one answer early through the hand's fault: a note.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub out_of_step: bool,
}

impl HostViolation {
    /// Whether this is an INFO note rather than a finding: it came after the hand misbehaved
    /// and it is no unsafe reaction. Sending before an answer the hand sent whole (sending
    /// before a broken one is not even a violation) stays a finding; a line ending, a command,
    /// a RealTime block or a way of leaving that follows a broken answer, a restart or a
    /// silence is what a host does to get the hand back, or to report it and go.
    pub fn is_note(&self) -> bool {
        self.after_misbehaviour && (self.clause != HostClause::WaitsForAnswer || self.out_of_step)
    }
}

/// An answer made but not yet delivered.
#[derive(Debug, Clone, Copy)]
struct InFlight {
    /// It ends the wait (it ends with the prompt, or it is RealTime feedback).
    ends_wait: bool,
    /// A misbehaviour made it end more than once (a second prompt; a feedback block with more
    /// bytes than the layout's).
    surplus: bool,
    /// The host sent again, giving up on it, before it was delivered: its prompt comes late.
    given_up: bool,
    /// A misbehaviour changed it (a delay holds it, and every answer queued behind it).
    misbehaved: bool,
}

/// Longest line kept for grading (longer lines are graded on their start).
const LINE_CAP: usize = 4096;

/// Most command words kept (the host's path through the protocol); a host that sends more
/// is graded on all of them all the same.
const COMMANDS_CAP: usize = 1000;

/// The host-side protocol state, fed both directions.
#[derive(Debug, Clone)]
pub struct HostChecker {
    profile: Arc<Profile>,
    line: Vec<u8>,
    /// The last line the host ended (with CR), for a message about what followed it.
    last_line: Option<Vec<u8>>,
    /// An LF came while the line under way was being typed (`LF sent`, a host that ends its
    /// lines with LF): the line that never ends with CR is that one bug, not a second.
    lf_in_line: bool,
    /// The last byte the host sent since the hand's last answer reached it or the port was
    /// last opened (for CR CR: a lone CR after an answer or a reopen is a resync).
    prev: Option<u8>,
    /// The host's side of the line still held answer bytes it had not read when it sent the
    /// bytes it sends next: told by the transport (a pty watches the host's reads and writes
    /// in order; TCP sees each write of a host it started as it is made, see
    /// `sim::host_writes`, and otherwise looks at the socket queues when the bytes arrive).
    unread: bool,
    /// The hand has misbehaved in this session.
    misbehaved: bool,
    /// A command line was sent and its answer has not ended yet (its last byte has not been
    /// delivered to the line).
    pending: bool,
    /// Answers made but not yet delivered, oldest first.
    in_flight: VecDeque<InFlight>,
    /// The hand delivered a prompt or a feedback block the host had not asked for (an extra
    /// one a misbehaviour added, or one of an answer the host had given up on): from then on
    /// a host that waits for each answer is one answer ahead of the hand through no fault of
    /// its own, and its early sends are notes.
    out_of_step: bool,
    /// The answer still coming was broken by a misbehaviour: the host may give up on it.
    broken: bool,
    /// The command word of the last line sent.
    last_command: Option<String>,
    /// In RealTime: data bytes still due for the block being sent.
    block_due: usize,
    /// In RealTime: the size of that block.
    block_size: usize,
    /// In RealTime: how many bytes of the block under way came in the host's earlier writes
    /// (`Some` once the block spans a write boundary), and, once it is complete, of the last
    /// block: a host that waits for feedback after a block too short for the layout completes
    /// it with the start of its next block.
    block_split: Option<usize>,
    /// A block that spanned a write boundary was completed by the write being judged now.
    split_completed_now: bool,
    /// The host broke the RealTime block framing (reported once, as its cause): the hand and
    /// the host no longer agree where blocks begin, and what the host sends until the port is
    /// reopened or the hand restarts is judged no further (its later "early" blocks and bad
    /// headers are that one bug's echoes, not new ones).
    desynced: bool,
    /// The mode the hand was in after its last answer.
    mode: Mode,
    /// Command words the host sent, in order.
    commands: Vec<String>,
    violations: Vec<HostViolation>,
    /// Why the host's bytes arrive garbled, once the line said so (a speed mismatch: the
    /// pty's notice, [`HostChecker::garbled_because`]).
    garbled: Option<String>,
}

impl HostChecker {
    /// A checker for a hand of this profile, at the prompt.
    pub fn new(profile: Arc<Profile>) -> HostChecker {
        HostChecker {
            profile,
            line: Vec::new(),
            last_line: None,
            lf_in_line: false,
            prev: None,
            unread: false,
            misbehaved: false,
            pending: false,
            in_flight: VecDeque::new(),
            out_of_step: false,
            broken: false,
            last_command: None,
            block_due: 0,
            block_size: 0,
            block_split: None,
            split_completed_now: false,
            desynced: false,
            mode: Mode::Idle,
            commands: Vec::new(),
            violations: Vec::new(),
            garbled: None,
        }
    }

    /// The line garbles what crosses it from now on (`why`: the pty's speed-mismatch notice,
    /// `the host opened the port at 19200 baud; the hand runs at 9600: ...`): every violation
    /// found after it says so, since the bytes it quotes are not what the host meant.
    pub fn garbled_because(&mut self, why: &str) {
        self.garbled = Some(why.to_string());
    }

    /// A violation's detail, with why the line garbles bytes when it does.
    fn detail(&self, detail: String) -> String {
        match &self.garbled {
            Some(why) => format!("{detail} (speed mismatch: {why})"),
            None => detail,
        }
    }

    /// What the host did wrong so far.
    pub fn violations(&self) -> &[HostViolation] {
        &self.violations
    }

    /// The command words the host sent, in order (its path through the protocol).
    pub fn commands(&self) -> &[String] {
        &self.commands
    }

    /// The protocol state now, for people and for hang signatures.
    pub fn state(&self) -> String {
        let after = self.last_command.as_deref().map(|c| format!(" after {c}")).unwrap_or_default();
        match self.mode {
            Mode::Loop if self.block_due > 0 => format!("RealTime, mid-block{after}"),
            Mode::Loop if self.pending => format!("RealTime, awaiting feedback{after}"),
            Mode::Loop => format!("RealTime loop{after}"),
            _ if self.pending => format!("awaiting the answer{after}"),
            _ if !self.line.is_empty() => format!("mid-line{after}"),
            _ => format!("at the prompt{after}"),
        }
    }

    /// The name of the answer the hand is about to send, `bytes` (for misbehaviour reports):
    /// by the command its echo names, else the host's last command (a host that sent its next
    /// line before this answer came has a last command this answer is not to).
    pub fn answer_state(&self, device: &Device, bytes: &[u8]) -> String {
        // The answer to LOOP itself is the last supervisory one (the loop starts after it).
        if device.mode() == Mode::Loop && self.mode == Mode::Loop {
            return "RealTime feedback".to_string();
        }
        let echo = bytes.split(|b| *b == b'\n').next().unwrap_or_default();
        if !echo.is_empty()
            && let Ok(Line::Command(c)) = gcl_model::parse_line(&self.profile, echo)
        {
            let canon = c.to_line(&self.profile);
            let word =
                canon.split_whitespace().next().unwrap_or_default().trim_start_matches(|c: char| c.is_ascii_digit());
            return format!("answer to {word}");
        }
        match &self.last_command {
            Some(c) => format!("answer to {c}"),
            None => "answer to an empty line".to_string(),
        }
    }

    fn violate(&mut self, clause: HostClause, kind: &str, detail: String) {
        // One of each kind per session is enough to grade and to deduplicate.
        if !self.violations.iter().any(|v| v.clause == clause && v.kind == kind) {
            let after_misbehaviour = self.misbehaved;
            let detail = self.detail(detail);
            self.violations.push(HostViolation {
                clause,
                kind: kind.to_string(),
                detail,
                after_misbehaviour,
                out_of_step: false,
            });
        }
    }

    /// The host sent before the answer it waits for had come ([`HostChecker::sends_early`]):
    /// pipelining, or, once the hand put it out of step, one answer early through the
    /// hand's fault (a note, under its own kind).
    fn early(&mut self, kind: &str, detail: String) {
        if self.desynced {
            // The host's own broken framing, reported once, put it out of step.
            return;
        }
        if !self.out_of_step {
            return self.violate(HostClause::WaitsForAnswer, kind, detail);
        }
        let kind = format!("{kind}, out of step");
        if !self.violations.iter().any(|v| v.clause == HostClause::WaitsForAnswer && v.kind == kind) {
            self.violations.push(HostViolation {
                clause: HostClause::WaitsForAnswer,
                kind,
                detail: self.detail(format!(
                    "{detail}, after the hand sent a prompt or block it had not asked for (an extra one, or a late \
                     one it had given up on), which it took for this answer"
                )),
                after_misbehaviour: true,
                out_of_step: true,
            });
        }
    }

    /// The host's side of the line holds answer bytes it has not read (`true`), as the
    /// transport saw just before the host bytes it passes next: sending then is sending
    /// before the answer, however fast the line delivered it.
    pub fn host_unread(&mut self, unread: bool) {
        self.unread = unread;
    }

    /// Host bytes as the hand reads them.
    pub fn host_bytes(&mut self, device: &Device, bytes: &[u8]) {
        let mut looping = device.mode() == Mode::Loop || self.mode == Mode::Loop;
        self.split_completed_now = false;
        for &b in bytes {
            // Sending while a broken answer is still coming gives up on it: its prompt, if it
            // comes, comes late.
            if self.pending && self.broken && self.block_due == 0 {
                self.in_flight.iter_mut().for_each(|f| f.given_up = true);
            }
            if looping {
                self.realtime_byte(device, b, &mut looping);
            } else {
                self.supervisory_byte(b);
            }
            self.prev = Some(b);
            // Only the first byte after the look: later ones follow it.
            self.unread = false;
        }
        if looping && self.block_due > 0 && self.block_split.is_none() {
            self.block_split = Some(self.block_size - self.block_due);
        }
    }

    /// Whether the host sends now while an answer is still coming, or with one it has not
    /// read (pipelining), and the answer was whole (a host may give up on a broken one).
    fn sends_early(&self) -> bool {
        (self.pending || (self.unread && self.line.is_empty())) && !self.broken
    }

    fn supervisory_byte(&mut self, b: u8) {
        if b == self.profile.framing.abort {
            self.line.clear();
            self.lf_in_line = false;
            self.pending = true;
            self.broken = true;
            self.last_command = Some("^C".into());
            return;
        }
        if b == b'\n' {
            // Which line it followed: the one being typed, else the one a CR just ended.
            let detail = match (&self.line[..], &self.last_line, self.prev) {
                ([], Some(l), Some(p)) if p == self.profile.framing.terminator => {
                    format!("LF after \"{}\" and its CR", esc(l))
                }
                ([], Some(l), _) => format!("LF after \"{}\"", esc(l)),
                ([], None, _) => "LF before any line".to_string(),
                (line, _, _) => format!("LF after \"{}\"", esc(line)),
            };
            self.lf_in_line |= !self.line.is_empty();
            self.violate(HostClause::LineEnding, "LF sent", detail);
            return;
        }
        if self.sends_early() {
            let answer = match &self.last_command {
                Some(cmd) if !cmd.is_empty() => format!("the answer to {cmd}"),
                _ => "the hand's answer".to_string(),
            };
            self.early("sent before the prompt", format!("byte \"{}\" sent before {answer} had ended", esc(&[b])));
        }
        if b == self.profile.framing.terminator {
            self.end_line();
        } else if self.line.len() < LINE_CAP {
            self.line.push(b);
        }
    }

    fn end_line(&mut self) {
        // LF never enters the line (`host_bytes` grades it apart).
        let text = std::mem::take(&mut self.line);
        self.lf_in_line = false;
        self.last_line = Some(text.clone());
        if text.iter().all(|c| c.is_ascii_whitespace()) {
            if self.prev == Some(self.profile.framing.terminator) {
                self.violate(HostClause::LineEnding, "CR CR", "an empty line (two CRs in a row)".into());
            }
            self.pending = true;
            self.broken = false;
            return;
        }
        match gcl_model::parse_line(&self.profile, &text) {
            Ok(Line::Command(c)) => {
                let canon = c.to_line(&self.profile);
                let word = canon
                    .split_whitespace()
                    .next()
                    .unwrap_or_default()
                    .trim_start_matches(|c: char| c.is_ascii_digit())
                    .to_string();
                self.last_command = Some(word.clone());
                if self.commands.len() < COMMANDS_CAP {
                    self.commands.push(word);
                }
            }
            Ok(Line::Empty) => {}
            Err(r) => {
                let problems: Vec<String> = r.problems.iter().map(|p| p.to_string()).collect();
                self.violate(
                    HostClause::ValidCommands,
                    "invalid command",
                    format!("\"{}\": {}", esc(&text), problems.join("; ")),
                );
                self.last_command =
                    Some(String::from_utf8_lossy(text.split(|c| *c == b' ').next().unwrap_or(&[])).into_owned());
            }
        }
        self.pending = true;
        self.broken = false;
    }

    fn realtime_byte(&mut self, device: &Device, b: u8, looping: &mut bool) {
        if self.block_due > 0 {
            self.block_due -= 1;
            self.split_completed_now = self.block_due == 0 && self.block_split.is_some();
            return;
        }
        if self.sends_early() && b != self.profile.framing.abort && !self.desynced && !self.short_block() {
            self.early(
                "block before feedback",
                format!("header \"{}\" sent before the answer to the last block", esc(&[b])),
            );
        }
        match ControlHeader::from_byte(b) {
            Some(ControlHeader::Abort) => {
                *looping = false;
                self.mode = Mode::Idle;
                self.pending = true;
                self.broken = false;
                self.last_command = Some("^C".into());
            }
            Some(h) => {
                let size = device.rt_layout().map_or(1, |l| l.control().size());
                self.block_split = None;
                if h.has_data() {
                    self.block_due = size.saturating_sub(1);
                    self.block_size = size;
                }
                self.pending = true;
                self.broken = false;
            }
            None if self.desynced => {}
            None => {
                if !self.short_block() {
                    self.violate(
                        HostClause::RealtimeBlocks,
                        "bad header",
                        format!(
                            "byte \"{}\" where a control block header was due (the block before had {} bytes)",
                            esc(&[b]),
                            self.block_size
                        ),
                    );
                }
                self.desynced = true;
            }
        }
    }

    /// When the last block was completed by the start of the write being judged, which goes
    /// on, and the framing now breaks in it (an early block, a bad header), the host waited
    /// for feedback after a block too short for the layout and then sent its next block: that
    /// is the one violation, and the framing is lost from here on. (A host that writes a block
    /// in two parts and then pipelines the next block in a third write is not taken for it:
    /// the break is not in the write that completed the block.) Whether it was so (and
    /// reported).
    fn short_block(&mut self) -> bool {
        let Some(got) = self.block_split.filter(|_| self.split_completed_now) else {
            return false;
        };
        self.violate(
            HostClause::RealtimeBlocks,
            "short block",
            format!(
                "a write of the host ended {got} bytes into a control block of {} (the layout's size), and its next \
                 write completed that block and went on: the host took {got} bytes for a whole block and waited for \
                 feedback that does not come until the block is whole",
                self.block_size
            ),
        );
        self.desynced = true;
        true
    }

    /// The hand's answer as it is queued for the line (after any misbehaviour); `misbehaved`
    /// when the fuzzer changed it. The wait it ends is over only once it is
    /// [delivered](HostChecker::delivered).
    pub fn hand_bytes(&mut self, device: &Device, bytes: &[u8], misbehaved: bool) {
        self.mode = device.mode();
        if misbehaved {
            self.misbehaved = true;
        }
        // An answer queued behind a misbehaved one still coming (one held back by a delay) is
        // late through the hand's fault too: the host may give up on it.
        let behind = self.in_flight.iter().any(|f| f.misbehaved);
        if misbehaved || behind {
            self.broken = true;
        }
        if bytes.is_empty() {
            return;
        }
        let prompt = self.profile.framing.prompt.as_bytes();
        let looping = self.mode == Mode::Loop;
        // Only a misbehaviour makes an answer end twice (a host that pipelines gets several
        // answers at once, each its own).
        // A prompt the host did not ask for: a second one in an answer, or one that comes while
        // the host's line is half-sent (appended to its echo, or a restart's power-up prompt):
        // the rest of its line then gets a prompt of its own.
        let surplus = misbehaved
            && if looping {
                device.rt_layout().is_some_and(|l| bytes.len() > l.feedback().size())
            } else {
                let prompts =
                    if prompt.is_empty() { 0 } else { bytes.windows(prompt.len()).filter(|w| *w == prompt).count() };
                prompts > 1 || (prompts == 1 && !self.line.is_empty())
            };
        self.in_flight.push_back(InFlight {
            ends_wait: looping || bytes.ends_with(prompt),
            surplus,
            given_up: false,
            misbehaved: misbehaved || behind,
        });
    }

    /// The last byte of the oldest answer not yet delivered has been handed to the line (for a
    /// paced line, once its wire time has passed): host bytes read before this are judged as
    /// sent while that answer was still coming, whatever the order the hand made them in.
    pub fn delivered(&mut self) {
        if let Some(f) = self.in_flight.pop_front() {
            if f.ends_wait {
                self.pending = false;
            }
            self.out_of_step |= f.surplus || (f.given_up && f.ends_wait);
        }
        self.prev = None;
    }

    /// The answers not yet delivered were discarded (the host went away).
    pub fn discarded(&mut self) {
        self.in_flight.clear();
        self.pending = false;
        // Nothing stale is left for the host to take for an answer.
        self.out_of_step = false;
    }

    /// A host opened the port (`true`) or the last one closed it: a CR that follows is a
    /// fresh start, not the second of two.
    pub fn connection(&mut self, _open: bool) {
        self.prev = None;
        self.desynced = false;
    }

    /// The hand restarted while answering (the answer just queued ends with its power-up
    /// output): it is in supervisory mode, at the prompt once that output is delivered, with
    /// no line or block under way, whatever mode it was in.
    pub fn restarted(&mut self) {
        self.mode = Mode::Idle;
        self.block_due = 0;
        self.block_size = 0;
        self.block_split = None;
        self.desynced = false;
        self.line.clear();
        self.lf_in_line = false;
        self.misbehaved = true;
        self.broken = true;
    }

    /// The host is gone: grades how it left when it `left` by itself (a host killed for
    /// hanging did not leave, and a line or loop it was in the middle of says nothing of
    /// how it leaves). A control block it left short is graded either way: a host that
    /// waits for feedback after a short block waits for ever.
    pub fn finish(&mut self, left: bool) {
        if self.block_due > 0 {
            self.violate(
                HostClause::RealtimeBlocks,
                "short block",
                format!("the last control block lacks {} of its {} bytes", self.block_due, self.block_size),
            );
        }
        if !left {
            return;
        }
        if self.mode == Mode::Loop {
            self.violate(
                HostClause::LeavesCleanly,
                "left in RealTime",
                "the host went away with the hand in its RealTime loop".into(),
            );
        }
        if !self.line.is_empty() && !self.lf_in_line {
            // A line must end in CR: the last one too (framing, not RealTime). One ended with
            // LF is already `LF sent`.
            self.violate(
                HostClause::LineEnding,
                "unterminated line",
                format!("\"{}\" never ended with CR", esc(&self.line)),
            );
        }
    }
}

impl HostChecker {
    /// The host is in the middle of a line already longer than any the hand takes: it is
    /// sending (a flood), even while it is blocked in a write the hand's line rate holds up.
    pub fn overlong_pending(&self) -> bool {
        self.line.len() > self.profile.framing.max_line
    }

    /// The host was stopped before it ended (`how`: `the run budget stopped the host`): a line
    /// it was sending that already runs past the longest line the hand takes is graded as a
    /// line that never ends, as when such a host leaves by itself ([`HostChecker::finish`]); a
    /// shorter one may have been about to end.
    pub fn cut_off(&mut self, how: &str) {
        if self.overlong_pending() {
            self.violate(
                HostClause::LineEnding,
                "unterminated line",
                format!("\"{}\" ran past the hand's longest line and had not ended when {how}", esc(&self.line)),
            );
        }
    }
}

fn esc(b: &[u8]) -> String {
    gcl_model::escape::escape(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seed hand's checker after the host wrote these chunks, each answered and delivered
    /// before the next, and left by itself.
    fn checked<'a>(host: impl IntoIterator<Item = &'a &'a [u8]>) -> HostChecker {
        let p = Profile::builtin("seed").unwrap();
        let mut d = Device::with_profile(p.clone());
        d.take_output();
        let mut c = HostChecker::new(p);
        for chunk in host {
            c.host_bytes(&d, chunk);
            d.handle_input(d.now(), chunk);
            d.run_until_idle(std::time::Duration::from_secs(100));
            let out = d.take_output();
            c.hand_bytes(&d, &out, false);
            c.delivered();
        }
        c.finish(true);
        c
    }

    fn run(host: &[&[u8]]) -> Vec<HostClause> {
        checked(host).violations().iter().map(|v| v.clause).collect()
    }

    #[test]
    fn a_correct_session_has_no_violation() {
        assert_eq!(run(&[b"\x03", b"FGET DP\r", b"1M 500\r", b"FGET P\r"]), vec![]);
    }

    #[test]
    fn each_clause_is_caught() {
        // One bug, one violation: a line ended with LF is not also a line never ended with CR.
        assert_eq!(run(&[b"FGET DP\n"]), vec![HostClause::LineEnding]);
        assert_eq!(run(&[b"FGET DP\r\n"]), vec![HostClause::LineEnding]);
        assert_eq!(run(&[b"FGET QQ\r"]), vec![HostClause::ValidCommands]);
        assert_eq!(run(&[b"FGET DP\rFGET DP\r"]), vec![HostClause::WaitsForAnswer]);
        assert_eq!(run(&[b"FGET DP"]), vec![HostClause::LineEnding]);
        assert_eq!(run(&[b"HI\r", b"1LOOP\r"]), vec![HostClause::LeavesCleanly]);
        // ^C may interrupt anything.
        assert_eq!(run(&[b"FGET DP\r\x03"]), vec![]);
    }

    /// A host that ends its lines with LF: one violation, `LF sent`, not also `unterminated
    /// line` for the same line (it was two findings); a line with no end at all is still one.
    #[test]
    fn a_line_ended_with_lf_is_one_violation() {
        let kinds = |host: &[&[u8]]| checked(host).violations().iter().map(|v| v.kind.clone()).collect::<Vec<_>>();
        assert_eq!(kinds(&[b"HI\n"]), vec!["LF sent"]);
        assert_eq!(kinds(&[b"HI\nFGET P\n"]), vec!["LF sent"]);
        assert_eq!(kinds(&[b"HI\r", b"FGET P"]), vec!["unterminated line"]);
        assert_eq!(kinds(&[b"HI\n\x03", b"FGET P"]), vec!["LF sent", "unterminated line"]);
    }

    /// An answer is named by the command its echo names: a host that sent `FGET P` before the
    /// answer to HI came had its answer to HI named "answer to FGET".
    #[test]
    fn an_answer_is_named_by_its_echo() {
        let p = Profile::builtin("seed").unwrap();
        let d = Device::with_profile(p.clone());
        let mut c = HostChecker::new(p);
        c.host_bytes(&d, b"HI\rFGET P\r");
        assert_eq!(c.answer_state(&d, b"HI\n\r=> "), "answer to HI");
        assert_eq!(c.answer_state(&d, b"FGET P\n\r0 0 0 0\n\r=> "), "answer to FGET");
        // No echo (a prompt alone): the last command.
        assert_eq!(c.answer_state(&d, b"\n\r=> "), "answer to FGET");
    }

    /// A byte sent early before any command names the hand's answer, not an empty command
    /// (`before the answer to  had ended`).
    #[test]
    fn an_early_byte_before_any_command_names_the_hands_answer() {
        let p = Profile::builtin("seed").unwrap();
        let d = Device::with_profile(p.clone());
        let mut c = HostChecker::new(p);
        c.hand_bytes(&d, b"\n\r=> ", false);
        c.delivered();
        c.host_unread(true);
        c.host_bytes(&d, b"HI\r");
        let v = c.violations();
        assert_eq!(v.len(), 1, "{v:?}");
        assert_eq!(v[0].detail, "byte \"H\" sent before the hand's answer had ended", "{v:?}");
    }

    /// An LF says which line it followed: the one a CR just ended (`"1FGET P" and its CR`), the
    /// one being typed, or none yet.
    #[test]
    fn an_lf_names_the_line_it_followed() {
        let detail = |host: &[&[u8]]| {
            let c = checked(host);
            c.violations().iter().find(|v| v.kind == "LF sent").map(|v| v.detail.clone()).unwrap_or_default()
        };
        assert_eq!(detail(&[b"HI\r", b"1FGET P\r\n"]), "LF after \"1FGET P\" and its CR");
        assert_eq!(detail(&[b"FGET D\nP\r"]), "LF after \"FGET D\"");
        assert_eq!(detail(&[b"\n"]), "LF before any line");
    }

    /// RealTime over motors 1-3 of seed after HI, with velocity control: a control block is a header
    /// and three velocity bytes.
    const RT: &[&[u8]] = &[b"HI\r", b"123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0\r", b"123LOOP\r"];

    fn kinds(host: &[&[u8]]) -> Vec<String> {
        checked(RT.iter().chain(host)).violations().iter().map(|v| format!("{}: {}", v.clause.id(), v.kind)).collect()
    }

    #[test]
    fn a_block_one_byte_short_is_one_violation_named_for_it() {
        let short: &[u8] = b"C\x14\x14";
        assert_eq!(kinds(&[short, short, short, short, b"\x03"]), vec!["realtime-blocks: short block"]);
        // The layout's size is no violation, and pipelining whole blocks stays what it is.
        let whole: &[u8] = b"C\x14\x14\x14";
        assert_eq!(kinds(&[whole, whole, whole, b"\x03"]), Vec::<String>::new());
        assert_eq!(kinds(&[b"C\x14\x14\x14C\x14\x14\x14", b"\x03"]), vec!["waits-for-answer: block before feedback"]);
        // A block written in two parts, then the next one pipelined in a write of its own.
        assert_eq!(
            kinds(&[b"C\x14", b"\x14\x14", b"C\x14\x14\x14C\x14\x14\x14", b"\x03"]),
            vec!["waits-for-answer: block before feedback"]
        );
    }

    const ANSWER: &[u8] = b"FGET P\n\r0 0 0 0\n\r=> ";

    /// The hand appends a second prompt to an answer: a host that waits for each prompt takes
    /// it for the next answer's and sends one answer early from then on, through the hand's
    /// fault (a note). An answer misbehaved otherwise leaves it in step: early is a finding.
    #[test]
    fn an_extra_prompt_puts_the_host_out_of_step_without_a_finding() {
        let p = Profile::builtin("seed").unwrap();
        let d = Device::with_profile(p.clone());
        for (extra, note) in [(&b"\n\r=> "[..], true), (&b"\n\r"[..], false)] {
            let mut c = HostChecker::new(p.clone());
            c.host_bytes(&d, b"FGET P\r");
            c.hand_bytes(&d, &[ANSWER, extra].concat(), true);
            c.delivered();
            c.host_bytes(&d, b"FGET P\r");
            c.hand_bytes(&d, ANSWER, false);
            // Sent on the stale prompt, before this answer came.
            c.host_bytes(&d, b"FGET P\r");
            let v = c.violations();
            assert_eq!(v.len(), 1, "{v:?}");
            assert_eq!((v[0].clause, v[0].is_note()), (HostClause::WaitsForAnswer, note), "{v:?}");
        }
    }

    /// The hand sends a prompt while the host's line is half-sent (a restart's power-up
    /// prompt, or one appended to the echo): it answers the half line, the rest of the line
    /// gets a prompt of its own, and a host that waits for each prompt goes on one answer
    /// early through the hand's fault (a note). A restart after the whole line leaves it in
    /// step: early is a finding.
    #[test]
    fn a_prompt_inside_the_hosts_line_puts_it_out_of_step_without_a_finding() {
        let p = Profile::builtin("seed").unwrap();
        let d = Device::with_profile(p.clone());
        let power_up = &b"\n\rBarrettHand Firmware\n\r=> "[..];
        for (first, answer, restart, rest, note) in [
            (&b"HI"[..], power_up, true, &b"\r"[..], true),
            (b"HI", b"HI\n\r=> ", false, b"\r", true),
            (b"HI\r", power_up, true, b"", false),
        ] {
            let mut c = HostChecker::new(p.clone());
            c.host_bytes(&d, first);
            c.hand_bytes(&d, answer, true);
            if restart {
                c.restarted();
            }
            c.delivered();
            if !rest.is_empty() {
                c.host_bytes(&d, rest);
                c.hand_bytes(&d, b"\n\r=> ", false);
            }
            c.host_bytes(&d, b"FGET P\r");
            c.hand_bytes(&d, ANSWER, false);
            // Sent on the stale prompt, before this answer came.
            c.host_bytes(&d, b"FGET P\r");
            let v = c.violations();
            let early: Vec<_> = v.iter().filter(|x| x.clause == HostClause::WaitsForAnswer).collect();
            assert_eq!(early.len(), 1, "{v:?}");
            assert_eq!(early[0].is_note(), note, "{v:?}");
        }
    }

    /// The hand holds an answer back past the host's timeout: the host gives up and sends
    /// again (no violation), the answer queued behind the held one is late too (giving up on
    /// it is no violation either), and once the late prompt comes the host is out of step.
    #[test]
    fn a_late_answer_puts_the_host_out_of_step_without_a_finding() {
        let p = Profile::builtin("seed").unwrap();
        let d = Device::with_profile(p.clone());
        let mut c = HostChecker::new(p);
        c.host_bytes(&d, b"FGET P\r");
        c.hand_bytes(&d, ANSWER, true);
        c.host_bytes(&d, b"FGET P\r");
        c.hand_bytes(&d, ANSWER, false);
        c.host_bytes(&d, b"FGET P\r");
        assert_eq!(c.violations(), &[], "giving up on a held answer and on the one behind it");
        c.hand_bytes(&d, ANSWER, false);
        (0..3).for_each(|_| c.delivered());
        c.host_bytes(&d, b"FGET P\r");
        c.hand_bytes(&d, ANSWER, false);
        // Sent on a late prompt, before this answer came.
        c.host_bytes(&d, b"FGET P\r");
        let v = c.violations();
        assert!(v.len() == 1 && v[0].is_note() && v[0].out_of_step, "{v:?}");
    }

    /// The hand restarts while the host's line is under way (its CR still to come, as from a
    /// host that writes a command and its CR apart): the rest of the line reaches the new hand
    /// as a line of its own, and the prompt that answers it is one the host never asked for
    /// (it took the power-up prompt for its line's answer), so its next line goes out one
    /// answer early through the hand's fault: a note. A restart between lines leaves the host
    /// in step.
    #[test]
    fn a_restart_that_cuts_the_hosts_line_puts_it_out_of_step_without_a_finding() {
        let p = Profile::builtin("seed").unwrap();
        let d = Device::with_profile(p.clone());
        let power_up: &[u8] = b"FGET \n\rBarrettHand Firmware\n\r=> ";
        let mut c = HostChecker::new(p.clone());
        c.host_bytes(&d, b"FGET DP");
        c.hand_bytes(&d, power_up, true);
        c.restarted();
        c.delivered();
        c.host_bytes(&d, b"\r");
        c.hand_bytes(&d, b"\n\r=> ", false);
        c.host_unread(true);
        c.host_bytes(&d, b"1M 5000\r");
        let v = c.violations();
        assert!(v.len() == 1 && v[0].is_note() && v[0].out_of_step, "{v:?}");
        // The restart came after the whole line: its power-up prompt is the line's answer.
        let mut c = HostChecker::new(p);
        c.host_bytes(&d, b"FGET DP\r");
        c.hand_bytes(&d, power_up, true);
        c.restarted();
        c.delivered();
        c.host_bytes(&d, b"1M 5000\r");
        c.hand_bytes(&d, b"1M 5000\n\r=> ", false);
        c.host_bytes(&d, b"FGET P\r");
        let v = c.violations();
        assert!(v.len() == 1 && !v[0].is_note(), "pipelining after a restart stays a finding: {v:?}");
    }

    #[test]
    fn an_answer_made_but_not_yet_delivered_is_still_coming() {
        let p = Profile::builtin("seed").unwrap();
        let d = Device::with_profile(p.clone());
        let mut c = HostChecker::new(p);
        c.host_bytes(&d, b"FGET DP\r");
        c.hand_bytes(&d, b"FGET DP\n\r1000 1000 1000 150\n\r=> ", false);
        c.host_bytes(&d, b"F");
        assert_eq!(c.violations()[0].clause, HostClause::WaitsForAnswer);
        let mut c = HostChecker::new(Profile::builtin("seed").unwrap());
        c.host_bytes(&d, b"FGET DP\r");
        c.hand_bytes(&d, b"FGET DP\n\r1000 1000 1000 150\n\r=> ", false);
        c.delivered();
        c.host_bytes(&d, b"FGET P\r");
        assert!(c.violations().is_empty(), "{:?}", c.violations());
    }
}
