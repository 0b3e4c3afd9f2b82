//! Where a failed case parts from the model, named by the input the model was answering.
//!
//! A case's golden splits the hand's answers by when the host reads them, not by what they
//! answer: after a line sent without waiting, a ^C, or lines queued behind a motion, a step's
//! expectation holds the end of an earlier answer and its own answer spills into the next
//! step. Naming a difference by the step it was read in blames the command after the one that
//! broke.
//!
//! So the model's own run of the case ([`model_run`], over the same simulated wire as the
//! golden's capture) tags every byte it answers with the step whose input came last before the
//! byte was produced: the input it answers. A failure's parting point is carried from the
//! hand's stream to the model's by counting prompts (everything between two prompts has the
//! same shape on both sides), and the tag there names the step; among several lines sent at
//! once, the echo names the line. The signature is then cut to the bug: the command, the
//! parameter or RealTime field (and the motors) it concerns, and the kind of difference:
//!
//! - `value`, `order`: a value of the answer differs, or the values come in another order;
//! - `status`: an `ERR` line where none was expected, none where one was, or another one; the
//!   signature is the status bits missing and extra, not the command, because one bug in
//!   status handling (a parser that refuses lower case, a status that is never reported)
//!   shows on every command it touches;
//! - `framing`: the echo, a line ending, the prompt, a block's header or size;
//! - `missing`: the answer, or one of its lines, never came;
//! - `extra`: more than the answer: a line or a prompt too many, bytes after the last answer,
//!   a flood;
//! - `restart`: a banner nobody asked for; `link`: the link failed.
//!
//! The signature (`FindingSignature`) also names the command before a read that decided its value
//! (`value at FGET after RESET`). Its `key` is what deduplication, groups and baselines compare: a
//! status difference is its bits whatever command shows it. A line whose values hold a relation (a
//! capture, then a value relative to it) is an order when another order of the hand's values fits
//! it with the captures of the steps before; the first answer after the model left the loop within
//! a step (a bad header's prompt) is the loop's exit. This module also owns the step-level
//! signature
//! it falls back on (`step_signature`, `Signature`) and the tokens of a golden line
//! (`expected_tokens`, `is_reordering`, `command_of`).

use std::collections::VecDeque;
use std::ops::RangeInclusive;
use std::sync::Arc;
use std::time::Duration;

use gcl_host::SimLink;
use gcl_host::link::{Link, LinkError};
use gcl_model::grammar::{Line, parse_line};
use gcl_model::realtime::RtLayout;
use gcl_model::spec::CommandKind;
use gcl_model::{Args, MotorSet, Profile};
use gcl_transcript::{Form, Transcript};
use serde::{Deserialize, Serialize};

use crate::replay::{ReplayOutcome, replay};
use crate::suite::Case;

/// The model's run of a case: its answers as one stream, each byte tagged with the step whose
/// input it answers.
#[derive(Debug, Clone, Default)]
pub struct ModelRun {
    /// Every byte the model answered after the first step's input, in order.
    pub stream: Vec<u8>,
    /// For each byte of `stream`, the step (0-based) whose input came last before it.
    pub tags: Vec<u32>,
    /// The RealTime layouts in force when each step's input went out.
    pub layouts: Vec<Option<RtLayout>>,
}

/// Bytes produced before any step's input (the power-up banner the replay drains).
const BEFORE: u32 = u32::MAX;

/// A [`SimLink`] that tags what the model produces with the step whose input came last.
struct Tagging {
    inner: SimLink,
    queue: VecDeque<u8>,
    tags: Vec<u32>,
    step: u32,
    sends: u32,
    layouts: Vec<Option<RtLayout>>,
}

impl Tagging {
    /// Takes what the model has produced so far, tagged with the present step.
    fn pull(&mut self) -> Result<(), LinkError> {
        let mut tmp = Vec::new();
        self.inner.recv(&mut tmp, Duration::ZERO)?;
        self.tag(tmp);
        Ok(())
    }

    fn tag(&mut self, bytes: Vec<u8>) {
        if self.step != BEFORE {
            self.tags.extend(std::iter::repeat_n(self.step, bytes.len()));
        }
        self.queue.extend(bytes);
    }
}

impl Link for Tagging {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.pull()?;
        self.layouts.push(self.inner.device().rt_layout().cloned());
        self.step = self.sends;
        self.sends += 1;
        self.inner.send(bytes)?;
        self.pull()
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        if self.queue.is_empty() {
            let mut tmp = Vec::new();
            self.inner.recv(&mut tmp, timeout)?;
            self.tag(tmp);
        }
        let n = self.queue.len();
        buf.extend(self.queue.drain(..));
        Ok(n)
    }

    fn pause(&mut self, d: Duration) {
        let _ = self.pull();
        self.inner.pause(d);
        let _ = self.pull();
    }

    fn elapsed(&self) -> Duration {
        self.inner.elapsed()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

/// Replays `t` on a fresh unmutated model with the suite's options, tagging its answers. The
/// replay's outcome is returned as the error when it does not pass (no case, then).
pub fn model_run(p: &Arc<Profile>, t: &Transcript) -> Result<ModelRun, Box<ReplayOutcome>> {
    model_run_on(p, crate::suite::model_config(&t.header), t)
}

/// [`model_run`] on a model built from `config` (a hypothesis about another hand: see
/// `fuzz::device::variant`).
pub fn model_run_on(
    p: &Arc<Profile>,
    config: gcl_model::DeviceConfig,
    t: &Transcript,
) -> Result<ModelRun, Box<ReplayOutcome>> {
    let mut link = Tagging {
        inner: SimLink::new(p.clone(), config),
        queue: VecDeque::new(),
        tags: Vec::new(),
        step: BEFORE,
        sends: 0,
        layouts: Vec::new(),
    };
    let out = replay(t, &mut link, &crate::suite::replay_options());
    let ReplayOutcome::Pass(pass) = out else { return Err(Box::new(out)) };
    let stream: Vec<u8> = pass.exchange.iter().flat_map(|e| e.received.iter().copied()).collect();
    // Sends are numbered over the steps that send; map them back to step indices.
    // (the replayer sends nothing for a step whose bytes are empty).
    let sending: Vec<u32> = t
        .steps
        .iter()
        .enumerate()
        .filter(|(_, s)| s.send.as_ref().is_some_and(|h| !h.bytes.is_empty()))
        .map(|(i, _)| i as u32)
        .collect();
    let tags: Vec<u32> = link.tags.iter().map(|n| sending.get(*n as usize).copied().unwrap_or(*n)).collect();
    let mut layouts = vec![None; t.steps.len()];
    for (n, l) in link.layouts.into_iter().enumerate() {
        if let Some(slot) = sending.get(n).and_then(|i| layouts.get_mut(*i as usize)) {
            *slot = l;
        }
    }
    if tags.len() != stream.len() {
        return Ok(ModelRun { stream, tags: Vec::new(), layouts });
    }
    Ok(ModelRun { stream, tags, layouts })
}

/// Where a finding parts from the model, cut to the bug: the command answered, the parameter
/// or RealTime field, the motors, and the kind of difference (see the module documentation).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct FindingSignature {
    /// The command word answered where the hand parts from the model (`FGET`, `^C`, `CR`,
    /// `RealTime block`, or the first word of a line the model refuses).
    pub command: String,
    /// The kind of difference: value, order, status, framing, missing, extra, restart, link.
    pub kind: String,
    /// What the difference concerns: the parameter of a get line or a listing's line (`P`), the
    /// RealTime field (`LFAP`), the status bits (`1024 missing`, `32 extra`), `echo`, `header`,
    /// `flood`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub detail: String,
    /// The motors whose values differ, where that applies (`123`, `4`).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub motors: String,
    /// For a value read back: the command before it that decided the value (the last motion
    /// for a position, the last set, FDEF, FLOAD or RESET for a stored parameter). For a ^C's
    /// status: the motion or loop it stopped, or was sent to stop (shown, not part of the key).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub cause: String,
    /// The transcript step that sent [`cause`](Self::cause) for a value read back, where the
    /// case sent it (not the preamble's own lines alone: any step). Not part of the key, not
    /// saved: the device fuzzer reads the value back just before it to ask the hand whether
    /// the value was already wrong there (see `fuzz::device::probe`).
    #[serde(skip)]
    pub cause_step: Option<usize>,
    /// What explains the whole failure as one bug, confirmed on the model: the case rewritten as
    /// a hand with that bug would take it answers what the hand did (`prefix 123+4`: `G` read
    /// as reaching motor 4 too; `MCV set without effect`). Set by the device fuzzer, which can
    /// rebuild a case (see `fuzz::device`); such a bug shows on every command that reads its
    /// effect back, so the explanation is the key.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub explanation: String,
    /// Where a status difference's bits stand against a `--baseline` that already has them on
    /// some command: `at FGET` where it had them on this command, `elsewhere` on any other
    /// (so they are told apart from the known ones, and stay one finding however many
    /// commands show them); empty without such a baseline. Set by the device fuzzer (see
    /// `fuzz::device::Baseline::qualify`).
    #[serde(skip)]
    pub scope: String,
}

impl FindingSignature {
    /// What deduplication and baselines compare: one bug, one key.
    ///
    /// - a status difference is its bits, whatever command shows it: a hand that refuses a
    ///   line as an unknown command (the bits it adds) whatever else the model says of it, else
    ///   the bits it leaves out, else those it adds;
    /// - a value read back is the command read and the command that decided the value
    ///   (`value at FGET after RESET`), or the parameter when no command before it did;
    /// - values in another order are the command;
    /// - anything else is the command, the kind and the detail (a RealTime field, `echo`);
    /// - a failure the device fuzzer explains as one bug (a prefix, a set without effect) is the
    ///   explanation, whatever shows it.
    ///
    /// The motors are shown, never compared: which motor shows a bug first is the fuzzer's draw.
    pub fn key(&self) -> String {
        if !self.explanation.is_empty() {
            return self.explanation.clone();
        }
        let with = |k: String, d: &str| if d.is_empty() { k } else { format!("{k} {d}") };
        match self.kind.as_str() {
            "status" => {
                let parts: Vec<&str> = self.detail.split(", ").collect();
                let extra = parts.iter().find(|d| d.ends_with(" extra"));
                let missing = parts.iter().find(|d| d.ends_with(" missing"));
                let unknown = extra.is_some_and(|e| {
                    e.trim_end_matches(" extra")
                        .split('+')
                        .any(|b| b == gcl_model::StatusBits::UNKNOWN_COMMAND.bits().to_string())
                });
                let pick = if unknown { extra } else { missing.or(extra) };
                let bits = pick.copied().unwrap_or(self.detail.as_str());
                if self.scope.is_empty() { format!("status {bits}") } else { format!("status {bits} {}", self.scope) }
            }
            "value" if !self.cause.is_empty() => format!("value at {} after {}", self.command, self.cause),
            "order" => format!("order at {}", self.command),
            _ => with(format!("{} at {}", self.kind, self.command), &self.detail),
        }
    }
}

impl std::fmt::Display for FindingSignature {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} at {}", self.kind, self.command)?;
        if !self.detail.is_empty() {
            write!(f, " ({})", self.detail)?;
        }
        if !self.motors.is_empty() {
            write!(f, " motors {}", self.motors)?;
        }
        if !self.cause.is_empty() {
            write!(f, " after {}", self.cause)?;
        }
        if !self.explanation.is_empty() {
            write!(f, ": {}", self.explanation)?;
        }
        Ok(())
    }
}

/// Where the hand's stream parts from the golden: the byte position in the hand's stream of the
/// case's answers, and the stream up to there with what follows as far as it was read.
struct Parting {
    /// The hand's answers, the failing step's as far as it was read.
    hand: Vec<u8>,
    /// The parting byte's position in `hand`.
    at: usize,
    /// Where the failing step's answer begins in `hand`.
    step_start: usize,
}

fn parting(out: &ReplayOutcome) -> Option<Parting> {
    let step = out.failed_step()?;
    let ex = out.exchange();
    let mut hand = Vec::new();
    let mut start = 0;
    for e in ex {
        if e.step == step {
            start = hand.len();
        }
        hand.extend_from_slice(&e.received);
    }
    let off = match out {
        ReplayOutcome::Mismatch(m) => m.offset,
        ReplayOutcome::Timeout(t) => t.offset,
        _ => hand.len() - start,
    };
    Some(Parting { at: (start + off).min(hand.len()), hand, step_start: start })
}

/// The steps of `t` a failed replay's difference concerns (`None` for a pass): from the
/// replay's failing step to the step whose input the model's answer at the parting byte
/// followed (the same step, but where a golden records an answer a step behind its line,
/// after a ^C mid-motion or a queued line). The model's run `run` is of `t`.
pub fn failing_steps(
    p: &Profile,
    t: &Transcript,
    run: &ModelRun,
    out: &ReplayOutcome,
) -> Option<RangeInclusive<usize>> {
    let step = out.failed_step()?;
    let pe = [p.framing.line_ending.as_bytes(), p.framing.prompt.as_bytes()].concat();
    let owner = parting(out)
        .and_then(|pt| carry(&pt.hand, pt.at, &run.stream, &pe))
        .and_then(|x| run.tags.get(x))
        .map(|s| *s as usize)
        .filter(|s| *s < t.steps.len())
        .unwrap_or(step);
    Some(step.min(owner)..=step.max(owner))
}

/// Positions just past each prompt (line ending then prompt) in `s`.
fn prompt_ends(s: &[u8], pe: &[u8]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut i = 0;
    while !pe.is_empty() && i + pe.len() <= s.len() {
        if &s[i..i + pe.len()] == pe {
            i += pe.len();
            out.push(i);
        } else {
            i += 1;
        }
    }
    out
}

/// The model's position for the hand's `at`: as many prompts in, and as many bytes past the
/// last one (no further than the model's next prompt).
fn carry(hand: &[u8], at: usize, model: &[u8], pe: &[u8]) -> Option<usize> {
    let h = prompt_ends(&hand[..at], pe);
    let base_h = h.last().copied().unwrap_or(0);
    let m = prompt_ends(model, pe);
    let base_m = if h.is_empty() { 0 } else { *m.get(h.len() - 1)? };
    let next = m.get(h.len()).copied().unwrap_or(model.len());
    let x = base_m + (at - base_h);
    Some(x.min(next.saturating_sub(1)).min(model.len().checked_sub(1)?))
}

/// The command word of a line as the signature shows it: the model's name for a command it
/// parses, `CR` for an empty line, else the first word without a motor prefix.
pub fn command_word(p: &Profile, line: &[u8]) -> String {
    command_of(line, false, p)
}

/// The signature of a failed replay of a case whose model run is `run`; `None` for a pass.
/// `whole_reads`: the link hands over an answer whole (the in-process sim), so a RealTime
/// answer that ends early or late is known to be of another size.
///
/// Where the hand parts from the model's run → a flood or restart → trailing bytes → a
/// RealTime block's field → the start of an answer (a prompt too many, a loop exit, the echo)
/// → the line of the answer it lies in (status, prompt, line ending, value).
pub fn signature(
    p: &Profile,
    t: &Transcript,
    run: &ModelRun,
    out: &ReplayOutcome,
    whole_reads: bool,
) -> Option<FindingSignature> {
    let step = out.failed_step()?;
    if let ReplayOutcome::Disconnected(_) = out {
        return Some(sig(command_at(p, t, step), "link", ""));
    }
    let Some(s) = Parted::of(p, t, run, out, step) else { return step_fallback(p, t, out) };
    if let Some(found) = s.flood_or_restart().or_else(|| s.trailing()).or_else(|| s.realtime_block(whole_reads)) {
        return Some(found);
    }
    let unit = s.unit();
    Some(s.answer_start(&unit).unwrap_or_else(|| s.in_line(&unit)))
}

/// Without the model's tags (a run whose timing the tagging changed): takes the replay; gives
/// the signature of the step read in.
fn step_fallback(p: &Profile, t: &Transcript, out: &ReplayOutcome) -> Option<FindingSignature> {
    let case = crate::suite::Case { profile: p.id.clone(), transcript: t.clone() };
    let (s, _) = step_signature(&case, out, p)?;
    let kind = match s.kind.as_str() {
        "missing-answer" => "missing",
        "flood" => "extra",
        k => k,
    };
    Some(sig(s.command.clone(), kind, ""))
}

/// Takes a transcript and a step; gives the bytes the step sends (none past the end).
fn sent_of(t: &Transcript, i: usize) -> Vec<u8> {
    t.steps.get(i).and_then(|s| s.send.as_ref()).map(|h| h.bytes.clone()).unwrap_or_default()
}

/// Takes a transcript and a step; gives whether the step sends or expects hex (RealTime).
fn hex_step(t: &Transcript, i: usize) -> bool {
    t.steps.get(i).is_some_and(|s| {
        s.send.as_ref().is_some_and(|h| h.form == Form::Hex) || s.expect.segments.iter().any(|g| g.form == Form::Hex)
    })
}

/// Takes a transcript and a step; gives whether the step sends ^C.
fn is_abort(p: &Profile, t: &Transcript, i: usize) -> bool {
    sent_of(t, i).first() == Some(&p.framing.abort)
}

/// The input a model position answers.
struct Owner {
    /// Its step.
    step: usize,
    /// The line among the step's lines.
    line: Vec<u8>,
    /// Where that line's answer begins in the model's stream.
    answer: usize,
    /// The command word.
    command: String,
}

/// Takes a position `x` in the model's run (`step`: the replay's failing step, for an untagged
/// position); gives the input it answers.
fn owner_of(p: &Profile, t: &Transcript, run: &ModelRun, step: usize, x: usize) -> Owner {
    let owner = run.tags.get(x).map_or(step, |s| *s as usize);
    let (line, a) = owner_line(p, &sent_of(t, owner), run, owner, x);
    let in_loop = run.layouts.get(owner).is_some_and(Option::is_some);
    let block_answer = in_loop && run.stream.get(a) == Some(&gcl_model::realtime::FEEDBACK_HEADER);
    let command = if hex_step(t, owner) || is_abort(p, t, owner) && block_answer {
        "RealTime block".to_string()
    } else if is_abort(p, t, owner) {
        "^C".to_string()
    } else {
        command_word(p, &line)
    };
    Owner { step: owner, line, answer: a, command }
}

/// A failed replay where the hand parts from the model's tagged run: what the signature's
/// stages read.
struct Parted<'a> {
    p: &'a Profile,
    t: &'a Transcript,
    run: &'a ModelRun,
    out: &'a ReplayOutcome,
    /// The replay's failing step.
    step: usize,
    pt: Parting,
    /// A line ending then the prompt.
    pe: Vec<u8>,
    /// The model's position for the parting byte.
    x: usize,
    /// The input the model's answer at `x` answers.
    owner: Owner,
}

/// The model's answer unit holding the parting: from the last prompt before it (or the
/// owner's answer's start) to the next prompt.
struct Unit {
    start: usize,
    end: usize,
    /// The owner's echo's length, when the unit begins with it.
    echo_len: usize,
    /// The unit is the first answer after the model left the loop.
    loop_exit: bool,
}

impl<'a> Parted<'a> {
    /// Takes the failed replay and the model's run; gives where the hand parts from it, or
    /// `None` (no parting byte, or a run without tags).
    fn of(p: &'a Profile, t: &'a Transcript, run: &'a ModelRun, out: &'a ReplayOutcome, step: usize) -> Option<Self> {
        let pt = parting(out)?;
        let fr = &p.framing;
        let pe = [fr.line_ending.as_bytes(), fr.prompt.as_bytes()].concat();
        let x = if run.tags.is_empty() { None } else { carry(&pt.hand, pt.at, &run.stream, &pe) }?;
        let owner = owner_of(p, t, run, step, x);
        Some(Parted { p, t, run, out, step, pt, pe, x, owner })
    }

    /// What the hand sent from the parting byte on.
    fn got(&self) -> &[u8] {
        &self.pt.hand[self.pt.at..]
    }

    /// Gives a flood (whatever it repeats), or a restart (a banner the model does not send).
    fn flood_or_restart(&self) -> Option<FindingSignature> {
        let banner = crate::record::BANNER_TEXT;
        let (got, model_rest) = (self.got(), &self.run.stream[self.x..]);
        // A flood is a flood, whatever it repeats (a banner flooded in answer to ^C is no restart).
        if let ReplayOutcome::Flooded(_) = self.out {
            return Some(sig(self.owner.command.clone(), "extra", "flood"));
        }
        if !model_rest.windows(banner.len()).any(|w| w == banner) && got.windows(banner.len()).any(|w| w == banner) {
            return Some(sig(self.owner.command.clone(), "restart", ""));
        }
        None
    }

    /// Gives bytes after the case's last answer, as extra to the last input.
    fn trailing(&self) -> Option<FindingSignature> {
        if let ReplayOutcome::Mismatch(m) = self.out
            && m.trailing
        {
            let c = owner_of(self.p, self.t, self.run, self.step, self.run.stream.len().saturating_sub(1)).command;
            return Some(sig(c, "extra", ""));
        }
        None
    }

    /// RealTime: a block's answer, by field (or its framing); `None` for any other input.
    fn realtime_block(&self, whole_reads: bool) -> Option<FindingSignature> {
        let Owner { step: owner, answer: a, command, .. } = &self.owner;
        let (owner, a, x, run, pt, out) = (*owner, *a, self.x, self.run, &self.pt, self.out);
        if command != "RealTime block" {
            return None;
        }
        let command = command.clone();
        // Past a prompt the model gave to input sent in the loop (a bad header's status), the
        // model has left the loop: the rest of the step is answered outside it, and a hand
        // that parts there stayed in.
        let sent_in_loop = run.layouts.get(owner).is_some_and(Option::is_some);
        if sent_in_loop && !prompt_ends(&run.stream[a..x], &self.pe).is_empty() {
            return Some(sig(command, "framing", "loop exit"));
        }
        let off = x - a;
        let layout = run.layouts.get(owner).cloned().flatten();
        let Some(fb) = layout.as_ref().map(|l| l.feedback()) else { return Some(sig(command, "framing", "")) };
        let hand_start = pt.at - off.min(pt.at);
        let hand_len = pt.hand.len() - hand_start;
        if matches!(out, ReplayOutcome::Timeout(_)) {
            return Some(sig(command, if hand_len == 0 { "missing" } else { "framing" }, "block"));
        }
        // A block that does not start where the model's does, or ends elsewhere: the hand
        // reads or writes blocks of another layout.
        let model_len = run.tags[a..].iter().take_while(|s| **s as usize == owner).count();
        if off == 0 || whole_reads && hand_len != model_len && model_len == fb.size() {
            return Some(sig(command, "framing", "block"));
        }
        Some(match fb.fields().iter().find(|f| (f.offset()..f.offset() + f.size()).contains(&off)) {
            Some(f) => sig(command, "value", f.name()),
            None if off >= fb.size() => sig(command, "extra", ""),
            None => sig(command, "framing", ""),
        })
    }

    /// Gives the model's answer unit holding the parting, and what its start is.
    fn unit(&self) -> Unit {
        let (p, t, run, x, pe) = (self.p, self.t, self.run, self.x, &self.pe);
        let fr = &p.framing;
        let Owner { step: owner, line, answer: a, .. } = &self.owner;
        let (owner, a) = (*owner, *a);
        let start = prompt_ends(&run.stream[..=x], pe).last().copied().filter(|e| *e <= x).unwrap_or(0).max(a).min(x);
        let end = prompt_ends(&run.stream[start..], pe).first().map_or(run.stream.len(), |e| start + e);
        let echo_len = if fr.echo && start == a && !is_abort(p, t, owner) {
            line.iter().filter(|b| **b != fr.terminator).count()
        } else {
            0
        };
        // The first line of a line's answer, right after an input the model took as leaving
        // RealTime mode: a hand that stayed in the loop takes the line for blocks.
        // (before the first line ending: within the echo. Past it, a status line is the line's
        // own: a CR that gets `ERR 2048` may be a hand still in the loop, or one that errs on
        // empty lines, and only the status tells them apart)
        let first_line = !run.stream[start..x].windows(fr.line_ending.len()).any(|w| w == fr.line_ending.as_bytes());
        let prev_send = (0..owner).rev().find(|i| !sent_of(t, *i).is_empty());
        let in_loop = |i: usize| run.layouts.get(i).is_some_and(Option::is_some);
        let leaves_loop = in_loop(owner) && is_abort(p, t, owner) || !in_loop(owner) && prev_send.is_some_and(in_loop);
        // Likewise for the first answer after the model left the loop within a step's answer: a
        // bad header ends the loop with its status and prompt, and the rest of the line (or the
        // lines sent with it) is answered outside it. Any prompt the model gives to an input sent
        // in the loop is that exit.
        let exits_at = |u: usize| -> bool {
            let Some(k) = u.checked_sub(1).and_then(|i| run.tags.get(i)).map(|k| *k as usize) else { return false };
            let Some(ks) = run.tags.iter().position(|s| *s as usize == k) else { return false };
            in_loop(k) && prompt_ends(&run.stream[ks..u], pe).first() == Some(&(u - ks))
        };
        // A prompt (or a status line) too many at the start of an answer, after which the hand
        // goes on with the model's answer: more than the answer before.
        // (not a status line where the model has just left the loop: a hand still in it refuses
        // the line's first byte as a header)
        let loop_exit = first_line && (start == a && leaves_loop || exits_at(start));
        Unit { start, end, echo_len, loop_exit }
    }

    /// Takes the unit; gives a prompt or status line too many at its start, a loop exit, or a
    /// parting within the echo; `None` past them.
    fn answer_start(&self, u: &Unit) -> Option<FindingSignature> {
        let (fr, run, x, pe, got) = (&self.p.framing, self.run, self.x, &self.pe, self.got());
        if x == u.start && x > 0 && got.starts_with(fr.line_ending.as_bytes()) {
            // (a bare prompt, or one status line and a prompt)
            let bare = got.starts_with(pe);
            let status_line = got[fr.line_ending.len()..].starts_with(b"ERR ") && !u.loop_exit;
            if let Some(mut e) = prompt_ends(got, pe).first().copied().filter(|_| bare || status_line) {
                // (bare prompts may come several: one too many per empty line queued before)
                while bare && got[e..].starts_with(pe) {
                    e += pe.len();
                }
                let after = &got[e..];
                let want = &run.stream[x..u.end.min(x + 4)];
                // (what follows may not have been read yet)
                if !want.is_empty() && after.starts_with(&want[..want.len().min(after.len())]) {
                    let c = owner_of(self.p, self.t, run, self.step, x - 1).command;
                    return Some(sig(c, "extra", ""));
                }
            }
        }
        if u.loop_exit {
            return Some(sig("RealTime block".into(), "framing", "loop exit"));
        }
        if x < u.start + u.echo_len {
            return Some(sig(self.owner.command.clone(), "framing", "echo"));
        }
        None
    }

    /// Takes the unit; gives the signature by the line of the model's answer the parting lies
    /// in against the hand's line there: a status, a missing or extra line, a prompt, a line
    /// ending, an order, or a value.
    fn in_line(&self, u: &Unit) -> FindingSignature {
        let (p, t, run, out, x, pt, step) = (self.p, self.t, self.run, self.out, self.x, &self.pt, self.step);
        let Owner { step: owner, line, answer: a, command } = &self.owner;
        let (owner, a, command) = (*owner, *a, command.clone());
        let fr = &p.framing;
        let got = self.got();
        // The line of the model's answer the parting lies in, and the hand's line there.
        let eol = fr.line_ending.as_bytes();
        let unit = &run.stream[u.start..u.end];
        let rel = (x - u.start).min(unit.len());
        let line_no = if u.start == a { count(&unit[..rel], eol) } else { 0 };
        let m_line = cut_line(&unit[find_back(unit, rel, eol)..], eol);
        let h_line = cut_line(&pt.hand[find_back(&pt.hand, pt.at, eol)..], eol);
        let param = param_at(p, line, line_no, m_line);
        let status_of = |l: &[u8]| -> Option<u64> {
            let s = String::from_utf8_lossy(l);
            let mut w = s.split_whitespace();
            (w.next() == Some("ERR")).then(|| w.next().and_then(|n| n.parse().ok()).unwrap_or(0))
        };
        let (ms, hs) = (status_of(m_line), status_of(h_line));
        if ms.is_some() || hs.is_some() {
            let s = sig(command, "status", &status_detail(ms.unwrap_or(0), hs.unwrap_or(0)));
            // (a ^C's status is about what it stopped, or was to stop: the motion or loop before it)
            let cause = if is_abort(p, t, owner) { stopped_by_abort(p, t, owner) } else { String::new() };
            return FindingSignature { cause, ..s };
        }
        let prompt = fr.prompt.as_bytes();
        let m_rest = &run.stream[x..u.end];
        if let ReplayOutcome::Timeout(to) = out {
            // Stopped short. Only the prompt's tail missing is framing (a prompt without its
            // space); an answer that stops before its prompt lacks part of itself.
            let kind =
                if to.offset > 0 && prompt.ends_with(m_rest) && !m_rest.is_empty() { "framing" } else { "missing" };
            return sig(command, kind, &param);
        }
        let trimmed = prompt.trim_ascii_end();
        let m_is_prompt = m_line.starts_with(trimmed) && !trimmed.is_empty();
        let h_is_prompt = h_line.starts_with(trimmed) && !trimmed.is_empty();
        if m_is_prompt && h_is_prompt {
            return sig(command, "framing", "prompt");
        }
        if m_is_prompt {
            return sig(command, "extra", &param);
        }
        if h_is_prompt {
            return sig(command, "missing", &param);
        }
        let at_eol = |s: &[u8]| s.first().is_some_and(|b| matches!(b, b'\n' | b'\r'));
        if at_eol(got) && at_eol(m_rest) {
            return sig(command, "framing", "line ending");
        }
        // Values: the golden line (with its ranges) against the hand's.
        let ts = |x: &[u8]| String::from_utf8_lossy(x).into_owned();
        let golden = golden_line(t, step, pt, eol).unwrap_or_else(|| ts(m_line));
        let h_text = ts(h_line);
        if is_reordering(&h_text, &golden) || reorders_with_captures(t, out, step, pt, eol) {
            return sig(command, "order", &param);
        }
        let motors = differing_motors(p, line, &h_text, &golden);
        let (cause, cause_step) = cause_of(p, t, owner, line, &param, &motors).unzip();
        FindingSignature { motors, cause: cause.unwrap_or_default(), cause_step, ..sig(command, "value", &param) }
    }
}

fn sig(command: String, kind: &str, detail: &str) -> FindingSignature {
    FindingSignature {
        command: gcl_model::escape::escape(command.as_bytes()),
        kind: kind.to_string(),
        detail: detail.to_string(),
        motors: String::new(),
        cause: String::new(),
        cause_step: None,
        explanation: String::new(),
        scope: String::new(),
    }
}

/// A status difference: the bits the model reports and the hand does not (`missing`), and
/// those the hand reports and the model does not (`extra`).
fn status_detail(model: u64, hand: u64) -> String {
    let bits =
        |v: u64| (0..63).filter(|b| v & (1 << b) != 0).map(|b| (1u64 << b).to_string()).collect::<Vec<_>>().join("+");
    let mut d = Vec::new();
    if model & !hand != 0 {
        d.push(format!("{} missing", bits(model & !hand)));
    }
    if hand & !model != 0 {
        d.push(format!("{} extra", bits(hand & !model)));
    }
    if d.is_empty() {
        d.push("format".into());
    }
    d.join(", ")
}

/// The command before the read that decided the value read: for a position, the last line
/// that moved one of the motors whose values differ (or initialised or reset the hand); for
/// a stored parameter, the last line that set it by name, restored its defaults, loaded it or
/// reset the hand. `None` for other live values (strain, temperature: every read shows their
/// bug, whatever came before) and when no line did; else the command's name and the step that
/// sent it.
fn cause_of(
    p: &Profile,
    t: &Transcript,
    owner: usize,
    line: &[u8],
    param: &str,
    motors: &str,
) -> Option<(String, usize)> {
    let id = p.param_id(param)?;
    let spec = p.param(id);
    let position = p.role(gcl_model::spec::Role::Position) == Some(id);
    if spec.live && !position {
        return None;
    }
    let global = spec.scope == gcl_model::spec::Scope::Global;
    let term = p.framing.terminator;
    let mut lines: Vec<(usize, Vec<u8>)> = Vec::new();
    for (i, s) in t.steps.iter().enumerate().take(owner + 1) {
        let Some(h) = &s.send else { continue };
        if h.form == Form::Hex {
            lines.push((i, b"LOOP".to_vec()));
            continue;
        }
        lines.extend(h.bytes.split(|b| *b == term).map(|l| (i, l.to_vec())));
    }
    // Up to the line answered.
    if let Some(i) = lines.iter().rposition(|(_, l)| l.as_slice() == line) {
        lines.truncate(i);
    }
    let differing = MotorSet::from_motors(motors.bytes().filter_map(|b| b.is_ascii_digit().then_some(b - b'0')));
    for (step, l) in lines.iter().rev() {
        let Ok(Line::Command(c)) = parse_line(p, l) else { continue };
        let k = c.kind(p);
        let decides = if position {
            let moved = c.prefix.unwrap_or(MotorSet::from_bits(0b1111));
            let touches = differing.is_empty() || moved.bits() & differing.bits() != 0;
            matches!(k, CommandKind::Initialize | CommandKind::Loop | CommandKind::Reset) || k.is_motion() && touches
        } else {
            let scoped = if global {
                matches!(k, CommandKind::GlobalDefaults | CommandKind::GlobalLoad)
            } else {
                matches!(k, CommandKind::MotorDefaults | CommandKind::MotorLoad)
            };
            scoped || k == CommandKind::Reset || matches!(&c.args, Args::Pairs(ps) if ps.iter().any(|(i, _)| *i == id))
        };
        if decides {
            return Some((p.command(c.command).name.clone(), *step));
        }
    }
    None
}

/// The motion or LOOP line last sent before step `owner` (a ^C): what it stopped, or was sent
/// to stop; empty when there is none.
fn stopped_by_abort(p: &Profile, t: &Transcript, owner: usize) -> String {
    let term = p.framing.terminator;
    for s in t.steps.iter().take(owner).rev() {
        let Some(h) = &s.send else { continue };
        if h.form == Form::Hex {
            continue;
        }
        for l in h.bytes.split(|b| *b == term).rev() {
            if let Ok(Line::Command(c)) = parse_line(p, l) {
                let k = c.kind(p);
                if k.is_motion() || k == CommandKind::Loop {
                    return p.command(c.command).name.clone();
                }
            }
        }
    }
    String::new()
}

/// The command at step `i` for a link failure: the step's own line.
fn command_at(p: &Profile, t: &Transcript, i: usize) -> String {
    let sent = t.steps.get(i).and_then(|s| s.send.as_ref()).map(|h| h.bytes.clone()).unwrap_or_default();
    command_of(&sent, t.steps.get(i).is_some_and(|s| s.send.as_ref().is_some_and(|h| h.form == Form::Hex)), p)
}

/// Among the lines step `owner` sent, the one whose answer holds model position `x`, and where
/// that answer begins in the model's stream. A line's answer begins with its echo; several
/// lines sent at once are answered in order.
fn owner_line(p: &Profile, sent: &[u8], run: &ModelRun, owner: usize, x: usize) -> (Vec<u8>, usize) {
    let fr = &p.framing;
    let first = run.tags.iter().position(|s| *s as usize == owner).unwrap_or(x).min(x);
    let mut lines: Vec<&[u8]> = sent.split_inclusive(|b| *b == fr.terminator).collect();
    if lines.is_empty() {
        return (Vec::new(), first);
    }
    if lines.len() == 1 || !fr.echo {
        return (strip(lines[0], fr.terminator).to_vec(), first);
    }
    // The last line whose echo begins at or before x, searched in order from the answer's start.
    let mut best = (strip(lines[0], fr.terminator).to_vec(), first);
    let mut from = first;
    let eol = fr.line_ending.as_bytes();
    for (k, l) in lines.drain(..).enumerate() {
        let l = strip(l, fr.terminator);
        if k == 0 {
            continue;
        }
        let mut needle = l.to_vec();
        needle.extend_from_slice(eol);
        let hay = &run.stream[from..=x.min(run.stream.len() - 1)];
        // The echo starts right after a prompt.
        let pe = [eol, fr.prompt.as_bytes()].concat();
        let found = hay.windows(pe.len() + needle.len()).position(|w| w.starts_with(&pe) && w.ends_with(&needle));
        match found {
            Some(i) => {
                let at = from + i + pe.len();
                best = (l.to_vec(), at);
                from = at;
            }
            None => break,
        }
    }
    best
}

fn strip(l: &[u8], term: u8) -> &[u8] {
    l.strip_suffix(&[term]).unwrap_or(l)
}

fn count(hay: &[u8], needle: &[u8]) -> usize {
    if needle.is_empty() {
        return 0;
    }
    hay.windows(needle.len()).filter(|w| *w == needle).count()
}

/// Start of the line holding position `at` (just past the line ending before it).
fn find_back(s: &[u8], at: usize, eol: &[u8]) -> usize {
    let at = at.min(s.len());
    (0..at).rev().find(|&i| s[..=i].ends_with(eol)).map_or(0, |i| i + 1)
}

/// The line starting at `s`, up to its line ending (or the end).
fn cut_line<'s>(s: &'s [u8], eol: &[u8]) -> &'s [u8] {
    let end = s.windows(eol.len().max(1)).position(|w| w == eol).unwrap_or(s.len());
    &s[..end]
}

/// Whether the hand's line at the parting, its values put in another order, is what the step
/// expects given the values the steps before it captured. A line that holds a relation between
/// its values (`{int as p1} {int p1*557/100 +-11%}`) read back in another order captures the
/// wrong value first, so its golden text, resolved against the hand's values, no longer shows
/// the order [`is_reordering`] looks for. Tries every order of up to six values, else the
/// reversed one.
fn reorders_with_captures(t: &Transcript, out: &ReplayOutcome, step: usize, pt: &Parting, eol: &[u8]) -> bool {
    let Some(expect) = t.steps.get(step).map(|s| &s.expect) else { return false };
    if expect.captures().next().is_none() && expect.relations().next().is_none() {
        return false;
    }
    let mut caps = gcl_transcript::Captures::new();
    for e in out.exchange().iter().filter(|e| e.step < step) {
        match t.steps.get(e.step).and_then(|s| s.expect.matches_with(&caps, &e.received)) {
            Some(c) => caps = c,
            None => return false,
        }
    }
    let got = &pt.hand[pt.step_start..];
    let ls = find_back(&pt.hand, pt.at, eol).max(pt.step_start) - pt.step_start;
    let le = ls + cut_line(&got[ls..], eol).len();
    let line = String::from_utf8_lossy(&got[ls..le]).into_owned();
    let tokens: Vec<&str> = line.split(' ').collect();
    if tokens.len() < 2 || tokens.iter().any(|x| x.is_empty()) {
        return false;
    }
    let fits = |order: &[&str]| {
        let text = order.join(" ");
        let mut m = gcl_transcript::Matcher::with_captures(expect, &caps);
        got[..ls].iter().chain(text.as_bytes()).all(|b| m.feed(*b) != gcl_transcript::Feed::Dead)
    };
    let mut orders: Vec<Vec<&str>> = Vec::new();
    if tokens.len() <= 6 {
        // Heap's algorithm.
        fn permute<'a>(k: usize, v: &mut Vec<&'a str>, out: &mut Vec<Vec<&'a str>>) {
            if k <= 1 {
                out.push(v.clone());
                return;
            }
            for i in 0..k {
                permute(k - 1, v, out);
                let j = if k.is_multiple_of(2) { i } else { 0 };
                v.swap(j, k - 1);
            }
        }
        permute(tokens.len(), &mut tokens.clone(), &mut orders);
    } else {
        orders.push(tokens.iter().rev().copied().collect());
    }
    orders.iter().filter(|o| **o != tokens).any(|o| fits(o))
}

/// The golden's text of the line the parting lies in (escaped, with elisions), read from the
/// failing step's expectation by the number of line endings the hand sent before it in the step.
fn golden_line(t: &Transcript, step: usize, pt: &Parting, eol: &[u8]) -> Option<String> {
    let s = t.steps.get(step)?;
    let text = s.expect.to_text();
    let text = text.trim_matches('"');
    let line_start = find_back(&pt.hand, pt.at, eol).max(pt.step_start);
    let n = count(&pt.hand[pt.step_start..line_start], eol);
    let e = gcl_transcript::escape_text(eol);
    text.split(e.as_str()).nth(n).map(str::to_string)
}

/// The parameter named on answer line `line_no` (1-based after the echo) of a get line, or
/// on the model's answer line `m_line` of a listing of values (`NAME value ...`).
fn param_at(p: &Profile, line: &[u8], line_no: usize, m_line: &[u8]) -> String {
    let Ok(Line::Command(c)) = parse_line(p, line) else { return String::new() };
    match (c.kind(p), &c.args) {
        (CommandKind::MotorGet | CommandKind::GlobalGet, Args::Names(ids)) => {
            line_no.checked_sub(1).and_then(|i| ids.get(i)).map(|id| p.param(*id).name.clone()).unwrap_or_default()
        }
        (
            CommandKind::MotorListValues
            | CommandKind::GlobalListValues
            | CommandKind::MotorListAllValues
            | CommandKind::GlobalListAllValues,
            _,
        ) => {
            let first = m_line.split(|b| *b == b' ').next().unwrap_or_default();
            let name = String::from_utf8_lossy(first);
            p.param_id(&name).map(|id| p.param(id).name.clone()).unwrap_or_default()
        }
        _ => String::new(),
    }
}

/// The motors whose values differ on a line of a motor command's answer (one value per motor
/// of its motor set, in order), as digits; empty where that does not apply.
fn differing_motors(p: &Profile, line: &[u8], actual: &str, golden: &str) -> String {
    let Ok(Line::Command(c)) = parse_line(p, line) else { return String::new() };
    if !matches!(c.kind(p), CommandKind::MotorGet) {
        return String::new();
    }
    let motors: MotorSet = c.prefix.unwrap_or(MotorSet::from_bits(0b1111));
    let a: Vec<&str> = actual.split_whitespace().collect();
    let e = expected_tokens(golden);
    if a.len() != e.len() {
        return String::new();
    }
    motors.iter().zip(a.iter().zip(&e)).filter(|(_, (x, tok))| !tok.accepts(x)).map(|(m, _)| m.to_string()).collect()
}

/// Where one failing case parts from its golden.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Signature {
    /// What groups compare: one bug, one key ([`crate::align::FindingSignature::key`]).
    pub key: String,
    /// The command being answered.
    pub command: String,
    /// The kind of difference (see [`crate::align`]).
    pub kind: String,
    /// What the difference concerns (a parameter, a RealTime field, status bits), if anything.
    pub detail: String,
    /// For a value read back: the command before it that decided the value.
    pub cause: String,
}

/// The signature of a failed replay by the step it failed in, the command that step sent
/// and the first differing line: what [`crate::align`] falls back on when the model's run of
/// the case cannot be tagged. Kinds: framing, status, order, value, missing-answer, flood,
/// link.
pub fn step_signature(case: &Case, outcome: &ReplayOutcome, profile: &Profile) -> Option<(Signature, Option<String>)> {
    let step = outcome.failed_step()?;
    let t = &case.transcript;
    let golden = t.steps.get(step.min(t.steps.len().saturating_sub(1)));
    let sent = golden.and_then(|s| s.send.as_ref()).map(|h| h.bytes.as_slice()).unwrap_or_default();
    let hex = golden.is_some_and(|s| s.expect.segments.iter().any(|g| g.form == Form::Hex))
        || golden.and_then(|s| s.send.as_ref()).is_some_and(|h| h.form == Form::Hex);
    let command = command_of(sent, hex, profile);
    let eol = profile.framing.line_ending.as_bytes();
    let prompt = profile.framing.prompt.as_bytes();
    let framing_text = gcl_transcript::escape_text(&[eol, prompt].concat());
    let (kind, hint) = match outcome {
        ReplayOutcome::Pass(_) => return None,
        ReplayOutcome::Disconnected(_) => ("link", None),
        ReplayOutcome::Flooded(_) => ("flood", None),
        ReplayOutcome::Timeout(to) => {
            if to.offset > 0 && !to.expected.is_empty() && framing_text.ends_with(&to.expected) {
                ("framing", None)
            } else {
                ("missing-answer", None)
            }
        }
        ReplayOutcome::Mismatch(m) if m.trailing => ("framing", None),
        ReplayOutcome::Mismatch(m) => {
            let got = m.exchange.last().map(|e| e.received.as_slice()).unwrap_or_default();
            classify(got, m.offset, &m.expected, &m.expected_full, sent, profile)
        }
    };
    let key = format!("{kind} at {command}");
    Some((Signature { key, command, kind: kind.to_string(), detail: String::new(), cause: String::new() }, hint))
}

/// The command word of a step's first line: `^C`, `CR`, `RealTime block`, or the word itself
/// without its motor prefix.
pub(crate) fn command_of(sent: &[u8], hex: bool, profile: &Profile) -> String {
    let fr = &profile.framing;
    if sent.first() == Some(&fr.abort) {
        return "^C".to_string();
    }
    if hex {
        return "RealTime block".to_string();
    }
    let line = sent.split(|b| *b == fr.terminator).next().unwrap_or_default();
    if line.iter().all(|b| b.is_ascii_whitespace()) {
        return "CR".to_string();
    }
    if let Ok(Line::Command(c)) = parse_line(profile, line) {
        return profile.command(c.command).name.clone();
    }
    // A line the model refuses: its first word, without a motor prefix, as sent.
    let text = String::from_utf8_lossy(line);
    let word = text.split_whitespace().next().unwrap_or_default();
    let bare = word.trim_start_matches(|c: char| profile.prefixes.iter().any(|p| p.char == c.to_ascii_uppercase()));
    let w = if bare.is_empty() { word } else { bare };
    w.chars().take(16).collect::<String>().to_ascii_uppercase()
}

fn classify(
    got: &[u8],
    offset: usize,
    expected_rest: &str,
    golden: &str,
    sent: &[u8],
    profile: &Profile,
) -> (&'static str, Option<String>) {
    let fr = &profile.framing;
    let offset = offset.min(got.len());
    let echo_len =
        if fr.echo { sent.iter().take_while(|b| **b != fr.terminator && **b != fr.abort).count() } else { 0 };
    if offset < echo_len {
        return ("framing", Some("echo".to_string()));
    }
    let is_eol = |b: &u8| matches!(b, b'\n' | b'\r');
    let line_start = got[..offset].iter().rposition(is_eol).map_or(0, |i| i + 1);
    let line_end = got[offset..].iter().position(is_eol).map_or(got.len(), |i| offset + i);
    let actual_line = &got[line_start..line_end];
    // The golden's line at the same place: as many line endings in as the answer has.
    let line_no = {
        let eol = fr.line_ending.as_bytes();
        got[..line_start].windows(eol.len().max(1)).filter(|w| *w == eol).count()
    };
    let expected_line = {
        let text = golden.trim_matches('"');
        let eol = gcl_transcript::escape_text(fr.line_ending.as_bytes());
        match text.split(eol.as_str()).nth(line_no) {
            Some(l) if !eol.is_empty() => l.to_string(),
            _ => {
                let mut s = gcl_transcript::escape_text(&got[line_start..offset]);
                let rest = expected_rest.split("\\n").next().unwrap_or_default();
                s.push_str(rest.split("\\r").next().unwrap_or_default());
                s
            }
        }
    };
    let status_word = b"ERR";
    let is_status = |l: &[u8]| l.starts_with(status_word);
    if is_status(actual_line) || expected_line.starts_with("ERR") {
        let number =
            |l: &str| l.split_whitespace().nth(1).filter(|n| n.bytes().all(|b| b.is_ascii_digit())).map(str::to_string);
        let hint = if expected_line.starts_with("ERR") {
            number(&expected_line)
        } else {
            number(&String::from_utf8_lossy(actual_line))
        };
        return ("status", hint);
    }
    let prompt = fr.prompt.trim_end();
    if actual_line.starts_with(prompt.as_bytes()) || expected_line.starts_with(prompt) {
        return ("framing", None);
    }
    let a_eol = got.get(offset).is_some_and(is_eol);
    let e_eol = expected_rest.starts_with("\\n") || expected_rest.starts_with("\\r");
    if a_eol && e_eol {
        return ("framing", None);
    }
    // One side ends the line where the other goes on, or the content differs.
    let kind = if is_reordering(&String::from_utf8_lossy(actual_line), &expected_line) { "order" } else { "value" };
    (kind, None)
}

/// Whether `actual` holds the tokens of `expected` in another order: the tokens do not match
/// in place, but each expected token (a literal, or an elision `{int A..B}` with its range,
/// or any other elision) matches a different actual token. A wrong value that happens to fit
/// a wide elision elsewhere is still a wrong value unless every token finds a partner.
pub fn is_reordering(actual: &str, expected: &str) -> bool {
    let a: Vec<&str> = actual.split_whitespace().collect();
    let e = expected_tokens(expected);
    if a.len() != e.len() || a.len() < 2 || a.len() > 64 {
        return false;
    }
    if a.iter().zip(&e).all(|(x, t)| t.accepts(x)) {
        return false;
    }
    // A perfect matching of expected tokens to actual ones (Kuhn's augmenting paths).
    fn augment(i: usize, e: &[Token], a: &[&str], seen: &mut [bool], owner: &mut [Option<usize>]) -> bool {
        for j in 0..a.len() {
            if !seen[j] && e[i].accepts(a[j]) {
                seen[j] = true;
                if owner[j].is_none_or(|k| augment(k, e, a, seen, owner)) {
                    owner[j] = Some(i);
                    return true;
                }
            }
        }
        false
    }
    let mut owner = vec![None; a.len()];
    (0..e.len()).all(|i| augment(i, &e, &a, &mut vec![false; a.len()], &mut owner))
}

/// One expected token of a golden line: a literal, an integer in a range, or anything.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Token {
    /// These characters exactly.
    Literal(String),
    /// A decimal integer within the range (inclusive).
    Int(i64, i64),
    /// Any token (an elision without a range).
    Any,
}

impl Token {
    /// Whether an actual token fits.
    pub fn accepts(&self, actual: &str) -> bool {
        match self {
            Token::Literal(l) => l == actual,
            Token::Int(lo, hi) => actual.parse::<i64>().is_ok_and(|v| (*lo..=*hi).contains(&v)),
            Token::Any => true,
        }
    }
}

/// The tokens of a golden line as written (escaped text with elisions): `{int A..B}` keeps its
/// range, any other elision matches anything.
pub fn expected_tokens(text: &str) -> Vec<Token> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut elision: Option<String> = None;
    let flush = |cur: &mut String, out: &mut Vec<Token>| {
        if !cur.is_empty() {
            out.push(Token::Literal(std::mem::take(cur)));
        }
    };
    for ch in text.chars() {
        match (&mut elision, ch) {
            (None, '{') => {
                flush(&mut cur, &mut out);
                elision = Some(String::new());
            }
            (Some(body), '}') => {
                let body = std::mem::take(body);
                elision = None;
                let range = body.strip_prefix("int ").and_then(|r| {
                    let (lo, hi) = r.trim().split_once("..")?;
                    Some((lo.parse().ok()?, hi.parse().ok()?))
                });
                out.push(range.map_or(Token::Any, |(lo, hi)| Token::Int(lo, hi)));
            }
            (Some(body), c) => body.push(c),
            (None, c) if c.is_whitespace() => flush(&mut cur, &mut out),
            (None, c) => cur.push(c),
        }
    }
    flush(&mut cur, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reordered_values_are_told_from_changed_ones() {
        assert!(is_reordering("150 1000 1000 1000", "1000 1000 1000 150"));
        assert!(is_reordering("150 1000 1000 1000", "{int 990..1010} 1000 1000 150"));
        assert!(!is_reordering("150 1000 1000 1001", "1000 1000 1000 150"));
        assert!(!is_reordering("1000 1000 1000 150", "1000 1000 1000 150"));
        // A wrong value is not an order because an elision elsewhere is wide (mcv-ignored).
        assert!(!is_reordering("793 793", "{int 144..298} {int 765..1744}"));
        assert!(is_reordering("800 200", "{int 144..298} {int 765..1744}"));
    }
}
