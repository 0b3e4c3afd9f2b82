//! Runs every fuzz entry point over its seed corpus in `fuzz/seeds/<target>/`, so the fuzz
//! logic is built and exercised on stable, and checks that the committed seeds are the ones
//! `gcl_fuzz::seeds::generate` makes (`UPDATE_SEEDS=1 cargo test -p gcl-fuzz` rewrites them).
//!
//! `crash-*` files are reproducers of model bugs the fuzzer found and that are reported, not
//! yet fixed: they run under `catch_unwind` and the test prints whether each still panics,
//! without failing. Every other seed must run clean.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::Duration;

use gcl_fuzz::seeds::{LINES, generate};
use gcl_fuzz::{DeviceSession, MAX_RESPONSE, Step, TARGETS, Wait, builtin_profiles};
use gcl_model::device::{Device, Fault, Mode};
use gcl_model::grammar::{Line, parse_line};

fn seed_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds").join(target)
}

fn seed_files(target: &str) -> Vec<PathBuf> {
    gcl_fuzz::replay::inputs([seed_dir(target)]).unwrap_or_default()
}

fn is_crash(path: &Path) -> bool {
    path.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("crash-"))
}

#[test]
fn committed_seeds_are_generated_ones() {
    let update = std::env::var_os("UPDATE_SEEDS").is_some();
    let mut stale = Vec::new();
    for seed in generate() {
        let path = seed_dir(seed.target).join(&seed.name);
        if std::fs::read(&path).ok().as_deref() != Some(&seed.bytes[..]) {
            if update {
                std::fs::create_dir_all(seed_dir(seed.target)).unwrap();
                std::fs::write(&path, &seed.bytes).unwrap();
            } else {
                stale.push(path.display().to_string());
            }
        }
    }
    assert!(stale.is_empty(), "stale or missing seeds (rerun with UPDATE_SEEDS=1): {stale:#?}");
}

#[test]
fn every_seed_runs_clean() {
    let mut ran = 0;
    for (target, entry) in TARGETS {
        let files = seed_files(target);
        assert!(files.len() >= 5, "{target}: only {} seeds", files.len());
        for file in files.iter().filter(|f| !is_crash(f)) {
            let data = std::fs::read(file).unwrap();
            if catch_unwind(AssertUnwindSafe(|| entry(&data))).is_err() {
                panic!("{target}: seed {} fails (its panic message is above)", file.display());
            }
            ran += 1;
        }
    }
    println!("{ran} seeds ran");
}

/// The replay binary of a target, built by cargo for these tests.
fn replay_binary(target: &str) -> &'static str {
    match target {
        "grammar" => env!("CARGO_BIN_EXE_grammar"),
        "device" => env!("CARGO_BIN_EXE_device"),
        "realtime" => env!("CARGO_BIN_EXE_realtime"),
        _ => env!("CARGO_BIN_EXE_spec"),
    }
}

/// Reproducers run in a child process: some findings abort (a failed allocation) rather than
/// panic, and an abort cannot be caught in this one.
#[test]
fn known_crashes_are_reported() {
    for (target, _) in TARGETS {
        for file in seed_files(target).iter().filter(|f| is_crash(f)) {
            let out = std::process::Command::new(replay_binary(target)).arg(file).output().unwrap();
            let verdict = if out.status.success() {
                "runs clean now: rename it to a regression seed".to_string()
            } else {
                let stderr = String::from_utf8_lossy(&out.stderr);
                let why = stderr.lines().find(|l| !l.starts_with("thread ") && !l.trim().is_empty()).unwrap_or("");
                format!("still crashes (model bug, reported): {why}")
            };
            println!("{target}: {}: {verdict}", file.display());
        }
    }
}

#[test]
fn device_sessions_round_trip_through_bytes() {
    let s = DeviceSession {
        profile: 2,
        // A fault past the sixteenth and the last one.
        faults: 0x1234 | 1 << 40 | 1 << (Fault::ALL.len() - 1),
        scenario: 7,
        steps: vec![Step { wait: 199, bytes: b"HI\r".to_vec() }, Step { wait: 3, bytes: vec![] }],
    };
    assert_eq!(DeviceSession::from_bytes(&s.to_bytes()), s);
    // Long chunks are split into steps that arrive at once.
    let long = DeviceSession { steps: vec![Step { wait: 5, bytes: vec![b'A'; 300] }], ..DeviceSession::default() };
    let back = DeviceSession::from_bytes(&long.to_bytes());
    assert_eq!(back.steps.len(), 2);
    assert_eq!((back.steps[0].wait, back.steps[1].wait), (5, 0));
    assert_eq!(back.steps.iter().map(|s| s.bytes.len()).sum::<usize>(), 300);
    // Every input is a session, a truncated one included.
    assert_eq!(DeviceSession::from_bytes(&[]).steps, vec![]);
    assert_eq!(
        DeviceSession::from_bytes(&[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 9, 200, b'x']).steps,
        vec![Step { wait: 9, bytes: vec![b'x'] }]
    );
    assert_eq!(Wait::from_byte(65), Wait::For(Duration::from_millis(50)));
    assert_eq!(Wait::from_byte(255), Wait::UntilIdle(Duration::from_secs(64)));
}

/// The output bound the `device` target enforces holds with room to spare for the longest
/// answers the embedded profiles give.
#[test]
fn longest_responses_fit_the_device_bound() {
    for profile in builtin_profiles() {
        let mut hand = Device::with_profile(profile.clone());
        let longest = ["A?", "?", "FLISTAV", "FLISTA", "PLISTAV", "ERR", "VERS", "RESET"]
            .iter()
            .map(|l| {
                hand.clear_output();
                let now = hand.now();
                hand.handle_input(now, format!("{l}\r").as_bytes());
                hand.take_output().len()
            })
            .max()
            .unwrap();
        assert!(longest * 2 < MAX_RESPONSE, "{}: {longest} bytes", profile.id);
    }
}

/// The grammar seeds hold both accepted and refused lines on every profile, so the round-trip
/// check is reached.
#[test]
fn grammar_seeds_reach_both_outcomes() {
    for profile in builtin_profiles() {
        let accepted = LINES.iter().filter(|l| matches!(parse_line(profile, l.as_bytes()), Ok(Line::Command(_))));
        assert!(accepted.count() >= 10, "{}", profile.id);
        assert!(LINES.iter().filter(|l| parse_line(profile, l.as_bytes()).is_err()).count() >= 10, "{}", profile.id);
    }
}

/// The device seeds reach what they are named for: a RealTime loop, a running command.
#[test]
fn device_seeds_reach_their_modes() {
    for file in seed_files("device").iter().filter(|f| !is_crash(f)) {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let run = gcl_fuzz::device(&std::fs::read(file).unwrap());
        assert!(run.output > 0, "{name}: no output");
        if name.contains("loop") || name.contains("bad-header") {
            assert!(run.modes.contains(&Mode::Loop), "{name}: never in LOOP: {run:?}");
        }
        if name.contains("abort") {
            assert!(run.modes.contains(&Mode::Busy), "{name}: never busy: {run:?}");
        }
    }
}

/// The embedded spec files load (and so reach the session on a loaded profile); the broken
/// ones give typed errors.
#[test]
fn spec_seeds_load_or_fail_as_named() {
    for seed in generate().into_iter().filter(|s| s.target == "spec") {
        let loaded = gcl_fuzz::spec(&seed.bytes);
        let should = !["include-cycle", "missing-include", "shared-only", "bad-toml", "unknown-field"]
            .contains(&seed.name.as_str());
        assert_eq!(loaded, should, "{}", seed.name);
    }
}
