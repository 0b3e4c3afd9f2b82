//! A Python host (pyserial) against `gcl sim --pty` and `--tcp` (`socket://`): the framing a
//! program outside Rust sees, and a Python host that behaves as BH8-262 host libraries do
//! (`python/host_compat.py`). Needs a Python with pyserial, found as every test finds Python
//! (`deps::python_with`: `GCL_PYTHON`, else `target/pyvenv`, else `python3`); without it the
//! tests say so in `cargo test`'s output, and fail under CI (`CI=true`).

mod deps;
mod sim_support;

use std::path::Path;
use std::process::Command;

use sim_support::{SimProcess, Transport};

fn check(python: &str, url: &str) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/pyserial_check.py");
    let out = Command::new(python).arg(&script).arg(url).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && stdout.trim() == "ok", "pyserial_check.py {url}:\n{stdout}\n{stderr}");
}

#[test]
fn pyserial_talks_to_the_simulator() {
    let Some(py) = deps::python_with(&["serial"]) else {
        return;
    };
    let pty = SimProcess::start(Transport::Pty, &["--profile", "seed"]);
    check(&py, &pty.address);
    // Reopening the port: the script runs again on the same hand.
    check(&py, &pty.address);
    let tcp = SimProcess::start(Transport::Tcp, &["--profile", "seed"]);
    check(&py, &format!("socket://{}", tcp.address));
}

#[test]
fn a_python_host_behaves_like_the_host_libraries_on_the_pty() {
    let Some(py) = deps::python_with(&["serial"]) else {
        return;
    };
    // The defaults of `gcl sim`: real time, paced at the hand's BAUD.
    let pty = SimProcess::start_exact(Transport::Pty, &["--profile", "bh8-262"]);
    std::thread::sleep(std::time::Duration::from_millis(200));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/host_compat.py");
    let out = Command::new(&py).arg(&script).arg(&pty.address).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && stdout.trim() == "ok", "host_compat.py:\n{stdout}\n{stderr}");
}
