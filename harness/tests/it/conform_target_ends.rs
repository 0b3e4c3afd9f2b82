//! How `gcl conform` ends against hands that cannot give a verdict on every case: a hand whose
//! motions end at once (the abort-timing cases are SKIP, with one line that says why, unless
//! `--assume-real-time`), and a hand that vanishes mid-run (an infrastructure error: exit 2,
//! `result: ERROR`, and no clause blamed for the dead link).

use std::process::Command;

fn gcl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_gcl"))
}

fn conform(target: &str, extra: &[&str]) -> (i32, String, String) {
    let out = gcl().args(["conform", "--target", target, "--profile", "seed"]).args(extra).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_hand_whose_motions_end_at_once_skips_the_abort_timing_cases_and_says_why() {
    let target = format!("exec:{} sim --stdio --profile seed", env!("CARGO_BIN_EXE_gcl"));
    let (code, out, err) = conform(&target, &[]);
    assert_eq!(code, 0, "{out}\n{err}");
    // Said once, on stderr with the pre-flight line (the summary on stdout does not repeat it).
    assert!(err.contains("motion-time probe: the target's motions end at once"), "{err}");
    assert_eq!(format!("{out}{err}").matches("motion-time probe").count(), 1, "one line says it: {out}{err}");
    // Exit 0, but not a PASS: the abort-timing cases did not run (issue 29 item 5).
    assert!(out.contains("result: PARTIAL: ") && out.contains(" cases\n"), "{out}");
    // The user insists: the abort-timing cases run, and fail on this hand.
    let (code, out, err) = conform(&target, &["--assume-real-time"]);
    assert_eq!(code, 1, "{out}");
    assert!(!format!("{out}{err}").contains("motion-time probe"), "{out}{err}");
    assert!(out.contains("result: FAIL"), "{out}");
}

#[test]
fn a_hand_that_vanishes_mid_run_is_an_error_not_a_clause() {
    let dir = tempfile::tempdir().unwrap();
    let flag = dir.path().join("started");
    // The hand answers for a second the first time it is started, and never again.
    let script = format!(
        "if [ -e '{f}' ]; then exit 1; fi; touch '{f}'; exec timeout 1 '{g}' sim --stdio --profile seed",
        f = flag.display(),
        g = env!("CARGO_BIN_EXE_gcl")
    );
    let sh = dir.path().join("hand.sh");
    std::fs::write(&sh, script).unwrap();
    // (abort-timing off: on this fast hand those cases fail for their own reason, and the run
    // must fail for the vanished hand alone)
    let (code, out, err) = conform(&format!("exec:sh {}", sh.display()), &["--no", "abort-timing"]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert!(out.contains("result: ERROR"), "{out}");
    // The reason is said once, on stderr, as it happens; the summary says where the run ended.
    assert!(err.contains("the hand vanished"), "{err}");
    assert!(out.contains("ended early at case"), "{out}");
    assert!(!out.contains("root causes first"), "a dead link is no group: {out}");
}
