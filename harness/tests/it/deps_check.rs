//! The rule for tests that need tools outside Rust (`deps`): one way to find Python for every
//! test, a missing tool fails under CI (`CI=true`), and elsewhere the skip shows in `cargo
//! test`'s default output (issue 21 item 1).

use crate::deps;

use std::path::Path;
use std::process::Command;

/// The probe the next test runs in a child: a test that needs pyserial.
#[test]
fn needs_pyserial() {
    let Some(py) = deps::python_with(&["serial"]) else {
        return;
    };
    assert!(Command::new(py).args(["-c", "import serial"]).status().unwrap().success());
}

#[test]
fn a_missing_tool_is_a_visible_skip_here_and_a_failure_under_ci() {
    let exe = std::env::current_exe().unwrap();
    let run = |ci: &str| {
        Command::new(&exe)
            .args(["--exact", "deps_check::needs_pyserial", "--test-threads", "1"])
            .env("GCL_PYTHON", "/nonexistent/python")
            .env("CI", ci)
            .output()
            .unwrap()
    };
    // Without --nocapture, as `cargo test` runs it: the line is on stderr all the same.
    let local = run("");
    let stderr = String::from_utf8_lossy(&local.stderr);
    assert!(local.status.success(), "{stderr}");
    assert!(
        stderr.contains("SKIPPED deps_check::needs_pyserial: /nonexistent/python with the Python module(s) serial"),
        "{stderr}"
    );
    // libtest counts the skip as a pass; the line after its result says it was not.
    let stdout = String::from_utf8_lossy(&local.stdout);
    assert!(stdout.contains("test result: ok. 1 passed"), "{stdout}");
    assert!(
        stderr.contains(
            "SKIPPED: 1 of the tests above did not run (libtest counts them as passed); 1 tests skipped so far in \
this run, for want of: /nonexistent/python with the Python module(s) serial (1); run: python3 -m venv target/pyvenv"
        ),
        "{stderr}"
    );
    let ci = run("true");
    let stdout = String::from_utf8_lossy(&ci.stdout);
    assert!(!ci.status.success(), "under CI a missing tool fails the test: {stdout}");
    assert!(stdout.contains("CI: deps_check::needs_pyserial needs /nonexistent/python"), "{stdout}");
}

#[test]
fn python_is_found_the_same_way_by_every_test() {
    // GCL_PYTHON first.
    let exe = std::env::current_exe().unwrap();
    let o = Command::new(&exe)
        .args(["--exact", "deps_check::needs_pyserial"])
        .env("GCL_PYTHON", "/opt/elsewhere/python")
        .env_remove("CI")
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("/opt/elsewhere/python"));
    // No test names an interpreter of its own: every one goes through `deps`.
    let tests = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/it");
    let mut offenders = Vec::new();
    for e in std::fs::read_dir(&tests).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "rs") {
            let text = std::fs::read_to_string(&p).unwrap();
            for (i, line) in text.lines().enumerate() {
                // (A line that names the interpreter deps found, as the word a document types for
                // it, says so: `deps::python`.)
                if (line.contains("\"python3\"") || line.contains("\"python\"")) && !line.contains("deps::python") {
                    offenders.push(format!("{}:{}: {}", p.display(), i + 1, line.trim()));
                }
            }
        }
    }
    assert!(offenders.is_empty(), "use deps::python() / deps::python_with():\n{}", offenders.join("\n"));
}
