//! The seed document's two example programs ("Supervisory Mode Example Program" and
//! "RealTime Mode Example Program"), ported to [`Hand`]. The `supervisory` and `realtime`
//! examples are thin command lines over these functions; the tests call them directly on every
//! transport.

use std::io::Write;
use std::time::Duration;

use super::{ClientError, Hand, RtFlags};

/// What the supervisory program saw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SupervisoryReport {
    /// The banner after RESET.
    pub banner: Vec<String>,
    /// Positions of F1, F2, F3 after `Close("123")`.
    pub after_close: Vec<i64>,
    /// Positions of F1, F2, F3 after `Open("123")`.
    pub after_open: Vec<i64>,
}

/// The supervisory example: initialise the hand, initialise all motors, close F1-F3, open
/// them. Prints what it does to `out`.
pub fn supervisory(hand: &mut Hand, out: &mut dyn Write) -> Result<SupervisoryReport, ClientError> {
    let _ = write!(out, "Initialization...");
    let banner = hand.initialize()?;
    let _ = writeln!(out, " Done ({})", banner.first().map(String::as_str).unwrap_or(""));
    let _ = writeln!(out, "InitHand(\"123S\")");
    hand.init_hand("123S")?;
    let _ = writeln!(out, "Close(\"123\")");
    hand.close("123")?;
    let after_close = hand.get("123", "P")?;
    let _ = writeln!(out, "  positions F1 F2 F3: {after_close:?}");
    let _ = writeln!(out, "Open(\"123\")");
    hand.open_fingers("123")?;
    let after_open = hand.get("123", "P")?;
    let _ = writeln!(out, "  positions F1 F2 F3: {after_open:?}");
    let _ = writeln!(out, "Done without interruption");
    Ok(SupervisoryReport { banner, after_close, after_open })
}

/// Which clock the RealTime program stops by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clock {
    /// [`crate::Link::elapsed`]: simulated time in-process, the wall clock elsewhere.
    Link,
    /// Wire time: every byte exchanged × 10 bits / `baud`. A `gcl sim --time fast` advances
    /// its simulated time by exactly this, so host and hand agree across a pty or TCP.
    Wire {
        /// The line rate counted.
        baud: u32,
    },
}

impl Clock {
    fn now(self, hand: &Hand) -> Duration {
        match self {
            Clock::Link => hand.elapsed(),
            Clock::Wire { baud } => hand.wire_time(baud),
        }
    }
}

/// What the RealTime program saw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RealtimeReport {
    /// Control blocks sent.
    pub iterations: u64,
    /// Time on the chosen clock from `RTStart` to the last block.
    pub elapsed: Duration,
    /// When (on the clock) F2 and F3 started, if they did.
    pub started: [Option<Duration>; 2],
    /// Last RealTime positions of F1, F2, F3.
    pub positions: [i64; 3],
    /// `FGET P` of F1, F2, F3 after leaving the loop.
    pub final_positions: Vec<i64>,
    /// Every block of the loop in order: the velocities it sent and the positions its
    /// feedback carried (what a plot of the run draws).
    pub blocks: Vec<RealtimeBlock>,
}

/// One control block of the RealTime program and the feedback it got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RealtimeBlock {
    /// The velocities sent to F1, F2, F3.
    pub velocities: [i64; 3],
    /// The positions of F1, F2, F3 in the feedback block that answered (LFAP; the hand sends
    /// the state from before the block's control data).
    pub positions: [i64; 3],
}

/// Velocity the fingers close at, and the position that starts the next finger.
const VELOCITY: i64 = 55;
const THRESHOLD: i64 = 5000;

/// The RealTime example: flags `RTSetFlags("123", 1, 1, 0, 0, 1, 0, 1, 0, 1)`, `123LOOP`; F1
/// closes at velocity 55; F2 starts when F1 passes 5000; F3 when F2 passes 5000; stops after
/// `run_for` (6 s in the seed) on `clock`. Prints progress and the final positions to `out`.
pub fn realtime(
    hand: &mut Hand,
    clock: Clock,
    run_for: Duration,
    out: &mut dyn Write,
) -> Result<RealtimeReport, ClientError> {
    let _ = write!(out, "Initialization...");
    hand.initialize()?;
    let _ = writeln!(out, " Done");
    hand.rt_set_flags("123", RtFlags::barrett(1, 1, 0, 0, 1, 0, 1, 0, 1))?;
    let _ = write!(out, "RealTime Loop - ");
    hand.rt_start("123")?;
    let start = clock.now(hand);
    hand.rt_update()?;
    let mut n = 0u64;
    let mut started = [None, None];
    let mut blocks = Vec::new();
    let mut elapsed;
    loop {
        elapsed = clock.now(hand).saturating_sub(start);
        let pos = |h: &Hand, m: char| h.rt_get_position(m).unwrap_or(0);
        let (p1, p2) = (pos(hand, '1'), pos(hand, '2'));
        hand.rt_set_velocity('1', VELOCITY)?;
        let v2 = if p1 > THRESHOLD { VELOCITY } else { 0 };
        let v3 = if p2 > THRESHOLD { VELOCITY } else { 0 };
        for (i, v) in [v2, v3].into_iter().enumerate() {
            if v != 0 && started[i].is_none() {
                started[i] = Some(elapsed);
                let _ = write!(out, "F{} starts at {:.3} s; ", i + 2, elapsed.as_secs_f64());
            }
        }
        hand.rt_set_velocity('2', v2)?;
        hand.rt_set_velocity('3', v3)?;
        let terminate = elapsed > run_for;
        n += 1;
        hand.rt_update()?;
        let positions = [1u8, 2, 3].map(|m| hand.rt_get_position((b'0' + m) as char).unwrap_or(0));
        blocks.push(RealtimeBlock { velocities: [VELOCITY, v2, v3], positions });
        if terminate {
            break;
        }
    }
    let positions = [1, 2, 3].map(|m| hand.rt_get_position((b'0' + m) as char).unwrap_or(0));
    hand.rt_abort()?;
    let final_positions = hand.get("123", "P")?;
    let _ = writeln!(out, "Done without interruption");
    let _ =
        writeln!(out, "{n} blocks in {:.3} s; final positions F1 F2 F3: {final_positions:?}", elapsed.as_secs_f64());
    Ok(RealtimeReport { iterations: n, elapsed, started, positions, final_positions, blocks })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::target::OpenOptions;

    fn hand() -> Hand {
        Hand::open(&"sim:seed".parse().unwrap(), &OpenOptions::default()).unwrap()
    }

    #[test]
    fn supervisory_closes_and_opens() {
        let mut out = Vec::new();
        let r = supervisory(&mut hand(), &mut out).unwrap();
        assert!(r.after_close.iter().all(|p| *p > 10_000), "{r:?}");
        assert!(r.after_open.iter().all(|p| *p < 100), "{r:?}");
        assert!(String::from_utf8_lossy(&out).contains("Close(\"123\")"));
    }

    #[test]
    fn realtime_cascades_the_fingers() {
        let mut out = Vec::new();
        let r = realtime(&mut hand(), Clock::Link, Duration::from_secs(6), &mut out).unwrap();
        let [f2, f3] = r.started;
        assert!(f2.unwrap() < f3.unwrap(), "{r:?}");
        // After 6 s every finger has closed to its stop.
        assert!(r.positions.iter().all(|p| *p > 15_000), "{r:?}");
        assert!(r.elapsed > Duration::from_secs(6));
        assert_eq!(r.final_positions.len(), 3);
        // Stopped early, the cascade shows: F1 ahead of F2 ahead of F3.
        let r = realtime(&mut hand(), Clock::Link, Duration::from_millis(2500), &mut out).unwrap();
        assert!(r.positions[0] > r.positions[1] && r.positions[1] > r.positions[2], "{r:?}");
    }
}
