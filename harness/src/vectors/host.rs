//! `host`: byte streams a hand sends after a host's request, and what the host must make of
//! them: an answer with its lines, a refusal with its status, a feedback block's values, an
//! acknowledgement, a prompt, a violation of GCL, or an incomplete answer (the host must
//! keep waiting, and a deadline ends it). Streams of well-formed answers come from the model;
//! violations are those answers broken one way each.
//!
//! The oracle is the host client core; [`outcome`] is the only function that touches it, so
//! a change in the core's types changes one place here.

use std::time::Duration;

use gcl_model::realtime::{Control, ControlHeader};
use gcl_model::{Device, MotorSet, Profile, RtLayout};
use serde_json::{Value, json};

use super::layout::{block_json, layout_with};
use super::{FileBuilder, Test, VectorsError};
use gcl_transcript::hex_bytes;

/// What the host asked.
#[derive(Debug, Clone)]
enum Request {
    /// A supervisory command line (sent with a CR).
    Command(String),
    /// A LOOP line, whose loop will have this layout.
    Loop(String, RtLayout),
    /// In RealTime mode (entered with this layout), a block with this header; control values
    /// are zeros.
    Block(ControlHeader, RtLayout),
    /// ^C while idle or while a motion runs.
    Abort,
    /// ^C in RealTime mode.
    AbortLoop(RtLayout),
}

/// The bytes a request sent, what the host made of the stream, and how many bytes it read.
type Read = (Vec<u8>, (Value, bool), usize);

/// One host test before the oracle runs: id, comment, request, stream, flags.
struct HostCase {
    id: String,
    comment: String,
    request: Request,
    stream: Vec<u8>,
    flags: Vec<&'static str>,
}

/// What a host makes of `stream` after `request`, as the test's `sent` and `outcome`; and
/// whether it is a GCL answer (as opposed to a violation or an incomplete answer).
///
/// The stream is fed one byte at a time and then all at once; both must agree.
fn outcome(p: &Profile, request: &Request, stream: &[u8]) -> Result<(Vec<u8>, Value, bool), VectorsError> {
    use gcl_host::client::core::{Answer, Framing, HostCore, Misuse, Refusal, Violation};
    let start = |core: &mut HostCore| -> Result<Vec<u8>, String> {
        let enter = |core: &mut HostCore, l: &RtLayout| -> Result<(), String> {
            core.start_loop("123LOOP", l.clone()).map_err(|e: Misuse| e.to_string())?;
            core.handle_input(b"123LOOP*");
            core.poll().map_err(|e| e.to_string())?;
            Ok(())
        };
        match request {
            Request::Command(line) => core.command(line).map_err(|e| e.to_string()),
            Request::Loop(line, l) => core.start_loop(line, l.clone()).map_err(|e| e.to_string()),
            Request::Block(h, l) => {
                enter(core, l)?;
                core.block(&Control::zeroed(*h, l.control())).map_err(|e| e.to_string())
            }
            Request::Abort => Ok(core.abort()),
            Request::AbortLoop(l) => {
                enter(core, l)?;
                Ok(core.abort())
            }
        }
    };
    let map = |r: Result<Option<Answer>, Violation>| -> (Value, bool) {
        match r {
            Ok(Some(Answer::Done(lines))) => (json!({ "kind": "lines", "lines": lines }), true),
            Ok(Some(Answer::LoopStarted)) => (json!({ "kind": "loop-started" }), true),
            Ok(Some(Answer::Feedback(feedback))) => {
                let values = match request {
                    Request::Block(_, l) => feedback.values(l.feedback()),
                    _ => Vec::new(),
                };
                (json!({ "kind": "feedback", "values": values }), true)
            }
            Ok(Some(Answer::Ack)) => (json!({ "kind": "ack" }), true),
            Ok(Some(Answer::Prompt(lines))) => (json!({ "kind": "prompt", "lines": lines }), true),
            Ok(Some(Answer::Refused(Refusal { code, lines, .. }))) => {
                (json!({ "kind": "refusal", "status": code, "lines": lines }), true)
            }
            Ok(None) => (json!({ "kind": "incomplete" }), false),
            Err(Violation::EchoMismatch { .. }) => (json!({ "kind": "violation", "violation": "echo" }), false),
            Err(_) => (json!({ "kind": "violation", "violation": "framing" }), false),
        }
    };
    let run = |chunk: usize| -> Result<Read, VectorsError> {
        let mut core = HostCore::new(Framing::of(p));
        let sent = start(&mut core).map_err(|e| VectorsError::Generate(format!("{request:?}: {e}")))?;
        let mut used = 0;
        for piece in stream.chunks(chunk.max(1)) {
            core.handle_input(piece);
            used += piece.len();
            match core.poll() {
                Ok(None) => {}
                other => return Ok((sent, map(other), used)),
            }
        }
        Ok((sent, map(Ok(None)), used))
    };
    let (sent, (v, ok), used) = run(1)?;
    let (_, (whole, _), _) = run(stream.len())?;
    if whole != v {
        return Err(VectorsError::Generate(format!(
            "{request:?}: the core reads {} differently byte by byte and whole",
            hex_bytes(stream)
        )));
    }
    let mut v = v;
    if let Value::Object(m) = &mut v {
        // Bytes of the stream the answer took (all of it unless the answer ended early).
        m.insert("length".into(), json!(used));
    }
    Ok((sent, v, ok))
}

/// The model's answer to `lines` sent one after the other to a fresh hand: the answer to
/// the last one.
fn answer(p: &std::sync::Arc<Profile>, lines: &[&str]) -> Vec<u8> {
    let mut hand = Device::with_profile(p.clone());
    hand.clear_output();
    let mut now = Duration::ZERO;
    let mut out = Vec::new();
    for l in lines {
        hand.handle_input(now, format!("{l}\r").as_bytes());
        now = hand.run_until_idle(now + Duration::from_secs(60));
        out = hand.take_output();
    }
    out
}

fn replace(hay: &[u8], from: &[u8], to: &[u8], once: bool) -> Vec<u8> {
    let mut out = Vec::new();
    let mut i = 0;
    let mut done = false;
    while i < hay.len() {
        if !(once && done) && hay[i..].starts_with(from) {
            out.extend_from_slice(to);
            i += from.len();
            done = true;
        } else {
            out.push(hay[i]);
            i += 1;
        }
    }
    out
}

fn request_json(r: &Request) -> Value {
    let layout = |l: &RtLayout| {
        json!({
            "motors": l.motors().iter().collect::<Vec<u8>>(),
            "control": block_json(l.control()),
            "feedback": block_json(l.feedback()),
        })
    };
    match r {
        Request::Command(line) => json!({ "kind": "command", "line": line }),
        Request::Loop(line, l) => json!({ "kind": "loop", "line": line, "layout": layout(l) }),
        Request::Block(h, l) => {
            json!({ "kind": "block", "header": (h.byte() as char).to_string(), "layout": layout(l) })
        }
        Request::Abort => json!({ "kind": "abort" }),
        Request::AbortLoop(l) => json!({ "kind": "abort-loop", "layout": layout(l) }),
    }
}

/// The `host` file: the model's answers → refusals → those answers broken → RealTime → ^C,
/// each case then run through the oracle ([`outcome`]) into a test.
pub(crate) fn build(b: &mut FileBuilder<'_>) -> Result<(), VectorsError> {
    let p = b.profile();
    let mut tests = HostCases::default();
    let fget = answer(p, &["FGET DP"]);
    answer_cases(p, &fget, &mut tests);
    refusal_cases(p, &mut tests);
    violation_cases(&fget, &mut tests);
    realtime_cases(p, &mut tests)?;
    abort_cases(&mut tests);
    for HostCase { id, comment, request: r, stream, flags } in tests.0 {
        let (sent, out, ok) = outcome(p, &r, &stream)?;
        let body = json!({
            "request": request_json(&r),
            "sent": hex_bytes(&sent),
            "stream": hex_bytes(&stream),
            "outcome": out,
        });
        b.push(Test::new(format!("host-{id}"), comment, ok, body).flags(&flags))?;
    }
    Ok(())
}

/// The host cases in the order they are written.
#[derive(Default)]
struct HostCases(Vec<HostCase>);

impl HostCases {
    /// Takes one case; keeps it after those before.
    fn add(&mut self, id: &str, comment: &str, request: Request, stream: Vec<u8>, flags: &[&'static str]) {
        self.0.push(HostCase { id: id.into(), comment: comment.into(), request, stream, flags: flags.to_vec() });
    }
}

/// A supervisory command line as a request.
fn cmd(s: &str) -> Request {
    Request::Command(s.to_string())
}

/// The flags of a case about the echo.
const ECHO: [&str; 1] = ["framing-echo"];

/// Takes the profile and the model's answer to FGET DP; adds the model's answers.
fn answer_cases(p: &std::sync::Arc<Profile>, fget: &[u8], t: &mut HostCases) {
    // Answers, from the model.
    t.add("answer-one-line", "FGET DP: the echo, one line, the prompt", cmd("FGET DP"), fget.to_vec(), &ECHO);
    t.add(
        "answer-two-lines",
        "FGET DP DS: one line per name",
        cmd("FGET DP DS"),
        answer(p, &["FGET DP DS"]),
        &["framing-echo", "seed-fget-format", "bh8-fget-format"],
    );
    t.add(
        "answer-no-lines",
        "FSET DP 100: the echo and the prompt",
        cmd("FSET DP 100"),
        answer(p, &["FSET DP 100"]),
        &ECHO,
    );
    t.add(
        "answer-empty-line",
        "a bare CR: no echo, a fresh prompt",
        cmd(""),
        answer(p, &[""]),
        &["framing-empty-line"],
    );
    t.add(
        "answer-echo-keeps-case",
        "the echo keeps the case that was sent",
        cmd("fget dp"),
        answer(p, &["fget dp"]),
        &["framing-echo", "framing-case"],
    );
    t.add("answer-version", "VERS: lines of text", cmd("VERS"), answer(p, &["VERS"]), &["bh8-vers-text"]);
    t.add(
        "answer-err-describes",
        "ERR 192: one line per bit",
        cmd("ERR 192"),
        answer(p, &["ERR 192"]),
        &["seed-err-command", "bh8-err-format"],
    );
}

/// Takes the profile; adds the model's refusals, and one with a status bit GCL does not define.
fn refusal_cases(p: &std::sync::Arc<Profile>, t: &mut HostCases) {
    // Refusals, from the model.
    t.add("refusal-unknown-command", "BOGUS is refused with 32", cmd("BOGUS"), answer(p, &["BOGUS"]), &ECHO);
    t.add("refusal-read-only", "FSET P 5 is refused with 256", cmd("FSET P 5"), answer(p, &["FSET P 5"]), &ECHO);
    t.add(
        "refusal-combined",
        "FSET NOPE 1 DP 99999 is refused with 192",
        cmd("FSET NOPE 1 DP 99999"),
        answer(p, &["FSET NOPE 1 DP 99999"]),
        &["framing-errors-combine"],
    );
    t.add(
        "refusal-before-hi",
        "C before HI is refused with 4",
        cmd("C"),
        answer(p, &["C"]),
        &["seed-motion-before-hi", "bh8-motion-before-hi"],
    );
    t.add(
        "refusal-unknown-bit",
        "a status with a bit GCL does not define is still a refusal, with its number",
        cmd("BOGUS"),
        b"BOGUS\n\rERR 32768\n\r=> ".to_vec(),
        &[],
    );
}

/// Takes the model's answer to FGET DP; adds it broken one way each, and incomplete.
fn violation_cases(fget: &[u8], t: &mut HostCases) {
    // Violations: the FGET DP answer broken one way each.
    t.add(
        "violation-echo-wrong",
        "the echo differs from the line sent",
        cmd("FGET DP"),
        replace(fget, b"FGET DP", b"FGET DQ", true),
        &ECHO,
    );
    t.add(
        "violation-echo-missing",
        "no echo: the answer starts with the line break",
        cmd("FGET DP"),
        replace(fget, b"FGET DP", b"", true),
        &ECHO,
    );
    t.add("violation-crlf", "CR LF instead of LF CR", cmd("FGET DP"), replace(fget, b"\n\r", b"\r\n", false), &ECHO);
    t.add(
        "violation-lf-only",
        "LF alone as the line break",
        cmd("FGET DP"),
        replace(fget, b"\n\r", b"\n", false),
        &ECHO,
    );
    t.add(
        "violation-missing-line-break",
        "the line break after the echo is missing",
        cmd("FGET DP"),
        replace(fget, b"\n\r", b"", true),
        &ECHO,
    );
    t.add(
        "violation-status-without-number",
        "ERR with no number",
        cmd("BOGUS"),
        b"BOGUS\n\rERR \n\r=> ".to_vec(),
        &ECHO,
    );
    t.add(
        "violation-status-not-a-number",
        "ERR with a word for a number",
        cmd("BOGUS"),
        b"BOGUS\n\rERR x\n\r=> ".to_vec(),
        &ECHO,
    );
    t.add(
        "incomplete-prompt-without-space",
        "`=>` without its space is not a prompt: the host keeps waiting",
        cmd("FGET DP"),
        fget[..fget.len() - 1].to_vec(),
        &ECHO,
    );
    t.add("incomplete-echo-only", "the echo and nothing else", cmd("FGET DP"), b"FGET DP".to_vec(), &ECHO);
}

/// Takes the profile; adds the RealTime cases (LOOP, feedback blocks, acknowledgements, ^C in
/// the loop) when its layouts have LCV and LFAP.
fn realtime_cases(p: &std::sync::Arc<Profile>, t: &mut HostCases) -> Result<(), VectorsError> {
    // RealTime.
    let names: Vec<String> = super::layout::rt_flags(p);
    let has = |n: &str| names.iter().any(|x| x == n);
    if has("LCV") && has("LFAP") {
        let l = layout_with(p, MotorSet::FINGERS, &["LCV", "LFAP"]);
        let rt = ["seed-rt-feedback-order", "seed-rt-field-order", "bh8-44-rt-field-order"];
        t.add(
            "loop-started",
            "LOOP answered by its echo and `*`",
            Request::Loop("123LOOP".into(), l.clone()),
            b"123LOOP*".to_vec(),
            &["bh8-loop-motors"],
        );
        t.add(
            "loop-refused-before-hi",
            "LOOP before HI is refused",
            Request::Loop("123LOOP".into(), l.clone()),
            answer(p, &["123LOOP"]),
            &["bh8-loop-failure", "seed-motion-before-hi", "bh8-motion-before-hi"],
        );
        t.add(
            "violation-loop-lines",
            "LOOP answered by a prompt, neither `*` nor ERR",
            Request::Loop("123LOOP".into(), l.clone()),
            b"123LOOP\n\r=> ".to_vec(),
            &["bh8-loop-failure"],
        );
        let mut fb = Vec::new();
        l.feedback().encode(b'*', &[5000, 0, 65535], &mut fb).map_err(|e| VectorsError::Generate(e.to_string()))?;
        t.add(
            "feedback-block",
            "a feedback block: `*` then LFAP of motors 1, 2, 3, high byte first",
            Request::Block(ControlHeader::DataFeedback, l.clone()),
            fb.clone(),
            &rt,
        );
        t.add(
            "feedback-after-a",
            "`A` asks for feedback without control data",
            Request::Block(ControlHeader::Feedback, l.clone()),
            fb.clone(),
            &rt,
        );
        t.add(
            "incomplete-short-block",
            "a feedback block one byte short: the host keeps waiting",
            Request::Block(ControlHeader::DataFeedback, l.clone()),
            fb[..fb.len() - 1].to_vec(),
            &rt,
        );
        t.add(
            "violation-block-header",
            "a feedback block must start with `*`",
            Request::Block(ControlHeader::DataFeedback, l.clone()),
            replace(&fb, b"*", b"#", true),
            &rt,
        );
        t.add("ack", "`a` is answered by `*` alone", Request::Block(ControlHeader::Ack, l.clone()), b"*".to_vec(), &rt);
        t.add(
            "ack-after-c",
            "`c` is answered by `*` alone",
            Request::Block(ControlHeader::DataAck, l.clone()),
            b"*".to_vec(),
            &rt,
        );
        t.add(
            "refusal-bad-header",
            "ERR 2048 in RealTime mode: back to supervisory mode",
            Request::Block(ControlHeader::Feedback, l.clone()),
            b"\n\rERR 2048\n\r=> ".to_vec(),
            &[],
        );
        t.add(
            "violation-loop-ended-silently",
            "a prompt in RealTime mode without an ERR line",
            Request::Block(ControlHeader::Feedback, l.clone()),
            b"\n\r=> ".to_vec(),
            &[],
        );
        t.add(
            "abort-loop",
            "^C leaves the loop with a prompt",
            Request::AbortLoop(l.clone()),
            b"\n\r=> ".to_vec(),
            &["bh8-abort-loop"],
        );
        t.add(
            "abort-loop-with-status",
            "^C leaves the loop with ERR 16384 and a prompt",
            Request::AbortLoop(l.clone()),
            b"\n\rERR 16384\n\r=> ".to_vec(),
            &["bh8-abort-loop"],
        );
        let all: Vec<&str> = names.iter().map(String::as_str).collect();
        let big = layout_with(p, MotorSet::ALL, &all);
        let values: Vec<i64> = big
            .feedback()
            .fields()
            .iter()
            .enumerate()
            .map(|(i, f)| if i % 2 == 0 { f.min() } else { f.max() })
            .collect();
        let mut fb = Vec::new();
        big.feedback().encode(b'*', &values, &mut fb).map_err(|e| VectorsError::Generate(e.to_string()))?;
        t.add(
            "feedback-every-field",
            "every feedback flag on all motors, each field at an edge of its type",
            Request::Block(ControlHeader::Feedback, big),
            fb,
            &rt,
        );
    }
    Ok(())
}

/// Adds ^C while idle and during a motion.
fn abort_cases(t: &mut HostCases) {
    t.add("abort-idle", "^C while idle: a fresh prompt", Request::Abort, b"\n\r=> ".to_vec(), &["framing-abort-idle"]);
    t.add(
        "abort-motion",
        "^C during a motion: ERR 16384 then the prompt",
        Request::Abort,
        b"\n\rERR 16384\n\r=> ".to_vec(),
        &["bh8-abort-motion", "seed-abort"],
    );
}
