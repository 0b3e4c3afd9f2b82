//! Property tests of the host library: whatever bytes a hand sends, the host core answers with
//! an [`Answer`] or a [`Violation`] and keeps its state consistent with what it answered; no
//! byte from a hand is ever blamed on the caller ([`Misuse`]); and the client never panics or
//! waits past its timeouts.

use std::time::Duration;

use gcl_host::client::core::{Answer, Framing, HostCore, HostMode, Misuse, Refusal, Violation};
use gcl_host::client::{ClientError, Hand, Timeouts};
use gcl_host::{Link, LinkError, SimLink};
use gcl_model::params::ParamStore;
use gcl_model::realtime::{Control, ControlHeader};
use gcl_model::spec::Scope;
use gcl_model::{DeviceConfig, MotorSet, Profile, RtLayout, StatusBits};
use proptest::prelude::*;

fn layout(p: &Profile) -> RtLayout {
    RtLayout::compute(p, &ParamStore::defaults(p), MotorSet::ALL)
}

/// Puts a core into one of its waiting states. Every request here is one a caller may make
/// in that state, so none is a misuse.
fn prime(core: &mut HostCore, state: u8, p: &Profile) -> Result<(), Misuse> {
    match state % 6 {
        0 => {
            core.command("FGET P")?;
        }
        1 => {
            core.start_loop("1234LOOP", layout(p))?;
        }
        2 | 3 => {
            // In a loop: feedback or ack.
            core.start_loop("1234LOOP", layout(p))?;
            core.handle_input(b"1234LOOP*");
            assert_eq!(core.poll(), Ok(Some(Answer::LoopStarted)));
            let h = if state % 6 == 2 { ControlHeader::Feedback } else { ControlHeader::Ack };
            core.block(&Control::new(h))?;
        }
        4 => {
            core.abort();
        }
        _ => {
            core.sync();
        }
    }
    Ok(())
}

/// Whether text shows no raw control byte: bytes from the hand are escaped when displayed.
fn printable(text: &str) -> bool {
    !text.chars().any(|c| c.is_control())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Random bytes in random chunks, in every waiting state: each poll is "more" while the
    /// core still waits, or a finished answer or violation after which it waits no more, in
    /// the mode its answer implies; violations display escaped; and the next request, after
    /// a supervisory answer, is never refused as a misuse.
    #[test]
    fn random_bytes_keep_the_core_consistent(
        state in 0u8..6,
        chunks in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..64), 0..40),
    ) {
        let p = Profile::builtin("bh8-262").unwrap();
        let mut core = HostCore::new(Framing::of(&p));
        prime(&mut core, state, &p).unwrap();
        for c in &chunks {
            core.handle_input(c);
            match core.poll() {
                Ok(None) => prop_assert!(core.is_waiting()),
                Ok(Some(answer)) => {
                    prop_assert!(!core.is_waiting());
                    match answer {
                        Answer::LoopStarted => prop_assert_eq!(core.mode(), HostMode::RealTime),
                        Answer::Prompt(_) | Answer::Done(_) => {
                            prop_assert_eq!(core.mode(), HostMode::Supervisory)
                        }
                        Answer::Refused(Refusal { status, code, .. }) => {
                            prop_assert_eq!(core.mode(), HostMode::Supervisory);
                            prop_assert_eq!(status, StatusBits::from_bits_truncate(code));
                        }
                        Answer::Feedback(v) => {
                            prop_assert_eq!(core.mode(), HostMode::RealTime);
                            let l = layout(&p);
                            prop_assert!(l.feedback().fields().iter().all(|f| v.get(f).is_some()));
                        }
                        Answer::Ack => prop_assert_eq!(core.mode(), HostMode::RealTime),
                    }
                    if core.mode() == HostMode::Supervisory {
                        // Back in supervisory mode, every request may be made again.
                        prime(&mut core, state, &p).unwrap();
                    } else {
                        let _ = core.abort();
                    }
                }
                Err(v) => {
                    prop_assert!(!core.is_waiting());
                    prop_assert!(printable(&v.to_string()), "{:?}", v.to_string());
                    if core.mode() == HostMode::Supervisory {
                        prime(&mut core, state, &p).unwrap();
                    } else {
                        let _ = core.abort();
                    }
                }
            }
        }
    }

    /// A reply split anywhere parses the same.
    #[test]
    fn a_reply_split_anywhere_parses_the_same(split in 0usize..40) {
        let mut core = HostCore::new(Framing::default());
        core.command("FGET DP").unwrap();
        let bytes = b"FGET DP\n\r1000 1000 1000 150\n\r=> ";
        let k = split.min(bytes.len());
        core.handle_input(&bytes[..k]);
        let first = core.poll().unwrap();
        core.handle_input(&bytes[k..]);
        let r = first.or_else(|| core.poll().unwrap());
        prop_assert_eq!(r, Some(Answer::Done(vec!["1000 1000 1000 150".into()])));
    }

    /// Any `ERR n` is data: the refusal carries its number, whatever bits it sets.
    #[test]
    fn any_status_is_a_refusal(code in any::<u32>()) {
        let mut core = HostCore::new(Framing::default());
        core.command("HI").unwrap();
        core.handle_input(format!("HI\n\rERR {code}\n\r=> ").as_bytes());
        let r = core.poll().unwrap();
        prop_assert_eq!(r, Some(Answer::Refused(Refusal { status: StatusBits::from_bits_truncate(code), code, lines: vec![] })));
    }

    /// Answers from a hand that keeps to GCL (the reference model over an in-process link)
    /// round trip through the client: a value set within a parameter's range reads back as
    /// set, on that motor only; a value past its range is refused with the hand's status and
    /// changes nothing. Nothing a well-formed hand says is a `Violation` or a `Misuse`.
    #[test]
    fn a_well_formed_hand_round_trips_parameters(
        profile in prop::sample::select(vec!["seed", "bh8-262-4.3", "bh8-262-4.4"]),
        pick in any::<prop::sample::Index>(),
        frac in 0.0f64..=1.0,
        motor in 1u8..=4,
    ) {
        let p = Profile::builtin(profile).unwrap();
        let writable: Vec<_> = p
            .params
            .iter()
            .filter(|x| {
                x.scope == Scope::Motor
                    && !x.read_only
                    && x.alias_of.is_none()
                    && x.values.is_none()
                    && x.get.is_none()
                    && x.set.is_none()
            })
            .cloned()
            .collect();
        prop_assert!(writable.len() > 10, "{}: {} writable parameters", profile, writable.len());
        let x = pick.get(&writable);
        let value = x.min + ((x.max - x.min) as f64 * frac) as i64;
        let m = motor.to_string();
        let mut link = SimLink::new(p.clone(), DeviceConfig::default());
        // The power-up banner is not an answer to anything.
        gcl_host::link::drain(&mut link, Duration::from_millis(100), Duration::from_secs(5)).unwrap();
        let mut hand = Hand::new(Box::new(link), p.clone());
        let before = hand.get("1234", &x.name).unwrap();
        hand.set(&m, &x.name, value).unwrap();
        let mut expected = before.clone();
        expected[usize::from(motor - 1)] = value;
        prop_assert_eq!(hand.get("1234", &x.name).unwrap(), expected.clone(), "{} {}FSET {} {}", profile, m, x.name, value);
        if x.max < (1 << 40) {
            let r = hand.set(&m, &x.name, x.max + 1);
            prop_assert!(matches!(r, Err(ClientError::Refused { code: 128, .. })), "{}: {:?}", x.name, r);
            prop_assert_eq!(hand.get("1234", &x.name).unwrap(), expected);
        }
    }

    /// A hand that babbles forever: every operation ends, by its timeout at the latest, and
    /// whatever went wrong is never blamed on the caller.
    #[test]
    fn a_babbling_hand_never_hangs_the_client_nor_blames_it(seed in any::<u64>(), op in 0u8..6) {
        let p = Profile::builtin("seed").unwrap();
        let mut hand = Hand::new(Box::new(Babble::new(seed)), p);
        hand.set_timeouts(Timeouts {
            reply: Duration::from_millis(200),
            motion: Duration::from_millis(200),
            block: Duration::from_millis(200),
            sync: Duration::from_millis(50),
        });
        let r: Result<(), ClientError> = match op {
            0 => hand.command("FGET DP").map(drop),
            1 => hand.initialize().map(drop),
            2 => hand.rt_start("123"),
            3 => hand.get("123", "P").map(drop),
            4 => hand.start("C").and_then(|()| hand.finish()).map(drop),
            _ => hand.resync(),
        };
        prop_assert!(!matches!(r, Err(ClientError::Misuse(_))), "{:?}", r);
        prop_assert!(hand.elapsed() < Duration::from_secs(60));
    }

    /// A hand that echoes each line and then answers with GCL-like pieces in any order (line
    /// breaks, prompts, `ERR`, numbers, words, `*`): whatever the client makes of it, it is
    /// never the caller's fault, and every operation ends.
    #[test]
    fn a_mimicking_hand_never_blames_the_caller(
        pieces in proptest::collection::vec(0usize..MIMIC_PIECES.len(), 0..12),
        op in 0u8..7,
    ) {
        let p = Profile::builtin("seed").unwrap();
        let mut hand = Hand::new(Box::new(Mimic::new(pieces)), p);
        hand.set_timeouts(Timeouts {
            reply: Duration::from_millis(200),
            motion: Duration::from_millis(200),
            block: Duration::from_millis(200),
            sync: Duration::from_millis(50),
        });
        let r: Result<(), ClientError> = match op {
            0 => hand.command("FGET DP").map(drop),
            1 => hand.reset().map(drop),
            2 => hand.rt_start("123"),
            3 => hand.get("123", "P").map(drop),
            4 => hand.pget("TEMP").map(drop),
            5 => hand.start("C").and_then(|()| hand.finish()).map(drop),
            _ => hand.abort().map(drop),
        };
        prop_assert!(!matches!(r, Err(ClientError::Misuse(_))), "{:?}", r);
        prop_assert!(hand.elapsed() < Duration::from_secs(60));
    }
}

/// What a [`Mimic`] answers with, after the echo.
const MIMIC_PIECES: &[&[u8]] =
    &[b"\n\r", b"=> ", b"ERR ", b"ERR 32", b"128", b"-7", b"x", b" ", b"*", b"BarrettHand Firmware", b"\n\r=> "];

/// A link that echoes what it is sent (without the CR) and then answers with the chosen
/// pieces, then a prompt; silence after that, on a simulated clock.
struct Mimic {
    pieces: Vec<usize>,
    queue: Vec<u8>,
    now: Duration,
}

impl Mimic {
    fn new(pieces: Vec<usize>) -> Mimic {
        Mimic { pieces, queue: Vec::new(), now: Duration::ZERO }
    }
}

impl Link for Mimic {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.queue.extend(bytes.iter().filter(|b| **b != b'\r' && **b != 3));
        for i in &self.pieces {
            self.queue.extend_from_slice(MIMIC_PIECES[*i]);
        }
        self.queue.extend_from_slice(b"\n\r=> ");
        Ok(())
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        if self.queue.is_empty() {
            self.now += timeout;
            return Ok(0);
        }
        self.now += Duration::from_millis(1);
        let n = self.queue.len().min(5);
        buf.extend(self.queue.drain(..n));
        Ok(n)
    }

    fn elapsed(&self) -> Duration {
        self.now
    }

    fn describe(&self) -> String {
        "mimic".into()
    }
}

/// A hand that refuses `VERS` has no firmware version: its `ERR 32` is a refusal, not a
/// version line a certificate could print.
#[test]
fn a_refused_vers_is_no_firmware_version() {
    let p = Profile::builtin("bh8-262").unwrap();
    let mut link = Canned::new(b"VERS\n\rERR 32\n\r=> ");
    let e = gcl_harness::conform::firmware_version(&mut link, &p, Duration::from_secs(1)).unwrap_err();
    assert!(matches!(e, ClientError::Refused { code: 32, .. }), "{e:?}");
    assert_eq!(link.sent, b"VERS\r");
    // A hand that answers gives its lines, without echo or prompt.
    let mut link = Canned::new(b"VERS\n\rBarrettHand Firmware 4.4\n\r=> ");
    let lines = gcl_harness::conform::firmware_version(&mut link, &p, Duration::from_secs(1)).unwrap();
    assert_eq!(lines, vec!["BarrettHand Firmware 4.4".to_string()]);
    // A hand that breaks GCL is told apart from one that refuses.
    let mut link = Canned::new(b"VERS\r\n4.4\r\n=> ");
    let e = gcl_harness::conform::firmware_version(&mut link, &p, Duration::from_secs(1)).unwrap_err();
    assert!(matches!(e, ClientError::Violation { violation: Violation::MissingLineBreak { .. }, .. }), "{e:?}");
}

/// A link that answers with fixed bytes, then silence, on a simulated clock.
struct Canned {
    answer: Vec<u8>,
    sent: Vec<u8>,
    now: Duration,
}

impl Canned {
    fn new(answer: &[u8]) -> Canned {
        Canned { answer: answer.to_vec(), sent: Vec::new(), now: Duration::ZERO }
    }
}

impl Link for Canned {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.sent.extend_from_slice(bytes);
        Ok(())
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        if self.answer.is_empty() {
            self.now += timeout;
            return Ok(0);
        }
        let n = self.answer.len();
        buf.append(&mut self.answer);
        Ok(n)
    }

    fn elapsed(&self) -> Duration {
        self.now
    }

    fn describe(&self) -> String {
        "canned".into()
    }
}

/// A link that answers every wait with random bytes, on a simulated clock.
struct Babble {
    x: u64,
    now: Duration,
}

impl Babble {
    fn new(seed: u64) -> Babble {
        Babble { x: seed | 1, now: Duration::ZERO }
    }
}

impl Link for Babble {
    fn send(&mut self, _bytes: &[u8]) -> Result<(), LinkError> {
        Ok(())
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        self.now += timeout.min(Duration::from_millis(1));
        let n = (self.x % 17) as usize;
        for _ in 0..n {
            self.x ^= self.x << 13;
            self.x ^= self.x >> 7;
            self.x ^= self.x << 17;
            buf.push((self.x >> 24) as u8);
        }
        Ok(n)
    }

    fn elapsed(&self) -> Duration {
        self.now
    }

    fn describe(&self) -> String {
        "babble".into()
    }
}
