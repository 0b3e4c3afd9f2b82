//! A Python host (pyserial) against `gcl sim --pty` and `--tcp` (`socket://`): the framing a
//! program outside Rust sees, and a Python host that behaves as BH8-262 host libraries do
//! (`python/host_compat.py`). Needs a Python with pyserial, found as every test finds Python
//! (`deps::python_with`: `GCL_PYTHON`, else `target/pyvenv`, else `python3`); without it the
//! tests say so in `cargo test`'s output, and fail under CI (`CI=true`).

use crate::deps;
use crate::sim_support;

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

/// A child process killed (and reaped) when the test lets go of it, however the test ends.
struct Reaped(std::process::Child);

impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// One run of `python/speed_host.py ARGS` against a fresh `gcl sim --pty --profile bh8-262`
/// (the hand at 9600). The host starts first and waits for the port's path on its stdin, which
/// is the simulator's stdout: it opens the port and sets its speed the moment the path is
/// announced, as a CI job that starts both at once may. Returns what the host printed (its
/// `first`/`then` lines) and what the simulator said on stderr.
fn speed_run(py: &str, args: &[&str]) -> (String, String) {
    use std::io::{BufRead, BufReader, Read};
    use std::os::fd::OwnedFd;
    use std::process::Stdio;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/speed_host.py");
    let mut host = Reaped(
        Command::new(py)
            .arg(&script)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap(),
    );
    let mut out = BufReader::new(host.0.stdout.take().unwrap());
    let mut ready = String::new();
    out.read_line(&mut ready).unwrap();
    assert_eq!(ready.trim(), "ready");
    let path_to_host: OwnedFd = host.0.stdin.take().unwrap().into();
    let log = tempfile::NamedTempFile::new().unwrap();
    let _sim = Reaped(
        Command::new(sim_support::GCL)
            .args(["sim", "--pty", "--profile", "bh8-262"])
            .stdin(Stdio::null())
            .stdout(Stdio::from(path_to_host))
            .stderr(log.reopen().unwrap())
            .spawn()
            .unwrap(),
    );
    let mut printed = String::new();
    out.read_to_string(&mut printed).unwrap();
    assert!(host.0.wait().unwrap().success(), "speed_host.py {args:?} failed:\n{printed}");
    (printed, std::fs::read_to_string(log.path()).unwrap())
}

/// The bytes a `speed_host.py` line of `printed` holds (`first HEX`, `then HEX`).
fn printed_bytes(printed: &str, which: &str) -> Vec<u8> {
    let hex = printed.lines().find_map(|l| l.strip_prefix(which)).unwrap_or_else(|| panic!("no {which}: {printed}"));
    (0..hex.trim().len()).step_by(2).map(|i| u8::from_str_radix(&hex.trim()[i..i + 2], 16).unwrap()).collect()
}

/// `runs` runs of [`speed_run`], a few at a time; each run's result.
fn speed_runs(py: &str, args: &[&str], runs: usize) -> Vec<(String, String)> {
    let threads = 4;
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| s.spawn(move || (t..runs).step_by(threads).map(|_| speed_run(py, args)).collect::<Vec<_>>()))
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    })
}

/// Issue 29 item 6: a host that sets 115200 on a hand at 9600 got clean answers in about one
/// run of three (the simulator set the hand's rate again after it had announced the port, over
/// the host's own setting). Over 20 runs, every run at the wrong speed is garbled and said so
/// once, and the same host that then finds the right speed talks; and a host at the right
/// speed is clean in every run, with nothing said (no false alarm).
#[test]
fn the_speed_a_host_sets_is_judged_on_every_run() {
    let Some(py) = deps::python_with(&["serial"]) else {
        return;
    };
    let notice = "gcl sim: the host opened the port at 115200 baud; the hand runs at 9600: bytes are garbled";
    for (printed, said) in speed_runs(&py, &["115200", "9600"], 20) {
        let first = printed_bytes(&printed, "first ");
        assert!(first.iter().all(|b| *b >= 0x80), "at 115200 nothing the hand sends is readable: {first:?}");
        assert_eq!(said.matches(notice).count(), 1, "the simulator says why, once:\n{said}");
        let then = printed_bytes(&printed, "then ");
        assert!(then.ends_with(b"\n\r=> ") && then.iter().all(|b| *b < 0x80), "at 9600 it talks: {then:?}");
    }
    for (printed, said) in speed_runs(&py, &["9600"], 20) {
        assert_eq!(printed_bytes(&printed, "first "), b"\n\r=> ", "at the hand's speed: {printed}");
        assert!(!said.contains("garbled"), "no alarm at the right speed:\n{said}");
    }
}
