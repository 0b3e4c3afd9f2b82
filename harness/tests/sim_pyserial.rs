//! A Python host (pyserial) against `gcl sim --pty` and `--tcp` (`socket://`): the framing a
//! program outside Rust sees, and a Python host that behaves as BH8-262 host libraries do
//! (`python/host_compat.py`). Needs a Python with pyserial: `GCL_PYTHON`, else a virtual
//! environment at `target/pyvenv` if there is one (`python3 -m venv target/pyvenv &&
//! target/pyvenv/bin/pip install pyserial`), else `python3`. The test never changes the
//! machine: without pyserial it says so and skips (GCL_SKIP_PYTHON=1 skips it quietly); under
//! CI (`CI=true`, where `.ci/run` installs pyserial) a missing pyserial is a failure.

mod sim_support;

use std::path::Path;
use std::process::Command;

use sim_support::{SimProcess, Transport};

/// The Python interpreter to use.
fn python() -> String {
    if let Ok(p) = std::env::var("GCL_PYTHON") {
        return p;
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/pyvenv/bin/python");
    if venv.exists() { venv.display().to_string() } else { "python3".into() }
}

/// Whether a Python with pyserial is there; skips with a message when not (fails under CI).
fn python_ready() -> bool {
    if std::env::var("GCL_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("GCL_SKIP_PYTHON=1: skipping the pyserial check");
        return false;
    }
    let ok = Command::new(python()).args(["-c", "import serial"]).output().is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            !std::env::var("CI").is_ok_and(|v| v == "true"),
            "CI: python3 with pyserial is needed (.ci/run installs it with pip)"
        );
        eprintln!(
            "SKIPPED: {} has no pyserial (python3 -m venv target/pyvenv && target/pyvenv/bin/pip install pyserial)",
            python()
        );
    }
    ok
}

fn check(url: &str) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/pyserial_check.py");
    let out = Command::new(python()).arg(&script).arg(url).output().unwrap();
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

#[test]
fn a_python_host_behaves_like_the_host_libraries_on_the_pty() {
    if !python_ready() {
        return;
    }
    // The defaults of `gcl sim`: real time, paced at the hand's BAUD.
    let pty = SimProcess::start_exact(Transport::Pty, &["--profile", "bh8-262"]);
    std::thread::sleep(std::time::Duration::from_millis(200));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/host_compat.py");
    let out = Command::new(python()).arg(&script).arg(&pty.address).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && stdout.trim() == "ok", "host_compat.py:\n{stdout}\n{stderr}");
}
