//! Issue 37: a serial campaign asked to change the hand's line rate (`--allow rate-change`)
//! follows it. A module of its own so that `.ci/run` runs it in its waiting lane, at normal
//! priority beside the other tests that wait on a hand paced in real time: in the counting
//! lane (nice 10, beside CPU-bound campaigns) the paced simulator answered late enough once
//! that a case failed and became a `not reproduced` note.

use std::process::Command;

use gcl_harness::fuzz::device::report;

use crate::fuzz_device::hand_paced_pty;

/// Issue 37: asked to (`--allow rate-change`), a serial campaign sends rate changes and its port
/// follows each after the hand's answer, as a host library does; before a connection closes the
/// hand is set back to the port's first rate. The hand is `gcl sim --pty` paced at its own BAUD,
/// which garbles both ways while the port's speed and the hand's rate differ. Seed 2 sends
/// `PSET LFDPD 1 BAUD 384` in its first cases, then more lines at 38400, then a RESET (which
/// loads the saved 96). Without the port following, the hand is lost at the first change:
/// garbled answers are findings, or the hand stops answering.
#[test]
fn a_serial_campaign_allowed_to_change_the_rate_follows_it_and_ends_at_the_starting_rate() {
    let (_sim, t) = hand_paced_pty("bh8-262-4.3");
    let dir = tempfile::tempdir().unwrap();
    let rep = dir.path().join("r");
    let out = Command::new(env!("CARGO_BIN_EXE_gcl"))
        .args(["fuzz", "device", "--target", &t.to_string(), "--profile", "bh8-262-4.3", "--no", "motion"])
        .args(["--allow", "rate-change", "--seed", "2", "--runs", "10", "--no-minimize", "-q"])
        .args(["--report", rep.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let r: report::FuzzReport = serde_json::from_slice(&std::fs::read(rep.join("fuzz-device.json")).unwrap())
        .unwrap_or_else(|e| panic!("{e}: {stderr}"));
    let writes = r.coverage.iter().find(|c| c.category == "param-write").expect("write coverage");
    assert!(!writes.missing.iter().any(|m| m == "BAUD"), "the campaign set BAUD: {writes:?}");
    assert!(
        r.findings.is_empty(),
        "{:#?}\n{stderr}",
        r.findings.iter().map(|f| f.signature.to_string()).collect::<Vec<_>>()
    );
    assert!(r.not_reproduced.is_empty(), "{:?}", r.not_reproduced);
    assert_eq!(
        r.hand_after.first().map(String::as_str),
        Some(
            "line: the hand answers at 9600 baud, the rate it started at (cases could change it, --allow \
             rate-change: the port followed each change and set the hand back)"
        ),
        "{stderr}"
    );
    assert_eq!(out.status.code(), Some(0), "{stderr}");
}
