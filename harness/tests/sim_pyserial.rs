//! A Python host (pyserial) against `gcl sim --pty` and `--tcp` (`socket://`): the framing a
//! program outside Rust sees. Needs python3 with pyserial. The test never changes the machine:
//! without pyserial it says so and skips (set GCL_SKIP_PYTHON=1 to skip silently); under CI
//! (`CI=true`, where `.ci/run` installs pyserial) a missing pyserial is a failure.

mod sim_support;

use std::path::Path;
use std::process::Command;

use sim_support::{SimProcess, Transport};

/// Whether python3 with pyserial is there; skips with a message when not (fails under CI).
fn python_ready() -> bool {
    if std::env::var("GCL_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("GCL_SKIP_PYTHON=1: skipping the pyserial check");
        return false;
    }
    let ok = Command::new("python3").args(["-c", "import serial"]).output().is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            !std::env::var("CI").is_ok_and(|v| v == "true"),
            "CI: python3 with pyserial is needed (.ci/run installs it with pip)"
        );
        eprintln!("SKIPPED: python3 with pyserial is not installed (pip install pyserial to run this test)");
    }
    ok
}

fn check(url: &str) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/pyserial_check.py");
    let out = Command::new("python3").arg(&script).arg(url).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && stdout.trim() == "ok", "pyserial_check.py {url}:\n{stdout}\n{stderr}");
}

#[test]
fn pyserial_talks_to_the_simulator() {
    if !python_ready() {
        return;
    }
    let pty = SimProcess::start(Transport::Pty, &["--profile", "seed"]);
    check(&pty.address);
    // Reopening the port: the script runs again on the same hand.
    check(&pty.address);
    let tcp = SimProcess::start(Transport::Tcp, &["--profile", "seed"]);
    check(&format!("socket://{}", tcp.address));
}
