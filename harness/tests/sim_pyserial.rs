//! A Python host (pyserial) against `gcl sim --pty` and `--tcp` (`socket://`): the framing a
//! program outside Rust sees. Needs python3; installs pyserial with pip when it is missing, so
//! `cargo test` alone is enough on a fresh machine. Set GCL_SKIP_PYTHON=1 to skip.

mod sim_support;

use std::path::Path;
use std::process::Command;

use sim_support::{SimProcess, Transport};

fn python_ready() -> bool {
    if std::env::var("GCL_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("GCL_SKIP_PYTHON=1: skipping the pyserial check");
        return false;
    }
    let has_pyserial =
        || Command::new("python3").args(["-c", "import serial"]).output().is_ok_and(|o| o.status.success());
    if !has_pyserial() {
        eprintln!("pyserial is missing: installing it with `python3 -m pip install pyserial`");
        for extra in [None, Some("--user")] {
            let mut pip = Command::new("python3");
            pip.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "pyserial"]);
            pip.args(extra);
            if pip.status().is_ok_and(|s| s.success()) && has_pyserial() {
                break;
            }
        }
    }
    let ok = has_pyserial();
    assert!(
        ok,
        "python3 with pyserial is needed for this test: pip install pyserial (or set GCL_SKIP_PYTHON=1 to skip it)"
    );
    true
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
