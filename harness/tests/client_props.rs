//! Property tests of the host library: no bytes from a hand can make it panic or wait past
//! its timeouts.

use std::time::Duration;

use gcl_harness::client::core::{Framing, HostCore, ProtocolError, Reply};
use gcl_harness::client::{ClientError, Hand, Timeouts};
use gcl_harness::{Link, LinkError};
use gcl_model::params::ParamStore;
use gcl_model::realtime::ControlHeader;
use gcl_model::{MotorSet, Profile, RtLayout};
use proptest::prelude::*;

fn layout(p: &Profile) -> RtLayout {
    RtLayout::compute(p, &ParamStore::defaults(p), MotorSet::ALL)
}

/// Puts a core into one of its waiting states.
fn prime(core: &mut HostCore, state: u8, p: &Profile) {
    match state % 6 {
        0 => {
            let _ = core.command("FGET P");
        }
        1 => {
            let _ = core.start_loop("1234LOOP", layout(p));
        }
        2 | 3 => {
            // In a loop: feedback or ack.
            let _ = core.start_loop("1234LOOP", layout(p));
            core.handle_input(b"1234LOOP*");
            let _ = core.poll();
            let h = if state % 6 == 2 { ControlHeader::Feedback } else { ControlHeader::Ack };
            let _ = core.block(h, &[]);
        }
        4 => {
            let _ = core.abort();
        }
        _ => {
            let _ = core.sync();
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Random bytes in random chunks, in every waiting state: never a panic, and every answer
    /// is either "more", a reply, or a typed error.
    #[test]
    fn random_bytes_never_panic_the_core(
        state in 0u8..6,
        chunks in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..64), 0..40),
    ) {
        let p = Profile::builtin("bh8-262").unwrap();
        let mut core = HostCore::new(Framing::of(&p));
        prime(&mut core, state, &p);
        for c in &chunks {
            core.handle_input(c);
            match core.poll() {
                Ok(_) => {}
                Err(ProtocolError::Status { .. } | ProtocolError::EchoMismatch { .. } | ProtocolError::Framing { .. }) => {
                    prime(&mut core, state, &p);
                }
                Err(ProtocolError::Usage(_)) => prime(&mut core, state, &p),
            }
        }
    }

    /// Random bytes around a real answer: a reply split anywhere parses the same.
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
        prop_assert_eq!(r, Some(Reply::Lines(vec!["1000 1000 1000 150".into()])));
    }

    /// A hand that babbles forever: every operation ends, by its timeout at the latest.
    #[test]
    fn a_babbling_hand_never_hangs_the_client(seed in any::<u64>(), op in 0u8..4) {
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
            _ => hand.resync(),
        };
        // Success is possible by chance; what matters is that it returned.
        let _ = r;
        prop_assert!(hand.elapsed() < Duration::from_secs(60));
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
