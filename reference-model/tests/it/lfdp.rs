//! Byte-array tests of the LFDP worked example and of LFAP's byte order, through the whole
//! device: supervisory commands set the scene, RealTime `A` blocks read the bytes.

use gcl_model::{Device, Motor};

use crate::support;
use support::{hand, send_bytes as send};

/// Sends a line and insists on the plain `<echo>\n\r=> ` answer.
fn ok(d: &mut Device, line: &str) {
    let want = format!("{line}\n\r=> ");
    assert_eq!(String::from_utf8_lossy(&send(d, line)), want, "answer to {line:?}");
}

/// Sends `n` `A` headers, one at a time, and returns the block each one got.
fn feedback_blocks(d: &mut Device, n: usize) -> Vec<Vec<u8>> {
    (0..n)
        .map(|_| {
            let now = d.now();
            d.handle_input(now, b"A");
            d.take_output()
        })
        .collect()
}

/// LFDPC 2, last reported 1500, the finger moved to 2000, motor 1 in the loop with only LFDP on.
fn worked_example(profile: &str, discard: bool) -> Vec<Vec<u8>> {
    let mut d = hand(profile);
    ok(&mut d, "HI");
    ok(&mut d, "1FSET LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 2");
    if discard {
        ok(&mut d, "PSET LFDPD 1");
    }
    ok(&mut d, "1M 1500");
    assert_eq!(send(&mut d, "1FGET P"), b"1FGET P\n\r1500\n\r=> ");
    ok(&mut d, "1M 2000");
    assert_eq!(d.position(Motor::F1), 2000);
    assert_eq!(send(&mut d, "1LOOP"), b"1LOOP*");
    let layout = d.rt_layout().unwrap();
    assert_eq!(layout.feedback().size(), 2, "header and one LFDP byte");
    feedback_blocks(&mut d, 3)
}

#[test]
fn seed_lfdp_carries_the_clipped_rest() {
    assert_eq!(worked_example("seed", false), vec![vec![0x2A, 0x7F], vec![0x2A, 0x7B], vec![0x2A, 0x00]]);
}

#[test]
fn bh8_lfdp_carries_the_clipped_rest_without_lfdpd() {
    for profile in ["bh8-262-4.3", "bh8-262-4.4"] {
        assert_eq!(
            worked_example(profile, false),
            vec![vec![0x2A, 0x7F], vec![0x2A, 0x7B], vec![0x2A, 0x00]],
            "{profile}"
        );
    }
}

#[test]
fn bh8_lfdpd_drops_the_clipped_rest() {
    for profile in ["bh8-262-4.3", "bh8-262-4.4"] {
        assert_eq!(
            worked_example(profile, true),
            vec![vec![0x2A, 0x7F], vec![0x2A, 0x00], vec![0x2A, 0x00]],
            "{profile}"
        );
    }
}

#[test]
fn lfdp_is_negative_when_the_finger_opens() {
    let mut d = hand("seed");
    ok(&mut d, "HI");
    ok(&mut d, "1FSET LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1");
    ok(&mut d, "1M 1000");
    send(&mut d, "1FGET P");
    ok(&mut d, "1M 900");
    send(&mut d, "1LOOP");
    // -100 is 0x9C in two's complement; then nothing is left.
    assert_eq!(feedback_blocks(&mut d, 2), vec![vec![0x2A, 0x9C], vec![0x2A, 0x00]]);
}

#[test]
fn lfap_is_big_endian() {
    for profile in ["seed", "bh8-262-4.3", "bh8-262-4.4"] {
        let mut d = hand(profile);
        ok(&mut d, "HI");
        ok(&mut d, "1FSET LFV 0 LFS 0 LFAP 1 LFDP 0");
        ok(&mut d, "1M 5000");
        send(&mut d, "1LOOP");
        // 5000 = 0x1388, high byte first.
        assert_eq!(feedback_blocks(&mut d, 1), vec![vec![0x2A, 0x13, 0x88]], "{profile}");
    }
}
