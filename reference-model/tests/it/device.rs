//! The device through its public surface, where a plain line/answer session under
//! `testdata/sessions/` cannot say it: simulated time, the world around the hand, bytes sent
//! mid-command, RealTime blocks, faults, events and the ends of time.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::device::{FaultSet, MAX_EVENTS};
use gcl_model::spec::embedded;
use gcl_model::{Device, DeviceConfig, Event, Fault, Mode, Motor, StatusBits};

use crate::support;
use support::{hand, hand_with, load_top, profile, send};

#[test]
fn banner_at_power_up() {
    let mut d = Device::with_profile(profile("seed"));
    let out = String::from_utf8(d.take_output()).unwrap();
    assert!(out.starts_with("\n\rBarrettHand Firmware"), "{out:?}");
    assert!(out.ends_with("\n\r=> "));
}

/// The answers of C, O and M are in `testdata/sessions/close-and-open.gcl`; this is the time
/// they take.
#[test]
fn closing_takes_simulated_time() {
    let mut d = hand("seed");
    send(&mut d, "HI");
    let t0 = d.now();
    assert_eq!(send(&mut d, "123C"), "123C\n\r=> ");
    assert!(d.now() - t0 > Duration::from_secs(1), "closing takes time");
    assert_eq!(send(&mut d, "2M 5000"), "2M 5000\n\r=> ");
    assert_eq!(d.position(Motor::F2), 5000);
}

#[test]
fn missed_position_gives_16() {
    let mut d = hand("seed");
    send(&mut d, "HI");
    // The spread stops at 3150.
    assert_eq!(send(&mut d, "SM 5000"), "SM 5000\n\rERR 16\n\r=> ");
    // An object in F1's way.
    let mut sc = d.scenario().clone();
    sc.objects[0] = Some(4000);
    d.set_scenario(sc);
    assert_eq!(send(&mut d, "1M 8000"), "1M 8000\n\rERR 16\n\r=> ");
    let p = d.position(Motor::F1);
    assert!((4000..=4600).contains(&p), "{p}");
    // Closing into it is not an error.
    send(&mut d, "1O");
    assert_eq!(send(&mut d, "1C"), "1C\n\r=> ");
}

#[test]
fn strain_limit_stops_a_finger() {
    let mut d = hand("seed");
    let mut sc = d.scenario().clone();
    sc.objects[1] = Some(3000);
    sc.strain_noise = 0;
    d.set_scenario(sc);
    send(&mut d, "HI");
    send(&mut d, "2FSET MSG 60");
    assert_eq!(send(&mut d, "2C"), "2C\n\r=> ");
    let p = d.position(Motor::F2);
    // 20 + 0.25 * (p - 3000) > 60 first at p = 3161.
    assert!((3150..3200).contains(&p), "{p}");
}

#[test]
fn abort_during_motion() {
    let mut s = hand("seed");
    send(&mut s, "HI");
    s.handle_input(s.now(), b"C\r");
    s.handle_timeout(s.now() + Duration::from_millis(200));
    s.handle_input(s.now(), b"\x03");
    assert_eq!(String::from_utf8(s.take_output()).unwrap(), "C\n\r=> ");
    assert!(!s.is_busy());
    let mut b = hand("bh8-262");
    send(&mut b, "HI");
    b.handle_input(b.now(), b"C\r");
    b.handle_timeout(b.now() + Duration::from_millis(100));
    b.handle_input(b.now(), b"\x03");
    assert_eq!(String::from_utf8(b.take_output()).unwrap(), "C\n\rERR 16384\n\r=> ");
}

#[test]
fn input_during_motion_waits_its_turn() {
    let mut d = hand("seed");
    send(&mut d, "HI");
    d.handle_input(d.now(), b"C\rFGET P\r");
    d.run_until_idle(Duration::from_secs(60));
    assert_eq!(String::from_utf8(d.take_output()).unwrap(), "C\n\r=> FGET P\n\r17000 17000 17000 3150\n\r=> ");
}

#[test]
fn overlong_line_is_an_error_and_bounded() {
    let mut d = hand("seed");
    let long = "X".repeat(10_000);
    let out = send(&mut d, &long);
    assert!(out.ends_with("\n\rERR 1024\n\r=> "));
    assert_eq!(send(&mut d, "FGET MPE"), "FGET MPE\n\r25 25 25 25\n\r=> ");
}

/// The seed's RealTime example: F1 and F2 with LCV, LFS and LFDP; the spread with LFDP only.
fn seed_rt(d: &mut Device) {
    send(d, "HI");
    send(d, "12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1");
    send(d, "4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1");
}

#[test]
fn seed_realtime_example_layout() {
    let mut d = hand("seed");
    seed_rt(&mut d);
    assert_eq!(send(&mut d, "124LOOP"), "124LOOP*");
    let l = d.rt_layout().unwrap();
    assert_eq!(l.control().size(), 3);
    assert_eq!(l.feedback().size(), 6);
    let names: Vec<_> = l.feedback().fields().iter().map(|f| (f.motor(), f.name())).collect();
    assert_eq!(
        names,
        vec![(Some(1), "LFS"), (Some(1), "LFDP"), (Some(2), "LFS"), (Some(2), "LFDP"), (Some(4), "LFDP")]
    );
    d.handle_input(d.now(), &[b'C', 20, 0xFB]);
    let fb = d.take_output();
    assert_eq!(fb.len(), 6);
    assert_eq!(fb[0], b'*');
    d.handle_input(d.now(), b"a");
    assert_eq!(d.take_output(), b"*");
    d.handle_input(d.now(), b"\x03");
    assert_eq!(d.take_output(), b"\n\r=> ");
    assert_eq!(d.mode(), Mode::Idle);
}

#[test]
fn realtime_velocity_moves_the_finger() {
    let mut d = hand("seed");
    seed_rt(&mut d);
    send(&mut d, "124LOOP");
    d.handle_input(d.now(), &[b'c', 55, 0]);
    let t = d.now() + Duration::from_millis(1000);
    d.handle_input(t, b"a");
    d.take_output();
    // 55 × LCVC 1 × 0.1 counts/ms for 1000 ms.
    assert_eq!(d.position(Motor::F1), 5500);
    assert_eq!(d.position(Motor::F2), 0);
}

#[test]
fn bad_header_returns_to_supervisory() {
    let mut d = hand("seed");
    seed_rt(&mut d);
    send(&mut d, "124LOOP");
    d.handle_input(d.now(), b"X");
    assert_eq!(d.take_output(), b"\n\rERR 2048\n\r=> ");
    assert_eq!(send(&mut d, "FGET LCV"), "FGET LCV\n\r1 1 1 0\n\r=> ");
}

#[test]
fn manual_example_43_feedback_is_8_bytes() {
    for (profile, size) in [("bh8-262-4.3", 8), ("bh8-262-4.4", 7)] {
        let mut d = hand(profile);
        send(&mut d, "HI");
        send(&mut d, "12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1");
        send(&mut d, "4FSET LCV 0 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1");
        send(&mut d, "PSET LFT 1");
        assert_eq!(send(&mut d, "124LOOP"), "124LOOP*", "{profile}");
        assert_eq!(d.rt_layout().unwrap().feedback().size(), size, "{profile}");
    }
}

#[test]
fn lfdp_worked_example_through_the_device() {
    let mut d = hand("seed");
    send(&mut d, "HI");
    send(&mut d, "1FSET LCV 1 LCVC 1 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 2");
    send(&mut d, "1M 1500");
    assert_eq!(send(&mut d, "1FGET P"), "1FGET P\n\r1500\n\r=> ");
    send(&mut d, "1M 2000");
    send(&mut d, "1LOOP");
    let mut sent = Vec::new();
    for _ in 0..3 {
        d.handle_input(d.now(), b"A");
        sent.push(d.take_output());
    }
    assert_eq!(sent, vec![vec![b'*', 0x7F], vec![b'*', 0x7B], vec![b'*', 0x00]]);
}

#[test]
fn same_inputs_same_bytes() {
    let run = || {
        let mut d = hand_with(profile("bh8-262"), DeviceConfig { seed: 7, ..Default::default() });
        ["HI", "FGET SG", "PGET TEMP", "GC", "FGET P SG", "GO", "PGET TEMP UPSECS"].map(|l| send(&mut d, l))
    };
    let first = run();
    assert!(first[1].starts_with("FGET SG\n\r"), "{first:?}");
    assert_eq!(first, run());
}

#[test]
fn faults_change_the_bytes() {
    let mut d = hand_with(
        profile("seed"),
        DeviceConfig { faults: vec![Fault::CrLf, Fault::FgetReversed], ..Default::default() },
    );
    assert_eq!(send(&mut d, "FGET DP"), "FGET DP\r\n150 1000 1000 1000\r\n=> ");
}

#[test]
fn the_longest_time_saturates_instead_of_overflowing() {
    let mut d = hand("bh8-262");
    // A command running, then the end of time: the command finishes, nothing overflows.
    d.handle_input(Duration::ZERO, b"HI\r");
    assert!(d.is_busy());
    d.handle_timeout(Duration::MAX);
    assert!(!d.is_busy());
    assert_eq!(d.now(), Duration::from_nanos(u64::MAX));
    assert!(String::from_utf8_lossy(&d.take_output()).ends_with("HI\n\r=> "));
    // Time going back is no time passing; the hand still answers.
    d.handle_input(Duration::from_secs(1), b"FGET S\r");
    assert_eq!(String::from_utf8_lossy(&d.take_output()), "FGET S\n\r0 0 0 0\n\r=> ");
    // In the loop, with the fingers moving, too.
    assert!(send(&mut d, "LOOP").ends_with('*'));
    d.handle_input(Duration::MAX, b"C\x40\x00\x40\x00\x40\x00\x40\x00");
    d.handle_timeout(Duration::MAX);
    assert_eq!(d.mode(), Mode::Loop);
    assert!(d.run_until_idle(Duration::MAX) >= d.now());
}

#[test]
fn events_report_lines_loops_and_power_ups() {
    let mut d = Device::with_profile(profile("seed"));
    assert_eq!(d.poll_event(), Some(Event::PoweredUp));
    assert_eq!(d.poll_event(), None);
    send(&mut d, "BOGUS");
    assert_eq!(d.poll_event(), Some(Event::LineDone(StatusBits::UNKNOWN_COMMAND)));
    send(&mut d, "HI");
    assert_eq!(d.poll_event(), Some(Event::LineDone(StatusBits::empty())));
    send(&mut d, "");
    assert_eq!(d.poll_event(), Some(Event::LineDone(StatusBits::empty())));
    send(&mut d, "LOOP");
    assert_eq!(d.poll_event(), Some(Event::LoopEntered));
    d.handle_input(d.now(), b"Z");
    assert_eq!(d.poll_event(), Some(Event::LoopLeft));
    assert_eq!(d.poll_event(), Some(Event::LineDone(StatusBits::BAD_HEADER)));
    send(&mut d, "RESET");
    assert_eq!(d.poll_event(), Some(Event::PoweredUp));
    // Nobody polling: the oldest are dropped, the newest kept.
    for _ in 0..2 * MAX_EVENTS {
        send(&mut d, "BOGUS");
    }
    send(&mut d, "HI");
    let kept: Vec<Event> = std::iter::from_fn(|| d.poll_event()).collect();
    assert_eq!(kept.len(), MAX_EVENTS);
    assert_eq!(kept.last(), Some(&Event::LineDone(StatusBits::empty())));
}

#[test]
fn framing_faults_are_profile_patches() {
    let p = profile("seed");
    let faults = vec![Fault::CrLf, Fault::PromptNoSpace, Fault::NoEcho, Fault::FgetReversed];
    let mut d = hand_with(p.clone(), DeviceConfig { faults, ..Default::default() });
    assert_eq!(d.profile().framing.line_ending, "\r\n");
    assert_eq!(d.profile().framing.prompt, "=>");
    assert!(!d.profile().framing.echo);
    assert_eq!(p.framing.line_ending, "\n\r", "the shared profile is untouched");
    d.handle_input(Duration::ZERO, b"FGET DP\r");
    assert_eq!(d.take_output(), b"\r\n150 1000 1000 1000\r\n=>");
    // No framing fault: the very profile the hand was given.
    let plain = Device::new(p.clone(), DeviceConfig { faults: vec![Fault::FgetReversed], ..Default::default() });
    assert!(Arc::ptr_eq(plain.profile(), &p));
}

#[test]
fn a_fault_set_holds_what_was_put_in_in_declaration_order() {
    let set: FaultSet = [Fault::RangeOffByOne, Fault::CrLf, Fault::RangeOffByOne].into_iter().collect();
    assert_eq!(set.iter().collect::<Vec<_>>(), vec![Fault::CrLf, Fault::RangeOffByOne]);
    assert!(set.contains(Fault::CrLf) && !set.contains(Fault::NoEcho));
    assert_eq!(FaultSet::default().iter().count(), 0);
    let all: FaultSet = Fault::ALL.iter().copied().collect();
    assert_eq!(all.iter().collect::<Vec<_>>(), Fault::ALL.to_vec());
}

#[test]
fn the_line_rate_is_read_where_the_profile_says() {
    let mut d = hand("seed");
    assert_eq!(d.baud(), 9600);
    send(&mut d, "FSET BAUD 192");
    assert_eq!(d.baud(), 19200);
    // A hand whose `[hand] baud` is a fixed rate keeps it whatever BAUD says.
    let top = embedded("seed.toml").unwrap().replacen("baud = \"BAUD\"", "baud = 38400", 1);
    let fixed = load_top(&top).unwrap();
    let mut d = hand_with(Arc::new(fixed), DeviceConfig::default());
    assert_eq!(send(&mut d, "FSET BAUD 192"), "FSET BAUD 192\n\r=> ");
    assert_eq!(d.baud(), 38400);
}

/// A hand that moves for twenty simulated minutes without a rest settles warmer than it
/// started but inside TEMP's declared range: the board cools toward ambient while it warms
/// (decision `bh8-board-heat`). Heat that only grows read past TEMP's maximum of 1250 here.
#[test]
fn a_hand_that_never_rests_stays_inside_the_temperature_range() {
    let p = profile("bh8-262-4.4");
    let temp_max = p.params.iter().find(|x| x.name == "TEMP").map(|x| x.max).unwrap();
    let mut d = hand("bh8-262-4.4");
    send(&mut d, "HI");
    let start = d.now();
    while d.now() - start < Duration::from_secs(20 * 60) {
        send(&mut d, "M 9000");
        send(&mut d, "M 1000");
    }
    let read = |d: &mut Device, name: &str| -> i64 {
        let answer = send(d, &format!("PGET {name}"));
        answer.lines().nth(1).and_then(|l| l.trim().parse().ok()).unwrap_or_else(|| panic!("{answer:?}"))
    };
    let (temp, peak) = (read(&mut d, "TEMP"), read(&mut d, "PTEMP"));
    let ambient = gcl_model::device::Scenario::default().temperature;
    assert!(temp > ambient + 100, "the moving hand warmed: TEMP {temp}");
    assert!(temp <= temp_max && peak <= temp_max, "TEMP {temp}, PTEMP {peak}, range max {temp_max}");
    assert!(temp <= ambient + 400 + 3, "settles at most 40.0 C above ambient: TEMP {temp}");
}
