//! Advancing the hand in one call gives the hand advanced a millisecond at a time while a
//! command runs: the ticks in which only a counter runs (HI settling at the open stop) pass at
//! once, and `handle_timeout_until_output` and `run_until_idle` run the ticks up to what they
//! wait for in one call, so every answer comes at the same instant, and the hand ends in the
//! same state (positions, velocities, every counter; the board's heat to far below TEMP's
//! resolution, since motion heats it in closed form), as when each millisecond of a command is
//! its own call.

use crate::support;

use std::time::Duration;

use gcl_model::{Device, DeviceConfig};
use support::{hand_with, profile};

const MS: Duration = Duration::from_millis(1);

/// The hand's whole state but its heat, and its heat (`Device` keeps it private; its debug
/// form prints it exactly).
fn hand_and_heat(d: &Device) -> (String, f64) {
    let all = format!("{d:?}");
    let at = all.find(", heat: ").expect("the hand's debug form shows its heat") + ", heat: ".len();
    let len = all[at..].find(',').expect("a field after the heat");
    let heat = all[at..at + len].parse().expect("the heat is a number");
    (format!("{}{}", &all[..at], &all[at + len..]), heat)
}

/// Asserts two hands are in the same state, the board's heat to far below TEMP's resolution
/// (a tenth of a degree).
fn assert_same_hand(a: &Device, b: &Device, what: &str) {
    let ((sa, ha), (sb, hb)) = (hand_and_heat(a), hand_and_heat(b));
    assert_eq!(sa, sb, "{what}");
    assert!((ha - hb).abs() <= 1e-9 * hb.abs().max(1.0), "{what}: heat {ha} against {hb}");
}

/// What the hand answered, and when.
type Heard = Vec<(Duration, Vec<u8>)>;

/// Sends `bytes` and takes what the hand answered at once (the echo), as a link does.
fn sent(d: &mut Device, bytes: &[u8]) -> Vec<u8> {
    d.handle_input(d.now(), bytes);
    d.take_output()
}

/// Sends `bytes`, then advances a millisecond per call while a command runs (as a link did
/// before the hand could run its ticks in one call), and to the end of `span` in one call when
/// none does (an idle hand, or a loop, has nothing to say until the host sends).
fn per_ms(d: &mut Device, bytes: &[u8], span: Duration) -> Heard {
    let mut heard = vec![(d.now(), sent(d, bytes))];
    let end = d.now() + span;
    while d.now() < end {
        let t = if d.is_busy() { d.now() + MS } else { end };
        d.handle_timeout(t);
        if !d.output().is_empty() {
            heard.push((d.now(), d.take_output()));
        }
    }
    heard
}

/// Sends `bytes`, then advances to each output and on to the end of `span` in as few calls as
/// `handle_timeout_until_output` needs.
fn jumping(d: &mut Device, bytes: &[u8], span: Duration) -> Heard {
    let mut heard = vec![(d.now(), sent(d, bytes))];
    let end = d.now() + span;
    loop {
        let stopped = d.handle_timeout_until_output(end);
        if !d.output().is_empty() {
            heard.push((d.now(), d.take_output()));
        }
        if !stopped {
            break;
        }
    }
    heard
}

fn session(profile_name: &str) -> Vec<Vec<u8>> {
    let lines: &[&str] = &[
        "HI",
        "C",
        "FGET P",
        "M 5000",
        "FSET ACCEL 2 MCV 40",
        "TC",
        "O",
        "IC",
        "1M 3000",
        "FGET TEMP",
        "PGET TEMP",
        "HI",
        "FSET LCV 1 LFV 1 LFAP 1 LFDP 1",
        "LOOP",
    ];
    let _ = profile_name;
    let mut out: Vec<Vec<u8>> = lines.iter().map(|l| format!("{l}\r").into_bytes()).collect();
    // In the loop: a velocity for every motor, feedback, then back to the prompt.
    out.push(vec![b'C', 40, 40, 40, 40]);
    out.push(b"A".to_vec());
    out.push(vec![3]);
    out.push(b"FGET P TEMP\r".to_vec());
    out
}

#[test]
fn one_call_runs_the_ticks_a_call_per_millisecond_runs() {
    for name in ["seed", "bh8-262"] {
        let p = profile(name);
        let mut a = hand_with(p.clone(), DeviceConfig { seed: 5, ..DeviceConfig::default() });
        let mut b = a.clone();
        for bytes in session(name) {
            let span = Duration::from_secs(8);
            let (x, y) = (per_ms(&mut a, &bytes, span), jumping(&mut b, &bytes, span));
            assert_eq!(x, y, "{name}: answers to {:?}", String::from_utf8_lossy(&bytes));
            assert_same_hand(&a, &b, &format!("{name}: the hand after {:?}", String::from_utf8_lossy(&bytes)));
        }
        // `run_until_idle` stops at the tick the command ends, as stepping does.
        let mut c = hand_with(p.clone(), DeviceConfig { seed: 9, ..DeviceConfig::default() });
        let mut d = c.clone();
        for line in ["HI", "C", "FSET MOV 30", "O", "TO"] {
            let bytes = format!("{line}\r").into_bytes();
            c.handle_input(c.now(), &bytes);
            while c.is_busy() {
                let t = c.now() + MS;
                c.handle_timeout(t);
            }
            d.handle_input(d.now(), &bytes);
            d.run_until_idle(Duration::from_secs(600));
            assert_same_hand(&c, &d, &format!("{name}: the hand after {line}"));
        }
    }
}
