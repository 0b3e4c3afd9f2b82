//! The framing pre-flight: before a suite, a probe of a few exchanges that names gross
//! framing faults in one line ("the hand's prompt is `=>` without the trailing space"), so a
//! team whose firmware breaks its prompt learns it from the first second of a run instead of
//! from 200 failures. The suite still runs afterwards, so every affected case is listed.
//!
//! The probe sends ^C, a bare CR, an unknown command word (its answer shows the echo and the
//! status format), VERS and RESET (its answer shows the banner), the same to the in-process
//! model and to the hand, and compares what came back: line ending, prompt text, echo, status
//! line shape, banner text; and who the hand says it is (the firmware series its VERS answer
//! and banner name, against the profile's: [`crate::identity`]). An answer that is the model's,
//! byte for byte, is complete: the next probe goes out once the line stays quiet for
//! `TRAILING` after it (bytes within it are that answer's, read on to a quiet); any other
//! answer, and RESET's, is read until the hand is quiet (`QUIET` after a prompt), within a
//! deadline from the model ([`crate::deadline`]), keeping at most [`MAX_ANSWER`] bytes. Bytes a
//! hand sends later than that land at the head of the next probe's answer, which then differs
//! from the model's and is read to a quiet: the last, RESET's, always is.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::escape::escape;
use gcl_model::spec::CommandKind;
use gcl_model::{DeviceConfig, Profile};

use crate::deadline::DeadlinePolicy;
use crate::replay::discard;
use gcl_host::link::{Link, LinkError, SimLink};

/// The most bytes of one probe answer kept.
pub const MAX_ANSWER: usize = 4096;

/// The longest the RESET probe waits for an answer that ends in a prompt.
const RESET_WAIT: Duration = Duration::from_secs(10);

/// How long the hand must be quiet for an answer to count as complete.
const QUIET: Duration = Duration::from_millis(60);

/// How long an answer that is already the model's is watched for more bytes: as long as the
/// runner watches after a case's last answer (`conform`'s trailing wait).
const TRAILING: Duration = Duration::from_millis(2);

/// The banner text hosts look for after RESET (see `shared/protocol-notes.md`).
const BANNER_TEXT: &[u8] = b"BarrettHand Firmware";

/// An unknown command word: it changes nothing, and its answer carries an error status.
pub const UNKNOWN: &[u8] = b"ZZQX";

/// What the pre-flight found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Preflight {
    /// Gross framing faults, one phrase each; empty when the framing is as the profile says.
    pub findings: Vec<String>,
    /// The clauses those faults break, first found first (`decision:framing-line-ending`),
    /// where the profile states one: failures of framing take them as their clause.
    pub clauses: Vec<String>,
    /// Whether the last answer ended in a prompt followed by 60 ms of silence: the line is
    /// then already drained, and a runner need not wait for quiet again.
    pub settled: bool,
    /// The hand named another firmware series than the profile models, in its banner or its
    /// `VERS` answer: the line that says so ([`crate::identity::mismatch`]).
    pub identity: Option<String>,
    /// Bytes sent and received, probe by probe, for a runner's wire-time bound.
    pub exchanged: Vec<(u64, u64)>,
}

impl Preflight {
    /// The one line printed at the top of the console output and of every report.
    pub fn line(&self) -> String {
        if self.findings.is_empty() {
            "pre-flight: framing as the profile says (echo, line ending, prompt, status format, banner)".to_string()
        } else {
            format!("pre-flight: {}", self.findings.join("; "))
        }
    }
}

struct Probe {
    send: Vec<u8>,
    what: &'static str,
}

fn probes(profile: &Profile) -> Vec<Probe> {
    let t = profile.framing.terminator;
    let vers = profile.command_of_kind(CommandKind::Version).map_or("VERS", |id| profile.command(id).name.as_str());
    vec![
        Probe { send: vec![profile.framing.abort], what: "^C" },
        Probe { send: vec![t], what: "a bare CR" },
        Probe { send: [UNKNOWN, &[t]].concat(), what: "an unknown command" },
        Probe { send: [vers.as_bytes(), &[t]].concat(), what: "VERS" },
        Probe { send: [b"RESET".as_slice(), &[t]].concat(), what: "RESET" },
    ]
}

/// Reads until the link has been quiet for [`QUIET`] after something prompt-like (ending in
/// `prompt`), or quiet after at least `min` has passed (`None`: only after a prompt), or until
/// `deadline`, keeping at most [`MAX_ANSWER`] bytes; or, with `complete`, as soon as what came
/// is exactly that (the model's whole answer, ending in its prompt: nothing is left to wait
/// for). Also says whether it ended on a prompt and a whole [`QUIET`] of silence after it.
fn collect(
    link: &mut dyn Link,
    min: Option<Duration>,
    deadline: Duration,
    prompt: &[u8],
    complete: Option<&[u8]>,
) -> Result<(Vec<u8>, bool), LinkError> {
    let start = link.elapsed();
    let mut got = Vec::new();
    let mut settled = false;
    loop {
        let spent = link.elapsed().saturating_sub(start);
        if spent >= deadline || got.len() >= MAX_ANSWER {
            break;
        }
        let wait = QUIET.min(deadline - spent);
        let n = link.recv(&mut got, wait)?;
        // The model's whole answer: done, unless more follows at once (looked for as long as a
        // case looks after its last answer), which then belongs to this answer, not the next.
        if complete.is_some_and(|c| !c.is_empty() && got == c) && link.recv(&mut got, TRAILING)? == 0 {
            break;
        }
        let spent = link.elapsed().saturating_sub(start);
        let prompt_like = !prompt.is_empty() && got.trim_ascii_end().ends_with(prompt);
        if n == 0 && !got.is_empty() && (prompt_like || min.is_some_and(|m| spent >= m)) {
            settled = prompt_like && wait == QUIET;
            break;
        }
    }
    got.truncate(MAX_ANSWER);
    Ok((got, settled))
}

/// Runs the probe on `link` (at an idle prompt) and compares with the model. The hand is left
/// after a RESET, at an idle prompt.
pub fn run(link: &mut dyn Link, profile: &Arc<Profile>, policy: &DeadlinePolicy) -> Result<Preflight, LinkError> {
    let mut model = SimLink::new(profile.clone(), DeviceConfig::default());
    discard(&mut model, Duration::from_millis(50), Duration::from_secs(1))?;
    let mut findings = Vec::new();
    let mut answers = Vec::new();
    let trimmed = profile.framing.prompt.trim_end().as_bytes();
    let mut settled = false;
    for p in probes(profile) {
        let t0 = model.elapsed();
        model.send(&p.send)?;
        let (expected, _) = collect(&mut model, Some(Duration::ZERO), Duration::from_secs(30), b"", None)?;
        let predicted = model.elapsed().saturating_sub(t0);
        link.send(&p.send)?;
        let actual;
        (actual, settled) = if p.what == "RESET" {
            // A power cycle: a real hand may take seconds before its banner; wait for a prompt.
            // The last probe: its answer is read to a whole [`QUIET`] after the prompt, so the
            // line is known drained (`settled`) and any bytes the hand sends after the
            // exchanges so far land here.
            collect(link, None, RESET_WAIT, trimmed, None)?
        } else {
            // An answer the same as the model's, byte for byte, is complete (it ends in the
            // prompt): the next probe goes out at once. Anything else is read to a quiet.
            let deadline = policy.deadline(predicted).max(policy.silent_wait);
            let complete = expected.ends_with(profile.framing.prompt.as_bytes()).then_some(expected.as_slice());
            collect(link, Some(policy.deadline(predicted).min(deadline)), deadline, trimmed, complete)?
        };
        let silent = actual.is_empty();
        answers.push((p, expected, actual));
        if silent {
            // A hand that says nothing at all says nothing to the rest either.
            let what = answers.last().map_or("", |(p, _, _)| p.what);
            return Ok(Preflight {
                findings: vec![format!("no answer to {what}; the hand may have stopped answering")],
                clauses: Vec::new(),
                settled: false,
                identity: None,
                exchanged: exchanged(&answers),
            });
        }
    }
    let fr = &profile.framing;
    let eol = fr.line_ending.as_bytes();
    let prompt = fr.prompt.as_bytes();
    let mut clauses = Vec::new();
    // The profile's decision with this id (or, for a suffix, the first whose id ends so).
    let decision = |want: &str| -> Option<String> {
        profile
            .decisions
            .iter()
            .find(|d| d.id == want || want.starts_with('-') && d.id.ends_with(want))
            .map(|d| format!("decision:{}", d.id))
    };

    // The bare CR's answer: line ending, then prompt.
    let (_, _, cr) = &answers[1];
    let mut hand_eol: Vec<u8> = cr.iter().copied().take_while(|b| matches!(b, b'\n' | b'\r')).collect();
    if cr.is_empty() {
        findings.push("no answer to a bare CR".to_string());
    } else {
        let hand_prompt = &cr[hand_eol.len()..];
        if hand_eol != eol {
            clauses.extend(decision("framing-line-ending"));
            findings.push(if hand_eol.is_empty() {
                format!("the prompt comes without a line ending in front (expected `{}`)", escape(eol))
            } else {
                format!("lines end in `{}` instead of `{}`", escape(&hand_eol), escape(eol))
            });
        }
        if hand_prompt != prompt {
            clauses.extend(decision("framing-prompt"));
            let trimmed = fr.prompt.trim_end().as_bytes();
            findings.push(if hand_prompt == trimmed {
                format!("the hand's prompt is `{}` without the trailing space", escape(hand_prompt))
            } else {
                format!("the hand's prompt is `{}`, not `{}`", escape(hand_prompt), escape(prompt))
            });
        }
    }
    if hand_eol.is_empty() {
        hand_eol = eol.to_vec();
    }

    // The unknown command: echo, then the status line.
    let (p, expected, actual) = &answers[2];
    let word = &p.send[..p.send.len() - 1];
    let echoes = expected.starts_with(word);
    if echoes && !actual.is_empty() && !actual.starts_with(word) {
        clauses.extend(decision("framing-echo"));
        findings.push("the hand does not echo what it receives".to_string());
    } else if !echoes && actual.starts_with(word) {
        clauses.extend(decision("framing-echo"));
        findings.push("the hand echoes what it receives, which the profile does not".to_string());
    }
    let status_line = |answer: &[u8], eol: &[u8]| -> Option<Vec<u8>> {
        // The first non-empty line after the echo.
        split(answer, eol).into_iter().skip(1).find(|l| !l.is_empty()).map(<[u8]>::to_vec)
    };
    if let (Some(want), Some(got)) = (status_line(expected, eol), status_line(actual, &hand_eol)) {
        if shape(&want) != shape(&got) {
            findings.push(format!("an error status reads `{}`, not in the form `{}`", escape(&got), escape(&want)));
        }
    } else if status_line(expected, eol).is_some() && !actual.is_empty() {
        findings.push(format!("{} gets no status line", p.what));
    }

    // Who the hand says it is: the VERS answer and the banner.
    let said: Vec<String> =
        [&answers[3].2, &answers[4].2].into_iter().flat_map(|a| crate::identity::answer_lines(a, profile)).collect();
    let identity = crate::identity::mismatch(profile, &said);

    // RESET: the banner.
    let (_, expected, actual) = &answers[4];
    let has = |a: &[u8]| a.windows(BANNER_TEXT.len()).any(|w| w == BANNER_TEXT);
    if has(expected) && !has(actual) {
        clauses.extend(decision("-banner-text"));
        findings.push(format!("RESET prints no banner (no `{}`)", String::from_utf8_lossy(BANNER_TEXT)));
    }
    for (p, _, actual) in &answers {
        if actual.is_empty() && p.what != "a bare CR" {
            findings.push(format!("no answer to {}", p.what));
        }
    }
    let exchanged = exchanged(&answers);
    Ok(Preflight { findings, clauses, settled, identity, exchanged })
}

/// Bytes sent and received, probe by probe.
fn exchanged(answers: &[(Probe, Vec<u8>, Vec<u8>)]) -> Vec<(u64, u64)> {
    answers.iter().map(|(p, _, actual)| (p.send.len() as u64, actual.len() as u64)).collect()
}

fn split<'a>(s: &'a [u8], sep: &[u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut rest = s;
    while let Some(i) = rest.windows(sep.len().max(1)).position(|w| w == sep) {
        out.push(&rest[..i]);
        rest = &rest[i + sep.len().max(1)..];
    }
    out.push(rest);
    out
}

/// A line's shape: runs of digits become `9`, so `ERR 32` and `ERR 1024` have one shape.
fn shape(line: &[u8]) -> Vec<u8> {
    let mut out: Vec<u8> = Vec::with_capacity(line.len());
    for &b in line {
        let c = if b.is_ascii_digit() { b'9' } else { b };
        if !(c == b'9' && out.last() == Some(&b'9')) {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use gcl_model::Fault;

    fn probe(faults: Vec<Fault>) -> Preflight {
        let p = Profile::builtin("seed").unwrap();
        let mut hand = SimLink::new(p.clone(), DeviceConfig { faults, ..Default::default() });
        discard(&mut hand, Duration::from_millis(50), Duration::from_secs(1)).unwrap();
        run(&mut hand, &p, &DeadlinePolicy::for_target(&gcl_host::Target::Sim { profile: None })).unwrap()
    }

    /// A hand that answers each probe with a fixed text.
    struct Scripted {
        answers: Vec<(&'static [u8], &'static [u8])>,
        pending: Vec<u8>,
        now: Duration,
    }

    impl Scripted {
        /// A hand that answers each probe of the pre-flight as the seed profile says (tests
        /// change one answer of it).
        fn healthy() -> Scripted {
            Scripted {
                answers: vec![
                    (b"\x03", b"\n\r=> "),
                    (b"\r", b"\n\r=> "),
                    (b"ZZQX\r", b"ZZQX\n\rERR 32\n\r=> "),
                    (b"VERS\r", b"VERS\n\rFirmware 4.4\n\r=> "),
                    (b"RESET\r", b"RESET\n\rBarrettHand Firmware 4.4\n\r=> "),
                ],
                pending: Vec::new(),
                now: Duration::ZERO,
            }
        }
    }

    impl Link for Scripted {
        fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
            if let Some((_, a)) = self.answers.iter().find(|(s, _)| *s == bytes) {
                self.pending.extend_from_slice(a);
            }
            Ok(())
        }
        fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
            self.now += timeout;
            let n = self.pending.len();
            buf.append(&mut self.pending);
            Ok(n)
        }
        fn elapsed(&self) -> Duration {
            self.now
        }
        fn describe(&self) -> String {
            "scripted".into()
        }
    }

    /// A hand whose answers come in parts, one part per read.
    struct Parted {
        answers: Vec<(&'static [u8], Vec<&'static [u8]>)>,
        pending: std::collections::VecDeque<&'static [u8]>,
        now: Duration,
    }

    impl Link for Parted {
        fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
            if let Some((_, parts)) = self.answers.iter().find(|(s, _)| *s == bytes) {
                self.pending.extend(parts.iter().copied());
            }
            Ok(())
        }
        fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
            self.now += timeout;
            let part = self.pending.pop_front().unwrap_or_default();
            buf.extend_from_slice(part);
            Ok(part.len())
        }
        fn elapsed(&self) -> Duration {
            self.now
        }
        fn describe(&self) -> String {
            "parted".into()
        }
    }

    #[test]
    fn a_prompt_right_after_a_complete_answer_is_named_with_that_answer() {
        // A hand that answers a bare CR with two prompts, the second a moment after the first:
        // the first is the model's whole answer, and the second must still be read as part of
        // it (what a wait for quiet saw), not taken as the head of ZZQX's answer.
        let p = Profile::builtin("seed").unwrap();
        let policy = DeadlinePolicy::for_target(&gcl_host::Target::Sim { profile: None });
        let hand = |cr: Vec<&'static [u8]>| Parted {
            answers: vec![
                (b"\x03", vec![b"\n\r=> "]),
                (b"\r", cr),
                (b"ZZQX\r", vec![b"ZZQX\n\rERR 32\n\r=> "]),
                (b"VERS\r", vec![b"VERS\n\rFirmware 4.4\n\r=> "]),
                (b"RESET\r", vec![b"RESET\n\rBarrettHand Firmware 4.4\n\r=> "]),
            ],
            pending: Default::default(),
            now: Duration::ZERO,
        };
        let at_once = run(&mut hand(vec![b"\n\r=> \n\r=> "]), &p, &policy).unwrap();
        assert!(!at_once.findings.is_empty(), "two prompts for a bare CR: {at_once:?}");
        let in_parts = run(&mut hand(vec![b"\n\r=> ", b"\n\r=> "]), &p, &policy).unwrap();
        assert_eq!(in_parts.findings, at_once.findings);
    }

    #[test]
    fn a_status_line_in_another_form_is_named() {
        let p = Profile::builtin("seed").unwrap();
        let mut hand = Scripted::healthy();
        hand.answers[2].1 = b"ZZQX\n\rError 32!\n\r=> ";
        let r = run(&mut hand, &p, &DeadlinePolicy::for_target(&gcl_host::Target::Sim { profile: None })).unwrap();
        assert_eq!(r.findings, vec!["an error status reads `Error 32!`, not in the form `ERR 32`"], "{r:?}");
        assert_eq!(shape(b"ERR 1024"), shape(b"ERR 32"));
    }

    /// A link that counts the reads longer than [`TRAILING`] that came back empty: each one is
    /// a wait for quiet.
    struct QuietWaits<'a> {
        inner: &'a mut dyn Link,
        empty: usize,
    }

    impl Link for QuietWaits<'_> {
        fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
            self.inner.send(bytes)
        }
        fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
            let n = self.inner.recv(buf, timeout)?;
            self.empty += usize::from(n == 0 && timeout > TRAILING);
            Ok(n)
        }
        fn elapsed(&self) -> Duration {
            self.inner.elapsed()
        }
        fn describe(&self) -> String {
            self.inner.describe()
        }
    }

    #[test]
    fn an_answer_the_same_as_the_model_s_is_not_waited_out_and_a_byte_after_one_is_still_named() {
        // A healthy hand: every answer but RESET's ends the moment it is the model's; RESET's
        // is read to a quiet, so the hand is left settled.
        let p = Profile::builtin("seed").unwrap();
        let policy = DeadlinePolicy::for_target(&gcl_host::Target::Sim { profile: None });
        let mut hand = SimLink::new(p.clone(), DeviceConfig::default());
        discard(&mut hand, Duration::from_millis(50), Duration::from_secs(1)).unwrap();
        let mut counted = QuietWaits { inner: &mut hand, empty: 0 };
        let r = run(&mut counted, &p, &policy).unwrap();
        assert!(r.findings.is_empty() && r.settled, "{r:?}");
        assert_eq!(counted.empty, 1, "one wait for quiet, after RESET's prompt");
        // A hand that sends a byte after its bare CR's prompt: the byte lands at the head of
        // the next answer, which is then not the model's, and the pre-flight names it.
        let mut hand = Scripted::healthy();
        let healthy = run(&mut hand, &p, &policy).unwrap();
        assert!(healthy.findings.is_empty(), "{healthy:?}");
        hand.answers[2].1 = b"?ZZQX\n\rERR 32\n\r=> ";
        let r = run(&mut hand, &p, &policy).unwrap();
        assert_eq!(r.findings, vec!["the hand does not echo what it receives"], "{r:?}");
    }

    #[test]
    fn a_healthy_hand_passes_the_pre_flight() {
        let r = probe(vec![]);
        assert!(r.findings.is_empty(), "{r:?}");
        assert!(r.line().contains("as the profile says"));
    }

    #[test]
    fn each_gross_framing_fault_is_named() {
        let r = probe(vec![Fault::PromptNoSpace]);
        assert_eq!(r.findings, vec!["the hand's prompt is `=>` without the trailing space"], "{r:?}");
        let r = probe(vec![Fault::CrLf]);
        assert_eq!(r.findings, vec!["lines end in `\\r\\n` instead of `\\n\\r`"], "{r:?}");
        assert_eq!(r.clauses, vec!["decision:framing-line-ending"], "{r:?}");
        let r = probe(vec![Fault::NoEcho]);
        assert_eq!(r.findings, vec!["the hand does not echo what it receives"], "{r:?}");
        let r = probe(vec![Fault::ResetNoBanner]);
        assert_eq!(r.findings, vec!["RESET prints no banner (no `BarrettHand Firmware`)"], "{r:?}");
    }

    #[test]
    fn a_hand_of_another_firmware_is_named_from_its_vers_or_its_banner() {
        let p = Profile::builtin("bh8-262-4.3").unwrap();
        let policy = DeadlinePolicy::for_target(&gcl_host::Target::Sim { profile: None });
        let hand = |vers: &'static [u8], banner: &'static [u8]| {
            let mut h = Scripted::healthy();
            h.answers[3].1 = vers;
            h.answers[4].1 = banner;
            h
        };
        let said = "identity: the hand says firmware 4.4; you chose bh8-262-4.3 (firmware 4.3): run with --profile bh8-262-4.4";
        // In VERS alone (a banner without a version), and in the banner alone (VERS refused).
        let mut h = hand(b"VERS\n\rFirmware Version 4.41\n\r=> ", b"RESET\n\rBarrettHand Firmware\n\r=> ");
        assert_eq!(run(&mut h, &p, &policy).unwrap().identity.as_deref(), Some(said));
        let mut h = hand(b"VERS\n\rERR 32\n\r=> ", b"RESET\n\rBarrettHand Firmware\n\rVersion 4.4x\n\r=> ");
        assert_eq!(run(&mut h, &p, &policy).unwrap().identity.as_deref(), Some(said));
        let mut h = hand(b"VERS\n\rVersion 4.34\n\r=> ", b"RESET\n\rBarrettHand Firmware\n\r=> ");
        assert_eq!(run(&mut h, &p, &policy).unwrap().identity, None);
    }
}
