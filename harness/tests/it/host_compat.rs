//! Host-library compatibility: small host programs that behave as public BH8-262 host
//! libraries do at the port, run against `gcl sim --pty` with its defaults (real time, paced
//! at the hand's BAUD), every one as a user would meet it:
//! - Barrett's C++ API: bare CR, RESET, then it searches the answer for `BarrettHand
//!   Firmware` followed by LF;
//! - a library that connects with ^C and reads exactly one prompt before its first command;
//! - a library that changes the baud rate: `PSET BAUD`, close without reading the answer,
//!   reopen, wait, CR, one prompt;
//! - a wall-clock RealTime loop for two seconds, on the seed and on bh8-262: its cycle rate
//!   stays within the line's limit, positions move as the commanded velocities say, and the
//!   feedback velocity read in the profile's unit (counts per 10 ms on a BH8-262, as
//!   libgripper reads it) agrees.

use crate::sim_support;

use std::io::Write;
use std::time::{Duration, Instant};

use gcl_model::Profile;
use nix::sys::termios::BaudRate;
use sim_support::{SimProcess, Transport, open_port, read_port, set_port_speed};

const PROMPT: &[u8] = b"\n\r=> ";

fn ends_prompt(b: &[u8]) -> bool {
    b.ends_with(PROMPT)
}

fn find(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

/// Sends a line and reads its answer up to the prompt.
fn exchange(port: &mut std::fs::File, line: &str) -> Vec<u8> {
    port.write_all(format!("{line}\r").as_bytes()).unwrap();
    read_port(port, &ends_prompt, None, Duration::from_secs(30))
}

#[test]
fn barrett_api_start_up_finds_its_banner_line_on_every_profile() {
    for name in ["seed", "bh8-262-4.3", "bh8-262-4.4"] {
        let sim = SimProcess::start_exact(Transport::Pty, &["--profile", name]);
        let mut port = open_port(&sim.address);
        assert_eq!(exchange(&mut port, ""), PROMPT, "{name}");
        let answer = exchange(&mut port, "RESET");
        assert!(find(&answer, b"BarrettHand Firmware\n"), "{name}: {:?}", String::from_utf8_lossy(&answer));
    }
}

#[test]
fn a_library_that_connects_with_ctrl_c_and_one_prompt_is_not_one_answer_off() {
    let sim = SimProcess::start_exact(Transport::Pty, &["--profile", "bh8-262"]);
    // The library opens the port some time after the hand powered up.
    std::thread::sleep(Duration::from_millis(200));
    let mut port = open_port(&sim.address);
    port.write_all(&[3]).unwrap();
    assert_eq!(read_port(&mut port, &ends_prompt, None, Duration::from_secs(5)), PROMPT);
    assert_eq!(exchange(&mut port, "FGET DP"), b"FGET DP\n\r8500 8500 8500 1575\n\r=> ");
    assert_eq!(exchange(&mut port, "PGET BAUD"), b"PGET BAUD\n\r96\n\r=> ");
}

#[test]
fn a_library_that_changes_the_baud_rate_reopens_to_one_fresh_prompt() {
    let sim = SimProcess::start_exact(Transport::Pty, &["--profile", "bh8-262"]);
    let mut port = open_port(&sim.address);
    assert_eq!(exchange(&mut port, ""), PROMPT);
    // Set the rate, and close without reading the answer.
    port.write_all(b"PSET BAUD 384\r").unwrap();
    std::thread::sleep(Duration::from_millis(100));
    drop(port);
    // Switch its own side, wait about a second (Barrett's API), send a CR.
    std::thread::sleep(Duration::from_millis(500));
    let mut port = open_port(&sim.address);
    set_port_speed(&port, BaudRate::B38400);
    port.write_all(b"\r").unwrap();
    let got = read_port(&mut port, &|_| false, Some(Duration::from_millis(400)), Duration::from_secs(5));
    assert_eq!(got, PROMPT, "exactly one fresh prompt");
    assert_eq!(exchange(&mut port, "PGET BAUD"), b"PGET BAUD\n\r384\n\r=> ");
}

#[test]
fn a_wall_clock_realtime_loop_stays_within_the_line_and_moves_as_commanded() {
    for name in ["seed", "bh8-262"] {
        wall_clock_loop(name);
    }
}

/// A velocity loop on the wall clock for 2 s against `gcl sim --pty --profile name`.
fn wall_clock_loop(name: &str) {
    let profile = Profile::builtin(name).unwrap();
    let sim = SimProcess::start_exact(Transport::Pty, &["--profile", name]);
    let mut port = open_port(&sim.address);
    assert_eq!(exchange(&mut port, ""), PROMPT);
    exchange(&mut port, "HI");
    // Motors 1 and 2: a velocity out; their velocity and position change back. Motor 4: only
    // its position change. C v1 v2 is 3 bytes; * lfv1 d1 lfv2 d2 d4 is 6.
    exchange(&mut port, "12FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 0 LFDP 1 LFDPC 1");
    exchange(&mut port, "4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1");
    if profile.param_id("LCT").is_some() {
        exchange(&mut port, "124FSET LCT 0 LFBP 0 LFAIN 0");
    }
    if profile.param_id("LFT").is_some() {
        exchange(&mut port, "PSET LFT 0");
    }
    let before = exchange(&mut port, "1FGET P");
    let p0: i64 = String::from_utf8_lossy(&before).split("\n\r").nth(1).unwrap().trim().parse().unwrap();
    port.write_all(b"124LOOP\r").unwrap();
    assert!(read_port(&mut port, &|b| b.ends_with(b"*"), None, Duration::from_secs(5)).ends_with(b"*"));
    // Close motors 1 and 2 at datum 20, as fast as the line lets the loop run.
    let v = 20i8;
    let start = Instant::now();
    let (mut cycles, mut moved, mut lfv_sum) = (0u32, 0i64, 0i64);
    while start.elapsed() < Duration::from_secs(2) {
        port.write_all(&[b'C', v as u8, v as u8]).unwrap();
        let fb = read_port(&mut port, &|b| b.len() >= 6, None, Duration::from_secs(5));
        assert_eq!(fb.len(), 6, "{name}: {fb:?}");
        lfv_sum += i64::from(fb[1] as i8);
        moved += i64::from(fb[2] as i8);
        cycles += 1;
    }
    let took = start.elapsed();
    port.write_all(&[3]).unwrap();
    read_port(&mut port, &ends_prompt, None, Duration::from_secs(5));
    let after = exchange(&mut port, "1FGET P");
    let p1: i64 = String::from_utf8_lossy(&after).split("\n\r").nth(1).unwrap().trim().parse().unwrap();
    // The line's limit: 9 bytes of 10 bits each per cycle at 9600 baud.
    let rate = f64::from(cycles) / took.as_secs_f64();
    let limit = 9600.0 / 90.0;
    assert!(rate <= limit * 1.01, "{name}: {rate:.1} cycles/s beats the line's {limit:.1}");
    // Positions move as the velocity says: the datum (with its fraction bits) times
    // rt_velocity_counts_per_ms per ms of loop, within a third (acceleration, the loop's
    // edges); the feedback deltas add up to the same motion.
    let h = &profile.hand;
    let per_ms = f64::from(v) / f64::from(1u32 << h.lcv_fraction_bits) * h.rt_velocity_counts_per_ms;
    let ms = took.as_secs_f64() * 1000.0;
    let expected = per_ms * ms;
    let actual = (p1 - p0) as f64;
    assert!((actual - expected).abs() <= expected / 3.0, "{name}: moved {actual} counts, velocity says {expected:.0}");
    assert!(
        (moved as f64 - actual).abs() <= actual / 3.0 + 10.0,
        "{name}: feedback deltas {moved}, position moved {actual}"
    );
    // A host that turns LFV back into counts per ms (LFV x LFVC in the profile's feedback unit:
    // per 10 ms tick on a BH8-262, as libgripper reads it) sees the same speed.
    let lfv_mean = lfv_sum as f64 / f64::from(cycles);
    let seen = lfv_mean * h.lfv_counts_per_ms;
    assert!(
        (seen - per_ms).abs() <= per_ms / 4.0,
        "{name}: LFV {lfv_mean:.1} reads as {seen:.2} counts/ms, commanded {per_ms:.2}"
    );
}
