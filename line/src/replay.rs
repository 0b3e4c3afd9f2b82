//! Replaying a transcript: send its host side through a [`Link`], compare every answer with
//! the golden one, and say how it ended.
//!
//! Each step waits at most its own `within` (or [`ReplayOptions::default_timeout`]), so a hung
//! hand never hangs a run. An answer is consumed as soon as the shortest prefix of what arrived
//! matches the step's expectation; bytes after it belong to the next step, and bytes left after
//! the last step are a mismatch of their own. Nothing here panics on a hand's bytes.
//!
//! Every step has a deadline and an answer ceiling: its `within` and a ceiling from its golden,
//! or a runner's `StepBudget`s. Outcomes are Pass, Mismatch (with the parting byte), Timeout,
//! Flooded (a bounded prefix) and Disconnected. Captured values carry from step to step, and an
//! answer complete sooner than its timing window (`within A..B`) is a Mismatch. The exchange as it
//! happened is written back as a transcript (`actual_transcript`) that keeps the golden's comments,
//! so a report finds the preamble and the check in it. `discard` drains a link keeping nothing.

use std::fmt::Write as _;
use std::time::Duration;

use gcl_host::link::{Link, LinkError};
use gcl_transcript::matcher::{Captures, Feed, Matcher, show};
use gcl_transcript::{DEFAULT_STEP_TIMEOUT, Form, HostBytes, Step, Transcript, escape_text};

/// How to replay.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReplayOptions {
    /// The wait of a step that has no `within`.
    pub default_timeout: Duration,
    /// Before the first step, bytes are read and discarded until the hand has been quiet this
    /// long (a power-up banner, the end of an earlier case).
    pub drain_quiet: Duration,
    /// The longest the start-of-run drain may take.
    pub drain_limit: Duration,
    /// Send ^C before the drain, to bring a hand that is moving, looping or mid-line back to
    /// an idle prompt (the answer is drained). Off by default: a transcript starts from its own
    /// preamble.
    pub resync: bool,
    /// After the last step, wait this long for bytes the hand should not send.
    pub trailing: Duration,
    /// Per-step budgets (index = step) that replace the step's `within` and
    /// [`ReplayOptions::default_timeout`], and its answer ceiling: a runner derives them from
    /// the model's own run of the transcript (`gcl_conformance::deadline`). Steps past the end of the
    /// list use `within`, the default timeout and [`default_ceiling`].
    pub budgets: Vec<StepBudget>,
    /// A step whose budget has passed with not one byte of its answer waits on until this much
    /// time has passed since it began (zero: no such grace). A hand that said nothing may be
    /// slow to start, or the machine busy; one that stopped mid-answer is judged at its
    /// deadline. Runs of silent steps are bounded by the runner's dead-hand rule.
    pub silent_wait: Duration,
}

/// What one step may take: how long its answer may take, and how many bytes it may be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepBudget {
    /// The deadline, from just before the step's bytes are sent.
    pub deadline: Duration,
    /// The most bytes of answer read for the step; beyond them the hand flooded.
    pub ceiling: usize,
}

/// Multiplier of the expected answer's length in an answer ceiling.
pub const CEILING_FACTOR: usize = 16;

/// Added to every answer ceiling: no step is judged a flood under 4 KiB.
pub const CEILING_FLOOR: usize = 4096;

/// The answer ceiling of a step whose expected answer is `expected_len` bytes long:
/// `expected_len` × [`CEILING_FACTOR`] + [`CEILING_FLOOR`].
pub fn ceiling_for(expected_len: usize) -> usize {
    expected_len.saturating_mul(CEILING_FACTOR).saturating_add(CEILING_FLOOR)
}

/// The answer ceiling of a step without a budget, from its golden expectation as written (its
/// escaped text is at least as long as the bytes it stands for, elisions aside).
pub fn default_ceiling(step: &Step) -> usize {
    ceiling_for(step.expect.to_text().len())
}

impl Default for ReplayOptions {
    fn default() -> ReplayOptions {
        ReplayOptions {
            default_timeout: DEFAULT_STEP_TIMEOUT,
            drain_quiet: Duration::from_millis(100),
            drain_limit: Duration::from_secs(5),
            resync: false,
            trailing: Duration::from_millis(50),
            budgets: Vec::new(),
            silent_wait: Duration::ZERO,
        }
    }
}

/// One step as it happened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Exchanged {
    /// The step, 0-based.
    pub step: usize,
    /// Its line in the transcript (0 when built in code).
    pub line: usize,
    /// What was sent.
    pub sent: Vec<u8>,
    /// What the hand answered: the matched answer, or for the last step of a failed replay
    /// everything received (at most the step's answer ceiling).
    pub received: Vec<u8>,
    /// Time from just before the step's bytes were sent until its answer was complete (or
    /// the step ended), on the link's clock.
    pub took: Duration,
}

/// A replay where every answer matched.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Passed {
    /// Time the replay took on the link's clock (simulated time for the simulator).
    pub elapsed: Duration,
    /// Every step.
    pub exchange: Vec<Exchanged>,
}

/// Where an answer parted from the golden one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mismatch {
    /// The step, 0-based.
    pub step: usize,
    /// Its line in the transcript.
    pub line: usize,
    /// Byte offset within the step's answer where the bytes part.
    pub offset: usize,
    /// The expectation from the parting byte on, as written (escaped text or hex, elisions
    /// in braces). Empty when the hand sent bytes after the end of the transcript.
    pub expected: String,
    /// The answer from the parting byte on, in the same form.
    pub actual: String,
    /// The whole expectation of the step, as written.
    pub expected_full: String,
    /// Whether the mismatch is bytes after the last step (nothing more was expected).
    pub trailing: bool,
    /// How the step's bytes are shown.
    pub form: Form,
    /// The exchange up to and including the failing step (whose `received` is the whole
    /// answer as far as it was read).
    pub exchange: Vec<Exchanged>,
}

/// A step that waited past its deadline.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TimedOut {
    /// The step, 0-based.
    pub step: usize,
    /// Its line in the transcript.
    pub line: usize,
    /// How long it waited.
    pub waited: Duration,
    /// Bytes of the answer that arrived, all matching so far.
    pub offset: usize,
    /// What was still expected, as written.
    pub expected: String,
    /// The whole expectation of the step, as written.
    pub expected_full: String,
    /// How the step's bytes are shown.
    pub form: Form,
    /// The exchange up to and including the step.
    pub exchange: Vec<Exchanged>,
}

/// The hand sent more than a step's answer ceiling while its answer was still open (an
/// `{any}` elision that never closes, a hand that streams bytes).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Flooded {
    /// The step, 0-based.
    pub step: usize,
    /// Its line in the transcript.
    pub line: usize,
    /// The ceiling that was passed, bytes.
    pub ceiling: usize,
    /// The whole expectation of the step, as written.
    pub expected_full: String,
    /// The exchange up to and including the step (whose `received` is the bounded prefix).
    pub exchange: Vec<Exchanged>,
}

/// The link failed: the hand disconnected, or an I/O error.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Disconnected {
    /// The step, 0-based (the number of steps when it happened after the last).
    pub step: usize,
    /// Its line in the transcript.
    pub line: usize,
    /// What the link said.
    pub reason: String,
    /// The exchange so far.
    pub exchange: Vec<Exchanged>,
}

/// Where a failed replay parted from the golden transcript, for reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Parting {
    /// The step, 0-based.
    pub step: usize,
    /// Its line in the transcript.
    pub line: usize,
    /// Byte offset within the step's answer.
    pub offset: usize,
    /// The expectation from that byte on, as written (empty: nothing more was expected).
    pub expected: String,
    /// The answer from that byte on, escaped or in hex (empty: nothing more arrived).
    pub actual: String,
}

/// How a replay ended. A runner's verdicts: `Pass` PASS, `Mismatch` and `Flooded` FAIL,
/// `Timeout` TIMEOUT, `Disconnected` ERROR.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReplayOutcome {
    /// Every answer matched.
    Pass(Passed),
    /// An answer differed (FAIL).
    Mismatch(Box<Mismatch>),
    /// A step waited past its deadline (TIMEOUT).
    Timeout(Box<TimedOut>),
    /// A step's answer passed its ceiling (FAIL: the hand flooded).
    Flooded(Box<Flooded>),
    /// The hand vanished or the link failed (ERROR).
    Disconnected(Box<Disconnected>),
}

impl ReplayOutcome {
    /// Whether every answer matched.
    pub fn is_pass(&self) -> bool {
        matches!(self, ReplayOutcome::Pass(_))
    }

    /// The exchange as far as it went.
    pub fn exchange(&self) -> &[Exchanged] {
        match self {
            ReplayOutcome::Pass(p) => &p.exchange,
            ReplayOutcome::Mismatch(m) => &m.exchange,
            ReplayOutcome::Timeout(t) => &t.exchange,
            ReplayOutcome::Flooded(f) => &f.exchange,
            ReplayOutcome::Disconnected(d) => &d.exchange,
        }
    }

    /// The failing step (0-based), if any.
    pub fn failed_step(&self) -> Option<usize> {
        match self {
            ReplayOutcome::Pass(_) => None,
            ReplayOutcome::Mismatch(m) => Some(m.step),
            ReplayOutcome::Timeout(t) => Some(t.step),
            ReplayOutcome::Flooded(f) => Some(f.step),
            ReplayOutcome::Disconnected(d) => Some(d.step),
        }
    }

    /// Where the answer parted from the golden one (mismatch or timeout).
    pub fn parting(&self) -> Option<Parting> {
        match self {
            ReplayOutcome::Mismatch(m) => Some(Parting {
                step: m.step,
                line: m.line,
                offset: m.offset,
                expected: m.expected.clone(),
                actual: m.actual.clone(),
            }),
            ReplayOutcome::Timeout(t) => Some(Parting {
                step: t.step,
                line: t.line,
                offset: t.offset,
                expected: t.expected.clone(),
                actual: String::new(),
            }),
            _ => None,
        }
    }

    /// One line saying how the replay ended.
    pub fn summary(&self) -> String {
        match self {
            ReplayOutcome::Pass(p) => format!("pass: {} steps", p.exchange.len()),
            ReplayOutcome::Mismatch(m) if m.trailing => {
                format!("mismatch after the last step{}: the hand sent more", at_line(m.line))
            }
            ReplayOutcome::Mismatch(m) => {
                format!("mismatch at step {}{}, byte {} of the answer", m.step + 1, at_line(m.line), m.offset)
            }
            ReplayOutcome::Timeout(t) => format!(
                "timeout at step {}{} after {}: {} bytes of the answer arrived",
                t.step + 1,
                at_line(t.line),
                gcl_transcript::format_duration(t.waited),
                t.offset
            ),
            ReplayOutcome::Flooded(f) => format!(
                "the hand flooded at step {}{}: more than {} bytes of answer without matching it (the first {} are kept)",
                f.step + 1,
                at_line(f.line),
                f.ceiling,
                f.ceiling
            ),
            ReplayOutcome::Disconnected(d) => {
                format!("link failed at step {}{}: {}", d.step + 1, at_line(d.line), d.reason)
            }
        }
    }

    /// A report for people: the summary, the step's bytes sent, and expected against actual
    /// from a little before the parting byte, with a caret under it.
    pub fn render(&self) -> String {
        let mut s = self.summary();
        s.push('\n');
        match self {
            ReplayOutcome::Pass(_) => {}
            ReplayOutcome::Mismatch(m) => {
                let got = m.exchange.last().map(|e| e.received.as_slice()).unwrap_or_default();
                if let Some(e) = m.exchange.last() {
                    let _ = writeln!(s, "  sent:     \"{}\"", escape_text(&e.sent));
                }
                let lines = side_by_side(got, m.offset, &m.expected, m.form, m.trailing);
                let _ = write!(s, "{}{lines}", golden_line(&lines, &m.expected_full));
            }
            ReplayOutcome::Timeout(t) => {
                let got = t.exchange.last().map(|e| e.received.as_slice()).unwrap_or_default();
                if let Some(e) = t.exchange.last() {
                    let _ = writeln!(s, "  sent:     \"{}\"", escape_text(&e.sent));
                }
                let lines = side_by_side(got, t.offset, &t.expected, t.form, false);
                let _ = write!(s, "{}{lines}", golden_line(&lines, &t.expected_full));
                let _ = writeln!(s, "  (nothing more arrived)");
            }
            ReplayOutcome::Flooded(f) => {
                if let Some(e) = f.exchange.last() {
                    let _ = writeln!(s, "  sent:     \"{}\"", escape_text(&e.sent));
                    let _ = writeln!(s, "  golden:   {}", f.expected_full);
                    let head = &e.received[..e.received.len().min(FLOOD_SHOWN)];
                    let _ = writeln!(s, "  actual:   \"{}\" … ({} bytes)", escape_text(head), e.received.len());
                }
            }
            ReplayOutcome::Disconnected(_) => {}
        }
        s
    }
}

/// ` (line N)` for a step read from a file; nothing for one built in code (line 0).
fn at_line(line: usize) -> String {
    if line == 0 { String::new() } else { format!(" (line {line})") }
}

/// Bytes before the parting byte shown for context.
const CONTEXT: usize = 24;

/// Bytes of an answer shown after the parting byte in a rendering.
const SHOWN_AFTER: usize = 400;

/// Bytes of a flood shown in a rendering.
const FLOOD_SHOWN: usize = 200;

/// The step's whole golden, as a line of its own, unless the `expected:` line already shows
/// all of it (the answer parts early and the golden has no elision before the parting byte).
fn golden_line(side_by_side: &str, golden: &str) -> String {
    if side_by_side.starts_with(&format!("  expected: {golden}\n")) {
        String::new()
    } else {
        format!("  golden:   {golden}\n")
    }
}

fn side_by_side(got: &[u8], offset: usize, expected_rest: &str, form: Form, trailing: bool) -> String {
    let offset = offset.min(got.len());
    let from = offset.saturating_sub(CONTEXT);
    let lead = if from > 0 { "…" } else { "" };
    let (q, sep) = if form == Form::Text { ("\"", "") } else { ("", " ") };
    let before = show(&got[from..offset], form);
    let shown = (got.len() - offset).min(SHOWN_AFTER);
    let mut after = show(&got[offset..offset + shown], form);
    if shown < got.len() - offset {
        let _ = write!(after, "… ({} more bytes)", got.len() - offset - shown);
    }
    let joint = if before.is_empty() || after.is_empty() { "" } else { sep };
    let joint_e = if before.is_empty() || expected_rest.is_empty() { "" } else { sep };
    let expected =
        if trailing { "(end of answer)".to_string() } else { format!("{q}{lead}{before}{joint_e}{expected_rest}{q}") };
    let actual = format!("{q}{lead}{before}{joint}{after}{q}");
    let caret = q.len() + lead.chars().count() + before.chars().count() + joint.len();
    format!("  expected: {expected}\n  actual:   {actual}\n            {}^ byte {offset}\n", " ".repeat(caret))
}

/// What [`discard`] saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Discarded {
    /// Bytes read and thrown away.
    pub bytes: u64,
    /// Whether the hand fell quiet; false when `limit` passed while it was still sending.
    pub quiet: bool,
}

/// Reads and throws away what the hand sends until it has been quiet for `quiet` or `limit`
/// has passed, keeping nothing: memory stays bounded however much a flooding hand sends.
pub fn discard(link: &mut dyn Link, quiet: Duration, limit: Duration) -> Result<Discarded, LinkError> {
    let start = link.elapsed();
    let mut scratch = Vec::with_capacity(8192);
    let mut bytes = 0u64;
    loop {
        scratch.clear();
        let n = link.recv(&mut scratch, quiet)?;
        bytes += n as u64;
        if n == 0 {
            return Ok(Discarded { bytes, quiet: true });
        }
        if link.elapsed().saturating_sub(start) >= limit {
            return Ok(Discarded { bytes, quiet: false });
        }
    }
}

fn link_failed(step: usize, line: usize, e: &LinkError, exchange: Vec<Exchanged>) -> ReplayOutcome {
    ReplayOutcome::Disconnected(Box::new(Disconnected { step, line, reason: e.to_string(), exchange }))
}

/// Replays `t` over `link`.
pub fn replay(t: &Transcript, link: &mut dyn Link, opts: &ReplayOptions) -> ReplayOutcome {
    let start = link.elapsed();
    let first_line = t.steps.first().map_or(0, |s| s.line);
    if opts.resync
        && let Err(e) = link.send(&[3])
    {
        return link_failed(0, first_line, &e, Vec::new());
    }
    if let Err(e) = discard(link, opts.drain_quiet, opts.drain_limit) {
        return link_failed(0, first_line, &e, Vec::new());
    }
    let mut exchange: Vec<Exchanged> = Vec::with_capacity(t.steps.len());
    let mut buf: Vec<u8> = Vec::new();
    // Values the answers captured, for the relations of later answers.
    let mut caps = Captures::new();
    for (i, step) in t.steps.iter().enumerate() {
        match run_step(i, step, link, opts, &mut buf, &mut exchange, &mut caps) {
            Ok(()) => {}
            Err(outcome) => return outcome,
        }
    }
    if !opts.trailing.is_zero()
        && let Err(e) = link.recv(&mut buf, opts.trailing)
    {
        let line = t.steps.last().map_or(0, |s| s.line);
        return link_failed(t.steps.len(), line, &e, exchange);
    }
    if !buf.is_empty() {
        let step = t.steps.len().saturating_sub(1);
        let last = t.steps.last();
        let mut exchange = exchange;
        let mut offset = 0;
        if let Some(e) = exchange.last_mut() {
            offset = e.received.len();
            e.received.extend_from_slice(&buf);
        }
        let form = if buf.iter().all(|b| (0x20..0x7f).contains(b) || matches!(b, b'\n' | b'\r' | b'\t')) {
            Form::Text
        } else {
            Form::Hex
        };
        return ReplayOutcome::Mismatch(Box::new(Mismatch {
            step,
            line: last.map_or(0, |s| s.line),
            offset,
            expected: String::new(),
            actual: show(&buf, form),
            expected_full: last.map(|s| s.expect.to_text()).unwrap_or_default(),
            trailing: true,
            form,
            exchange,
        }));
    }
    ReplayOutcome::Pass(Passed { elapsed: link.elapsed().saturating_sub(start), exchange })
}

fn run_step(
    i: usize,
    step: &Step,
    link: &mut dyn Link,
    opts: &ReplayOptions,
    buf: &mut Vec<u8>,
    exchange: &mut Vec<Exchanged>,
    caps: &mut Captures,
) -> Result<(), ReplayOutcome> {
    if let Some(p) = step.pause {
        link.pause(p);
    }
    let sent = step.send.as_ref().map(|s: &HostBytes| s.bytes.clone()).unwrap_or_default();
    let t0 = link.elapsed();
    if !sent.is_empty()
        && let Err(e) = link.send(&sent)
    {
        let took = link.elapsed().saturating_sub(t0);
        exchange.push(Exchanged { step: i, line: step.line, sent, received: Vec::new(), took });
        return Err(link_failed(i, step.line, &e, std::mem::take(exchange)));
    }
    let budget = opts.budgets.get(i).copied();
    let timeout = budget.map_or_else(|| step.within.unwrap_or(opts.default_timeout), |b| b.deadline);
    // (the default ceiling writes the expectation out to measure it: that waits until an
    // answer is longer than the least ceiling could be)
    let ceiling = std::cell::LazyCell::new(|| budget.map_or_else(|| default_ceiling(step), |b| b.ceiling));
    let at_least = budget.map_or(CEILING_FLOOR, |b| b.ceiling);
    let mut m = Matcher::with_captures(&step.expect, caps);
    let mut fed = 0;
    // When the answer's first byte came after the deadline (a silent step's grace), the
    // rest of the answer gets the deadline again from there.
    let mut first_byte: Option<Duration> = None;
    let consumed = 'outer: loop {
        if m.is_complete() {
            break 'outer fed;
        }
        while fed < buf.len() {
            let b = buf[fed];
            fed += 1;
            match m.feed(b) {
                Feed::Complete => break 'outer fed,
                Feed::Alive => {}
                Feed::Dead => {
                    let offset = fed - 1;
                    let form = m.form_at_parting();
                    let expected = m.expected_at_parting();
                    buf.truncate(offset.saturating_add(*ceiling));
                    let took = link.elapsed().saturating_sub(t0);
                    exchange.push(Exchanged { step: i, line: step.line, sent, received: std::mem::take(buf), took });
                    let got = &exchange[exchange.len() - 1].received;
                    return Err(ReplayOutcome::Mismatch(Box::new(Mismatch {
                        step: i,
                        line: step.line,
                        offset,
                        expected,
                        actual: show(&got[offset..], form),
                        expected_full: step.expect.to_text(),
                        trailing: false,
                        form,
                        exchange: std::mem::take(exchange),
                    })));
                }
            }
        }
        if buf.len() > at_least && buf.len() > *ceiling {
            buf.truncate(*ceiling);
            let took = link.elapsed().saturating_sub(t0);
            exchange.push(Exchanged { step: i, line: step.line, sent, received: std::mem::take(buf), took });
            return Err(ReplayOutcome::Flooded(Box::new(Flooded {
                step: i,
                line: step.line,
                ceiling: *ceiling,
                expected_full: step.expect.to_text(),
                exchange: std::mem::take(exchange),
            })));
        }
        let spent = link.elapsed().saturating_sub(t0);
        let limit = if buf.is_empty() {
            timeout.max(opts.silent_wait)
        } else {
            let first = *first_byte.get_or_insert(spent);
            if first > timeout { first + timeout } else { timeout }
        };
        let before = link.elapsed();
        let got = if spent < limit { link.recv(buf, limit - spent) } else { Ok(0) };
        match got {
            Err(e) => {
                buf.truncate(*ceiling);
                let took = link.elapsed().saturating_sub(t0);
                exchange.push(Exchanged { step: i, line: step.line, sent, received: std::mem::take(buf), took });
                return Err(link_failed(i, step.line, &e, std::mem::take(exchange)));
            }
            Ok(0) if spent >= limit || link.elapsed() == before || link.elapsed().saturating_sub(t0) >= limit => {
                let form = m.form_at_parting();
                let expected = m.expected_rest();
                let offset = buf.len();
                let took = link.elapsed().saturating_sub(t0);
                exchange.push(Exchanged { step: i, line: step.line, sent, received: std::mem::take(buf), took });
                return Err(ReplayOutcome::Timeout(Box::new(TimedOut {
                    step: i,
                    line: step.line,
                    waited: took,
                    offset,
                    expected,
                    expected_full: step.expect.to_text(),
                    form,
                    exchange: std::mem::take(exchange),
                })));
            }
            Ok(_) => {}
        }
    };
    let rest = buf.split_off(consumed);
    let received = std::mem::replace(buf, rest);
    let took = link.elapsed().saturating_sub(t0);
    if let Some(caught) = m.captures() {
        *caps = caught;
    }
    // A timing window: an answer complete sooner than its lower bound fails at its last byte.
    if let Some(earliest) = step.earliest
        && took < earliest
    {
        let form = m.form_at_parting();
        let offset = received.len().saturating_sub(1);
        let actual = show(received.get(offset..).unwrap_or_default(), form);
        exchange.push(Exchanged { step: i, line: step.line, sent, received, took });
        return Err(ReplayOutcome::Mismatch(Box::new(Mismatch {
            step: i,
            line: step.line,
            offset,
            expected: format!(
                "the answer complete no sooner than {} (it was complete after {})",
                gcl_transcript::format_duration(earliest),
                gcl_transcript::format_duration(took)
            ),
            actual,
            expected_full: step.expect.to_text(),
            trailing: false,
            form,
            exchange: std::mem::take(exchange),
        })));
    }
    exchange.push(Exchanged { step: i, line: step.line, sent, received, took });
    Ok(())
}

/// The exchange written as a transcript: `t`'s header, each step's pause, sent bytes and
/// `within`, and the bytes the hand actually answered as an exact expectation. For reports and
/// certificates ("what the hand said").
pub fn actual_transcript(t: &Transcript, exchange: &[Exchanged]) -> Transcript {
    let steps = exchange
        .iter()
        .filter_map(|e| {
            let s = t.steps.get(e.step)?;
            let form = s.expect.segments.first().map_or(Form::Text, |g| g.form);
            let expect = match form {
                Form::Text => gcl_transcript::Expect::text(&e.received),
                Form::Hex => gcl_transcript::Expect::hex(&e.received),
            };
            Some(Step {
                line: 0,
                comments: s.comments.clone(),
                pause: s.pause,
                send: s.send.clone(),
                within: s.within,
                earliest: s.earliest,
                expect,
            })
        })
        .collect();
    Transcript { header: t.header.clone(), steps }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gcl_host::SimLink;
    use gcl_model::{DeviceConfig, Fault, Profile};
    use gcl_transcript::parse;

    const FGET: &str = "gcl-transcript 1\nid: t\ntitle: t\nclause: c\nlevel: MUST\nprofile: seed\n\nsend \"\\x03\"\nexpect \"\\n\\r=> \"\n\nsend \"FGET DP\\r\"\nexpect \"FGET DP\\n\\r{int 990..1010} 1000 1000 150\\n\\r=> \"\n";

    fn sim(faults: Vec<Fault>) -> SimLink {
        SimLink::new(Profile::builtin("seed").unwrap(), DeviceConfig { faults, ..Default::default() })
    }

    #[test]
    fn passes_on_the_model() {
        let t = parse(FGET).unwrap();
        let out = replay(&t, &mut sim(vec![]), &ReplayOptions::default());
        assert!(out.is_pass(), "{}", out.render());
        assert_eq!(out.exchange()[1].received, b"FGET DP\n\r1000 1000 1000 150\n\r=> ");
        let actual = actual_transcript(&t, out.exchange());
        assert!(actual.to_text().contains("expect \"FGET DP\\n\\r1000 1000 1000 150\\n\\r=> \""));
    }

    #[test]
    fn captures_carry_from_step_to_step_and_windows_have_a_floor() {
        // DP reads 1000 1000 1000 150 on the seed: motor 2's DP is captured, then the spread's
        // is held to 3/20 of it (150), exactly.
        let related = FGET.replace("{int 990..1010} 1000 1000 150", "1000 {int 1..20000 as dp} 1000 150").replace(
            "\n\nsend \"FGET DP",
            "\n\nsend \"FGET DP\\r\"\nexpect \"FGET DP\\n\\r1000 1000 1000 150\\n\\r=> \"\n\nsend \"FGET DP",
        );
        let t = parse(&format!(
            "{related}\nsend \"SFGET DP\\r\"\nexpect \"SFGET DP\\n\\r{{int dp*3/20 +-0%}}\\n\\r=> \"\n"
        ))
        .unwrap();
        let out = replay(&t, &mut sim(vec![]), &ReplayOptions::default());
        assert!(out.is_pass(), "{}", out.render());
        // 3/19 of 1000 is 157.9, rounded outward 157..158: 150 parts at its last digit.
        let off = parse(&t.to_text().replace("dp*3/20 +-0%", "dp*3/19 +-0%")).unwrap();
        let out = replay(&off, &mut sim(vec![]), &ReplayOptions::default());
        let ReplayOutcome::Mismatch(m) = &out else { panic!("{}", out.render()) };
        assert_eq!((m.step, m.expected.as_str()), (3, "{int 157..158}\\n\\r=> "));
        // An answer that comes sooner than its window's lower bound fails.
        let early = parse(&t.to_text().replacen("expect \"FGET DP", "expect within 1s..2s \"FGET DP", 1)).unwrap();
        let out = replay(&early, &mut sim(vec![]), &ReplayOptions::default());
        let ReplayOutcome::Mismatch(m) = &out else { panic!("{}", out.render()) };
        assert_eq!(m.step, 1);
        assert!(m.expected.starts_with("the answer complete no sooner than 1s"), "{}", m.expected);
    }

    #[test]
    fn mismatch_shows_the_parting_byte() {
        let t = parse(FGET).unwrap();
        let out = replay(&t, &mut sim(vec![Fault::CrLf]), &ReplayOptions::default());
        let ReplayOutcome::Mismatch(m) = &out else { panic!("{}", out.render()) };
        assert_eq!((m.step, m.line, m.offset), (0, 8, 0));
        let parting = out.parting().unwrap();
        assert_eq!((parting.step, parting.offset, parting.actual.as_str()), (0, 0, "\\r\\n=> "));
        assert_eq!(m.expected, "\\n\\r=> ");
        assert_eq!(m.actual, "\\r\\n=> ");
        let r = out.render();
        assert!(r.contains("expected: \"\\n\\r=> \""), "{r}");
        assert!(r.contains("actual:   \"\\r\\n=> \""), "{r}");
        let out = replay(&t, &mut sim(vec![Fault::FgetReversed]), &ReplayOptions::default());
        let ReplayOutcome::Mismatch(m) = &out else { panic!("{}", out.render()) };
        assert_eq!((m.step, m.offset), (1, 10));
        assert_eq!(m.actual, "50 1000 1000 1000\\n\\r=> ");
        assert!(m.expected.starts_with("{int 990..1010} 1000"), "{}", m.expected);
        let r = out.render();
        assert!(r.contains("^ byte 10"), "{r}");
    }

    #[test]
    fn a_short_answer_times_out_at_the_step_deadline() {
        let t = parse(FGET).unwrap();
        let out = replay(&t, &mut sim(vec![Fault::PromptNoSpace]), &ReplayOptions::default());
        let ReplayOutcome::Timeout(to) = &out else { panic!("{}", out.render()) };
        assert_eq!((to.step, to.offset), (0, 4));
        assert_eq!(to.expected, " ");
        assert!(to.waited >= DEFAULT_STEP_TIMEOUT);
    }

    /// A hand that answers RESET with an endless stream (never the banner's end).
    struct Flooding {
        inner: SimLink,
        flooding: bool,
    }

    impl Link for Flooding {
        fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
            if bytes.starts_with(b"RESET") {
                self.flooding = true;
                return Ok(());
            }
            self.inner.send(bytes)
        }
        fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
            if self.flooding {
                // The echo, then text that never reaches the banner.
                self.inner.pause(Duration::from_millis(1));
                let before = buf.len();
                if before == 0 {
                    buf.extend_from_slice(b"RESET\n\r");
                }
                buf.extend(std::iter::repeat_n(b'x', 65536));
                return Ok(buf.len() - before);
            }
            self.inner.recv(buf, timeout)
        }
        fn elapsed(&self) -> Duration {
            self.inner.elapsed()
        }
        fn describe(&self) -> String {
            "flooding".into()
        }
    }

    #[test]
    fn a_hand_that_floods_an_open_elision_fails_with_a_bounded_prefix() {
        let text = "gcl-transcript 1\nid: t\ntitle: t\nclause: c\nlevel: MUST\nprofile: seed\n\nsend \"\\x03\"\nexpect \"\\n\\r=> \"\n\nsend \"RESET\\r\"\nexpect within 10s \"RESET{any}BarrettHand Firmware{any}\\n\\r=> \"\n";
        let t = parse(text).unwrap();
        let mut link = Flooding { inner: sim(vec![]), flooding: false };
        let out = replay(&t, &mut link, &ReplayOptions::default());
        let ReplayOutcome::Flooded(f) = &out else { panic!("{}", out.render()) };
        assert_eq!(f.step, 1);
        assert_eq!(f.ceiling, default_ceiling(&t.steps[1]));
        assert_eq!(out.exchange()[1].received.len(), f.ceiling, "only the prefix up to the ceiling is kept");
        assert!(out.summary().starts_with("the hand flooded at step 2"), "{}", out.summary());
        // A budget from the model sets the ceiling instead.
        let opts = ReplayOptions {
            budgets: vec![
                StepBudget { deadline: Duration::from_secs(1), ceiling: 100 },
                StepBudget { deadline: Duration::from_secs(1), ceiling: 5000 },
            ],
            ..ReplayOptions::default()
        };
        let mut link = Flooding { inner: sim(vec![]), flooding: false };
        let out = replay(&t, &mut link, &opts);
        assert_eq!(out.exchange().last().map(|e| e.received.len()), Some(5000), "{}", out.summary());
    }

    #[test]
    fn extra_bytes_after_the_last_step_are_a_mismatch() {
        let mut t = parse(FGET).unwrap();
        t.steps[1].send = Some(HostBytes::text(b"FGET DP\rFGET DP\r".to_vec()));
        let out = replay(&t, &mut sim(vec![]), &ReplayOptions::default());
        let ReplayOutcome::Mismatch(m) = &out else { panic!("{}", out.render()) };
        assert!(m.trailing);
        assert!(m.actual.starts_with("FGET DP"), "{}", m.actual);
    }
}
