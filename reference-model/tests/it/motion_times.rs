//! How long the simulated BH8-262 takes to move, against the units of decision
//! `bh8-velocity-units`, worked out here from the evidence rather than from the profile's
//! `[hand]` constants: the controller samples every 16 × (SAMPLE + 1) cycles of a 1.25 MHz
//! clock (409.6 µs at SAMPLE 31); MCV, MOV and IVEL are in 1/16 count per sample; the RealTime
//! velocity LCV × LCVC / 16 is in counts per sample; the feedback velocity LFV × LFVC is in
//! counts per 10 ms tick. If the profile's data drifts from these units, the times below move
//! and the test fails.

use std::time::Duration;

use gcl_model::{Device, DeviceConfig, Profile, Scenario};

use crate::support;

const PROFILES: [&str; 2] = ["bh8-262-4.3", "bh8-262-4.4"];

/// The HCTL-1100 clock of the BH8-262 (1.25 MHz) and the SAMPLE parameter's default (31).
fn sample_ms(profile: &Profile) -> f64 {
    let sample = profile.default_for(profile.param_id("SAMPLE").expect("SAMPLE"), 1) as f64;
    16.0 * (sample + 1.0) / 1.25e6 * 1000.0
}

/// A parameter's default for motor `m`.
fn default(profile: &Profile, name: &str, m: u8) -> f64 {
    profile.default_for(profile.param_id(name).unwrap_or_else(|| panic!("{name}")), m) as f64
}

/// Milliseconds to cover `counts` at a velocity of `units` (1/16 count per sample).
fn travel_ms(profile: &Profile, counts: f64, units: f64) -> f64 {
    counts / (units / 16.0) * sample_ms(profile)
}

/// A hand whose joints start at `at`, banner taken.
fn hand(profile: &str, at: [i64; 4]) -> Device {
    let scenario = Scenario { initial_positions: at, ..Scenario::default() };
    support::hand_with(support::profile(profile), DeviceConfig { scenario, ..DeviceConfig::default() })
}

/// Sends `line` and runs it to completion; returns how long it took in ms and what it printed.
fn timed(d: &mut Device, line: &str) -> (f64, String) {
    let start = d.now();
    let out = support::send(d, line);
    (d.now().saturating_sub(start).as_secs_f64() * 1000.0, out)
}

/// `got` is within `frac` of `want` (the acceleration ramp and whole-ms ticks add a little).
fn near(got: f64, want: f64, frac: f64, what: &str) {
    assert!(
        (got - want).abs() <= want * frac,
        "{what}: {got:.1} ms, the units say {want:.1} ms (±{:.0}%)",
        frac * 100.0
    );
}

#[test]
fn full_close_and_spread_take_as_long_as_the_default_velocities_say() {
    for name in PROFILES {
        let p = Profile::builtin(name).unwrap();
        let mut d = hand(name, [0; 4]);
        assert!(timed(&mut d, "HI").1.ends_with("=> "));
        // C from fully open: every finger to CT at MCV (default 100: 6.25 counts per sample).
        let (took, out) = timed(&mut d, "123C");
        assert_eq!(out, "123C\n\r=> ", "{name}");
        let want = travel_ms(&p, default(&p, "CT", 1), default(&p, "MCV", 1));
        near(took, want, 0.03, &format!("{name}: 123C from open"));
        assert!(
            (1000.0..1300.0).contains(&took),
            "{name}: a full close at MCV 100 takes about 1.1 s, took {took:.0} ms"
        );
        // O back at MOV.
        let (took, _) = timed(&mut d, "123O");
        let want = travel_ms(&p, default(&p, "CT", 1) - default(&p, "OT", 1), default(&p, "MOV", 1));
        near(took, want, 0.03, &format!("{name}: 123O from CT"));
        // The spread over its whole range at its own MCV (default 60).
        let (took, _) = timed(&mut d, "SC");
        let want = travel_ms(&p, default(&p, "CT", 4), default(&p, "MCV", 4));
        near(took, want, 0.03, &format!("{name}: SC from open"));
    }
}

#[test]
fn hi_from_closed_opens_at_ivel_then_settles() {
    for name in PROFILES {
        let p = Profile::builtin(name).unwrap();
        let closed = [p.hand.finger_limit, p.hand.finger_limit, p.hand.finger_limit, p.hand.spread_limit];
        let mut d = hand(name, closed);
        let (took, out) = timed(&mut d, "HI");
        assert_eq!(out, "HI\n\r=> ", "{name}");
        // Every motor opens at its IVEL (fingers 300, spread 150) and settles at the stop; the
        // slowest one sets the time.
        let settle = p.hand.hi_settle_ms as f64 * default(&p, "IHIT", 1).max(1.0);
        let want = (1..=4u8)
            .map(|m| travel_ms(&p, closed[m as usize - 1] as f64, default(&p, "IVEL", m)))
            .fold(0.0f64, f64::max)
            + settle;
        near(took, want, 0.03, &format!("{name}: HI from closed"));
        assert!(gcl_model::Motor::ALL.iter().all(|&m| d.position(m) == 0), "{name}: HI ends at 0");
    }
}

#[test]
fn realtime_velocity_moves_and_reads_back_in_the_drivers_units() {
    for name in PROFILES {
        let p = Profile::builtin(name).unwrap();
        let mut d = hand(name, [0; 4]);
        timed(&mut d, "HI");
        // One finger, a velocity and an absolute position back, as a velocity loop uses it.
        let (_, out) = timed(&mut d, "1FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0");
        assert!(out.ends_with("=> "), "{name}: {out:?}");
        if p.param_id("LCT").is_some() {
            timed(&mut d, "1FSET LCT 0 LFBP 0 LFAIN 0");
        }
        timed(&mut d, "PSET LFT 0");
        assert_eq!(timed(&mut d, "1LOOP").1, "1LOOP*");
        // Datum 48: 3 counts per sample, 7.32 counts/ms.
        let datum = 48u8;
        let per_sample = f64::from(datum) / 16.0;
        let t0 = d.now();
        d.handle_input(t0, &[b'c', datum]);
        assert_eq!(d.take_output(), b"*");
        let span = Duration::from_millis(500);
        d.handle_timeout(t0 + span);
        d.handle_input(t0 + span, b"A");
        let block = d.take_output();
        assert_eq!(block.len(), 4, "{name}: *, LFV, LFAP (2 bytes): {block:?}");
        let lfv = f64::from(block[1] as i8);
        let lfap = f64::from(u16::from_be_bytes([block[2], block[3]]));
        // libgripper reads LFV as counts per 10 ms tick.
        let want_lfv = per_sample * 10.0 / sample_ms(&p);
        assert!((lfv - want_lfv).abs() <= 1.0, "{name}: LFV {lfv}, the units say {want_lfv:.1} counts per 10 ms");
        let want_pos = per_sample / sample_ms(&p) * span.as_secs_f64() * 1000.0;
        near(lfap, want_pos, 0.02, &format!("{name}: position after 500 ms at datum {datum}"));
    }
}
