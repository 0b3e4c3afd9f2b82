//! Recording: run a script's host side against a hand and capture what it answers, step by
//! step, then write the answers down as a golden [`Transcript`].
//!
//! A step of a recording ends
//! - at the first prompt (line ending then `=> `) after its bytes went out;
//! - for a LOOP line, at the `*` that opens RealTime mode;
//! - in RealTime mode, once the hand has sent as many bytes as the reference model answers to
//!   the same bytes (a feedback block of the layout's size, or `*`);
//! - for [`Action::NoWait`] and [`Action::Partial`], once the hand has been quiet for
//!   [`RecordOptions::quiet`];
//! - or at its timeout.
//!
//! To know when RealTime mode starts and how big its blocks are, the recorder runs a *shadow*
//! reference model of the profile beside the link and feeds it the same bytes. The shadow only
//! shapes the capture; every byte written to the transcript comes from the link.
//!
//! A recording of a hand known to differ from the profile gives the shadow the difference
//! (`RecordOptions::shadow`). A step's answer stops at `MAX_STEP_ANSWER` (a typed `Flooded` error),
//! and errors show at most 200 bytes of an answer.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::grammar::{self, Line};
use gcl_model::realtime::RtLayout;
use gcl_model::spec::CommandKind;
use gcl_model::{Device, DeviceConfig, Event, Mode, Profile};

use gcl_host::client::core::Framing;
use gcl_host::link::{Link, LinkError, byte_time, drain};
use gcl_transcript::script::{Action, Script, ScriptStep};
use gcl_transcript::{DEFAULT_STEP_TIMEOUT, Expect, Form, Header, HostBytes, Piece, Step, Transcript};

/// The text every banner contains (decision `bh8-banner-text`, notes: RESET).
pub const BANNER_TEXT: &[u8] = b"BarrettHand Firmware";

/// How to record.
#[derive(Debug, Clone)]
pub struct RecordOptions {
    /// The profile of the shadow model (block sizes, the prompt, the CR).
    pub profile: Arc<Profile>,
    /// Capture timeout of a step whose script gives none.
    pub timeout: Duration,
    /// Silence that ends a [`Action::NoWait`] step, and the start-of-run drain.
    pub quiet: Duration,
    /// Write a RESET's banner as `{any}BarrettHand Firmware{any}` instead of its exact text.
    pub elide_banner: bool,
    /// How the shadow model's hand differs from the profile's (default: not at all). Its
    /// blocks' sizes and its mode decide where an answer ends, so a recording of a hand known
    /// to differ in them (a hypothesis of the device fuzzer: a RealTime flag without effect)
    /// gives the shadow the same difference.
    pub shadow: DeviceConfig,
}

impl RecordOptions {
    /// Defaults for a profile: 30 s per step, 100 ms of quiet, banners elided.
    pub fn new(profile: Arc<Profile>) -> RecordOptions {
        RecordOptions {
            profile,
            timeout: Duration::from_secs(30),
            quiet: Duration::from_millis(100),
            elide_banner: true,
            shadow: DeviceConfig::default(),
        }
    }
}

/// What one step captured.
#[derive(Debug, Clone, PartialEq)]
pub struct Captured {
    /// The bytes sent.
    pub sent: Vec<u8>,
    /// The hand's answer.
    pub output: Vec<u8>,
    /// Time from the send to the end of the answer, on the link's clock.
    pub took: Duration,
    /// Whether the bytes were sent in RealTime mode (per the shadow model).
    pub realtime: bool,
    /// The RealTime layouts in force when the bytes were sent.
    pub layout: Option<RtLayout>,
    /// Whether the step ended at its timeout instead of its natural end.
    pub timed_out: bool,
    /// Whether the step ended because the answer passed [`MAX_STEP_ANSWER`] (a flooding
    /// hand); `output` then holds the first [`MAX_STEP_ANSWER`] bytes and the recording stops.
    pub flooded: bool,
}

/// The most bytes one step's answer may hold: the longest real answer (a RESET banner, a
/// parameter listing) is a few kilobytes; a hand past this floods, and the recording stops
/// there instead of keeping everything it sends.
pub const MAX_STEP_ANSWER: usize = 1 << 20;

/// The most bytes of an answer an error message shows.
const SHOWN_IN_ERRORS: usize = 200;

/// Runs the steps against `link` and captures each answer. The link should be fresh or idle:
/// anything it sends before the first step is drained first.
pub fn capture(link: &mut dyn Link, steps: &[ScriptStep], opts: &RecordOptions) -> Result<Vec<Captured>, LinkError> {
    let mut r = Recorder::start(link, opts)?;
    r.capture(link, steps, opts)
}

/// A recording under way: the shadow model beside the link and the bytes the link sent past
/// the last step's answer. [`capture`] is [`Recorder::start`] then [`Recorder::capture`]; a
/// caller that records many scripts with the same first steps on equal fresh links may keep a
/// clone of the recorder (and of its link) after those steps and go on from there: what
/// follows is what the whole recording would capture, since both are deterministic values.
#[derive(Debug, Clone)]
pub struct Recorder {
    framing: Framing,
    shadow: Device,
    carry: Vec<u8>,
}

impl Recorder {
    /// Starts a recording on `link` (fresh or idle): drains what it sends first.
    pub fn start(link: &mut dyn Link, opts: &RecordOptions) -> Result<Recorder, LinkError> {
        let profile = &opts.profile;
        // The recorder writes down whatever the hand says, GCL or not, so it does not parse the
        // answer; it only needs the host core's notion of where an answer ends.
        let framing = Framing::of(profile);
        let mut shadow = Device::new(profile.clone(), opts.shadow.clone());
        shadow.clear_output();
        while shadow.poll_event().is_some() {}
        drain(link, opts.quiet, Duration::from_secs(10))?;
        Ok(Recorder { framing, shadow, carry: Vec::new() })
    }

    /// The recording with `shadow` as its shadow model from here on: a model in the state the
    /// recorder's own shadow would be in after the steps so far (one that ran them by
    /// [`shadow_step`], their pauses included, for the steps recorded with
    /// [`Recorder::step_seen`]).
    pub fn with_shadow(mut self, shadow: Device) -> Recorder {
        self.shadow = shadow;
        self
    }

    /// Runs the steps and captures each answer, stopping after a step that floods.
    pub fn capture(
        &mut self,
        link: &mut dyn Link,
        steps: &[ScriptStep],
        opts: &RecordOptions,
    ) -> Result<Vec<Captured>, LinkError> {
        let mut out = Vec::with_capacity(steps.len());
        for step in steps {
            let c = self.step(link, step, opts)?;
            let flooded = c.flooded;
            out.push(c);
            if flooded {
                break;
            }
        }
        Ok(out)
    }

    /// Runs one step and captures its answer.
    pub fn step(
        &mut self,
        link: &mut dyn Link,
        step: &ScriptStep,
        opts: &RecordOptions,
    ) -> Result<Captured, LinkError> {
        if let Some(p) = step.pause {
            let t = self.shadow.now() + p;
            self.shadow.handle_timeout(t);
        }
        let seen = shadow_step(&mut self.shadow, step, opts.profile.framing.terminator);
        self.step_seen(link, step, opts, seen)
    }

    /// [`Recorder::step`] with what the recorder's shadow makes of it already known: `seen` is
    /// [`shadow_step`] of a model in the state this recorder's shadow is in, after the step's
    /// pause. The recorder's own shadow is left as it is (see [`Recorder::with_shadow`]).
    pub fn step_seen(
        &mut self,
        link: &mut dyn Link,
        step: &ScriptStep,
        opts: &RecordOptions,
        seen: ShadowStep,
    ) -> Result<Captured, LinkError> {
        let framing = &self.framing;
        if let Some(p) = step.pause {
            link.pause(p);
        }
        let sent = step.action.wire_bytes(opts.profile.framing.terminator);
        let ShadowStep { was_loop, layout, out: shadow_out, entered_loop } = seen;
        if !sent.is_empty() {
            link.send(&sent)?;
        }
        let t0 = link.elapsed();
        let timeout = step.timeout.unwrap_or(opts.timeout);
        let mut buf = std::mem::take(&mut self.carry);
        // (bytes already searched hold no prompt: each look starts where one could begin)
        let mut searched = 0;
        let mut end = |buf: &[u8]| -> Option<usize> {
            let prompt_end = framing.prompt_end_from(buf, searched);
            searched = framing.prompt_search_start(buf.len()).max(searched);
            if was_loop {
                let size_end = (buf.len() >= shadow_out.len() && !shadow_out.is_empty()).then_some(shadow_out.len());
                return match (prompt_end, size_end) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                };
            }
            if entered_loop {
                let star = buf.iter().position(|b| *b == gcl_model::realtime::FEEDBACK_HEADER).map(|i| i + 1);
                return match (prompt_end, star) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                };
            }
            prompt_end
        };
        let mut timed_out = false;
        let mut flooded = false;
        let cut = if step.action.ends_on_quiet() {
            loop {
                let before = link.elapsed();
                let n = link.recv(&mut buf, opts.quiet)?;
                if buf.len() > MAX_STEP_ANSWER {
                    flooded = true;
                    break MAX_STEP_ANSWER;
                }
                if n == 0 || link.elapsed().saturating_sub(t0) >= timeout || link.elapsed() == before {
                    break buf.len();
                }
            }
        } else {
            loop {
                if let Some(e) = end(&buf) {
                    break e;
                }
                if buf.len() > MAX_STEP_ANSWER {
                    flooded = true;
                    break MAX_STEP_ANSWER;
                }
                let spent = link.elapsed().saturating_sub(t0);
                if spent >= timeout {
                    timed_out = true;
                    break buf.len();
                }
                let before = link.elapsed();
                let n = link.recv(&mut buf, timeout - spent)?;
                if n == 0 && link.elapsed() == before {
                    timed_out = true;
                    break buf.len();
                }
            }
        };
        self.carry = buf.split_off(cut);
        Ok(Captured {
            sent,
            output: buf,
            took: link.elapsed().saturating_sub(t0),
            realtime: was_loop,
            layout,
            timed_out,
            flooded,
        })
    }
}

/// What the recorder's shadow model makes of one step: whether the step was sent in RealTime
/// mode and with which layouts, the shadow's answer (whose size ends a RealTime answer), and
/// whether the step entered the loop and stayed in it.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowStep {
    /// Whether the shadow was in RealTime mode when the bytes were sent.
    pub was_loop: bool,
    /// The shadow's RealTime layouts then.
    pub layout: Option<RtLayout>,
    /// The shadow's answer.
    pub out: Vec<u8>,
    /// Whether the step entered the loop and stayed in it.
    pub entered_loop: bool,
}

/// The recorder's shadow's run of a step whose pause has passed: the step's bytes, then (unless
/// the step ends on quiet) the model run until it is idle; its output and events are taken.
pub fn shadow_step(shadow: &mut Device, step: &ScriptStep, terminator: u8) -> ShadowStep {
    let sent = step.action.wire_bytes(terminator);
    let was_loop = shadow.mode() == Mode::Loop;
    let layout = shadow.rt_layout().cloned();
    shadow.clear_output();
    shadow.handle_input(shadow.now(), &sent);
    if !step.action.ends_on_quiet() {
        shadow.run_until_idle(Duration::from_secs(600));
    }
    let out = shadow.take_output();
    // Whether this step entered the loop (and stayed in it), from what the shadow reports.
    let mut in_loop = was_loop;
    while let Some(e) = shadow.poll_event() {
        match e {
            Event::LoopEntered => in_loop = true,
            Event::LoopLeft => in_loop = false,
            Event::PoweredUp | Event::LineDone(_) => {}
        }
    }
    ShadowStep { was_loop, layout, out, entered_loop: !was_loop && in_loop }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() || hay.len() < needle.len() {
        return None;
    }
    hay.windows(needle.len()).position(|w| w == needle)
}

/// The `within` to write for a step: enough for a slow hand (twice the time it took plus twice
/// the wire time of its bytes at 9600 baud, plus a second), at least 30 s for a line that moves
/// motors (or a `wait`), 10 s for RESET; `None` when [`DEFAULT_STEP_TIMEOUT`] is enough.
pub fn suggest_within(
    profile: &Profile,
    action: &Action,
    sent: &[u8],
    took: Duration,
    output_len: usize,
) -> Option<Duration> {
    let wire = byte_time(9600) * (output_len + sent.len()).min(1 << 20) as u32;
    let mut need = took.saturating_mul(2) + wire * 2 + Duration::from_secs(1);
    let floor = |need: &mut Duration, d: Duration| *need = (*need).max(d);
    if matches!(action, Action::Wait) {
        floor(&mut need, Duration::from_secs(30));
    }
    for line in sent.split(|b| *b == profile.framing.terminator) {
        if let Ok(Line::Command(c)) = grammar::parse_line(profile, line) {
            let kind = c.kind(profile);
            if kind.is_motion() || kind == CommandKind::Initialize {
                floor(&mut need, Duration::from_secs(30));
            } else if kind == CommandKind::Reset {
                floor(&mut need, Duration::from_secs(10));
            }
        }
    }
    let secs = need.as_millis().div_ceil(1000);
    let d = Duration::from_secs(u64::try_from(secs).unwrap_or(u64::MAX).min(gcl_transcript::MAX_DURATION.as_secs()));
    (d > DEFAULT_STEP_TIMEOUT).then_some(d)
}

/// The expectation for an answer that carries a banner: the bytes before the first line break
/// exactly (the echo), then `{any}BarrettHand Firmware{any}`, then the closing line ending and
/// prompt exactly. `None` if the answer has no banner text or does not end with the prompt.
pub fn banner_expect(output: &[u8], eol_prompt: &[u8]) -> Option<Expect> {
    let at = find(output, BANNER_TEXT)?;
    if !output.ends_with(eol_prompt) || output.len() < at + BANNER_TEXT.len() + eol_prompt.len() {
        return None;
    }
    let echo_end = output.iter().position(|b| *b == b'\n' || *b == b'\r').unwrap_or(at).min(at);
    let mut e = Expect::default();
    e.push_bytes(Form::Text, &output[..echo_end]);
    e.push(Form::Text, Piece::Any);
    e.push_bytes(Form::Text, BANNER_TEXT);
    e.push(Form::Text, Piece::Any);
    e.push_bytes(Form::Text, eol_prompt);
    Some(e)
}

/// How a captured answer is written: hex for RealTime answers that are not supervisory text
/// (no prompt), an escaped string otherwise.
pub fn answer_form(c: &Captured, eol_prompt: &[u8]) -> Form {
    if c.realtime && find(&c.output, eol_prompt).is_none() { Form::Hex } else { Form::Text }
}

/// The transcript step for a script step and what it captured, with the exact answer (or the
/// banner elided, per `opts`).
pub fn step_from(step: &ScriptStep, c: &Captured, opts: &RecordOptions) -> Step {
    let profile = &opts.profile;
    let eol_prompt: Vec<u8> = [profile.framing.line_ending.as_bytes(), profile.framing.prompt.as_bytes()].concat();
    let send = match &step.action {
        Action::Wait => None,
        Action::Bytes { form, .. } => Some(HostBytes { bytes: c.sent.clone(), form: *form }),
        _ => Some(HostBytes::text(c.sent.clone())),
    };
    let form = answer_form(c, &eol_prompt);
    let expect = match (opts.elide_banner, banner_expect(&c.output, &eol_prompt)) {
        (true, Some(e)) => e,
        _ if form == Form::Hex => Expect::hex(&c.output),
        _ => Expect::text(&c.output),
    };
    let within = suggest_within(profile, &step.action, &c.sent, c.took, c.output.len());
    Step { line: 0, comments: step.comments.clone(), pause: step.pause, send, within, earliest: None, expect }
}

/// Why a recording failed.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The link failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// A step got no complete answer before its timeout.
    #[error("step {step} (script line {line}): no complete answer within {timeout:?}; got {got}")]
    Timeout {
        /// The step, 0-based.
        step: usize,
        /// Its script line.
        line: usize,
        /// Its capture timeout.
        timeout: Duration,
        /// What arrived, escaped and quoted (at most its first 200 bytes, then a note of the rest).
        got: String,
    },
    /// A step's answer passed [`MAX_STEP_ANSWER`]: the hand floods.
    #[error(
        "step {step} (script line {line}): the hand sent more than {limit} bytes without ending its answer (a flood); \
it began {head}"
    )]
    Flooded {
        /// The step, 0-based.
        step: usize,
        /// Its script line.
        line: usize,
        /// The ceiling passed, bytes.
        limit: usize,
        /// The answer's first 200 bytes, escaped and quoted.
        head: String,
    },
}

/// The first [`SHOWN_IN_ERRORS`] bytes of an answer, escaped and quoted, with a note of how many more
/// there were: an error message never carries a flood.
fn shown(bytes: &[u8]) -> String {
    let head = gcl_transcript::escape_text(&bytes[..bytes.len().min(SHOWN_IN_ERRORS)]);
    match bytes.len().checked_sub(SHOWN_IN_ERRORS) {
        Some(more) if more > 0 => format!("\"{head}\" and {more} more bytes"),
        _ => format!("\"{head}\""),
    }
}

/// Records a script: runs it, then writes each answer down. With `allow_timeouts`, a step that
/// times out keeps what arrived; otherwise it is an error.
pub fn record(
    link: &mut dyn Link,
    header: Header,
    script: &Script,
    opts: &RecordOptions,
    allow_timeouts: bool,
) -> Result<(Transcript, Vec<Captured>), RecordError> {
    let captured = capture(link, &script.steps, opts)?;
    if let Some((i, c)) = captured.iter().enumerate().find(|(_, c)| c.flooded) {
        return Err(RecordError::Flooded {
            step: i,
            line: script.steps[i].line,
            limit: MAX_STEP_ANSWER,
            head: shown(&c.output[..c.output.len().min(SHOWN_IN_ERRORS)]),
        });
    }
    if !allow_timeouts && let Some((i, c)) = captured.iter().enumerate().find(|(_, c)| c.timed_out) {
        let s = &script.steps[i];
        return Err(RecordError::Timeout {
            step: i,
            line: s.line,
            timeout: s.timeout.unwrap_or(opts.timeout),
            got: shown(&c.output),
        });
    }
    let steps = script.steps.iter().zip(&captured).map(|(s, c)| step_from(s, c, opts)).collect();
    Ok((Transcript { header, steps }, captured))
}

#[cfg(test)]
mod tests {
    use super::*;
    use gcl_host::SimLink;

    #[test]
    fn records_lines_loops_blocks_and_banners() {
        let p = Profile::builtin("seed").unwrap();
        let mut link = SimLink::new(p.clone(), DeviceConfig::default());
        let steps: Vec<ScriptStep> = [
            Action::abort(),
            Action::Line(b"RESET".to_vec()),
            Action::Line(b"HI".to_vec()),
            Action::Line(b"1FSET LCV 0 LCPG 0 LFV 0 LFS 0 LFAP 1 LFDP 0".to_vec()),
            Action::Line(b"1LOOP".to_vec()),
            Action::Bytes { bytes: b"A".to_vec(), form: Form::Hex },
            Action::abort(),
        ]
        .into_iter()
        .map(ScriptStep::new)
        .collect();
        let opts = RecordOptions::new(p.clone());
        let caps = capture(&mut link, &steps, &opts).unwrap();
        assert!(caps.iter().all(|c| !c.timed_out));
        assert_eq!(caps[0].output, b"\n\r=> ");
        assert_eq!(caps[2].output, b"HI\n\r=> ");
        assert_eq!(caps[4].output, b"1LOOP*");
        assert_eq!(caps[5].output, [b'*', 0, 0]);
        assert!(caps[5].realtime);
        assert_eq!(caps[6].output, b"\n\r=> ");
        let s = step_from(&steps[1], &caps[1], &opts);
        assert_eq!(s.expect.to_text(), "\"RESET{any}BarrettHand Firmware{any}\\n\\r=> \"");
        assert_eq!(s.within, Some(Duration::from_secs(10)));
        let s = step_from(&steps[5], &caps[5], &opts);
        assert_eq!(s.expect.to_text(), "hex 2A 00 00");
        assert_eq!(step_from(&steps[2], &caps[2], &opts).within, Some(Duration::from_secs(30)));
    }

    #[test]
    fn a_step_ends_at_the_first_prompt_and_the_rest_carries_over() {
        let p = Profile::builtin("seed").unwrap();
        let mut link = SimLink::new(p.clone(), DeviceConfig::default());
        let steps = vec![
            ScriptStep::new(Action::Bytes { bytes: b"FGET DP\rFGET DS\r".to_vec(), form: Form::Text }),
            ScriptStep::new(Action::Wait),
        ];
        let caps = capture(&mut link, &steps, &RecordOptions::new(p)).unwrap();
        assert_eq!(caps[0].output, b"FGET DP\n\r1000 1000 1000 150\n\r=> ");
        assert_eq!(caps[1].output, b"FGET DS\n\r1200 1200 1200 150\n\r=> ");
    }
}
