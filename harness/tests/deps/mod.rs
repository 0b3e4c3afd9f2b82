//! Tools outside Rust that some tests need (Python, pyserial, a C compiler with
//! AddressSanitizer, an example binary): one way to find each, and one way to say a test did
//! not run.
//!
//! Python is `GCL_PYTHON`, else the virtual environment at `target/pyvenv`, else `python3`
//! (README). The tests never change the machine. A missing tool is:
//! - under CI (`CI=true`, where `.ci/run` installs what the tests use): a failure;
//! - elsewhere: a skip that shows in `cargo test`'s default output. libtest keeps what a test
//!   prints with `eprintln!` (and `io::stderr()`) to itself unless the test fails, so the line
//!   is written to a duplicate of file descriptor 2, which it does not capture:
//!   `SKIPPED <test>: <what is missing> (<how to get it>)`.

#![allow(dead_code)] // each test file uses a part

use std::io::Write;
use std::os::fd::AsFd;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Whether this is a CI run (`CI=true`), where nothing may be skipped.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// The test under way: libtest names each test's thread after it.
fn test_name() -> String {
    std::thread::current().name().unwrap_or("a test").to_string()
}

/// The test under way cannot run for want of `what` (`how` says how to get it): a failure
/// under CI, else a visible line.
pub fn missing(what: &str, how: &str) {
    let test = test_name();
    assert!(!under_ci(), "CI: {test} needs {what} ({how})");
    let line = format!("SKIPPED {test}: {what} is missing ({how})\n");
    match std::io::stderr().as_fd().try_clone_to_owned() {
        Ok(fd) => {
            let _ = std::fs::File::from(fd).write_all(line.as_bytes());
        }
        Err(_) => eprint!("{line}"),
    }
}

/// The Python interpreter: `GCL_PYTHON`, else `target/pyvenv/bin/python` when it exists, else
/// `python3`.
pub fn python() -> String {
    if let Ok(p) = std::env::var("GCL_PYTHON")
        && !p.is_empty()
    {
        return p;
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/pyvenv/bin/python");
    if venv.exists() { venv.display().to_string() } else { "python3".into() }
}

/// [`python`] when it runs and imports every module of `modules`; `None` after [`missing`]
/// otherwise.
pub fn python_with(modules: &[&str]) -> Option<String> {
    let py = python();
    let imports = if modules.is_empty() { "pass".to_string() } else { format!("import {}", modules.join(", ")) };
    let ok = Command::new(&py).args(["-c", &imports]).output().is_ok_and(|o| o.status.success());
    if ok {
        return Some(py);
    }
    let what = if modules.is_empty() {
        format!("a Python interpreter ({py})")
    } else {
        format!("{py} with the Python module(s) {}", modules.join(", "))
    };
    missing(&what, "python3 -m venv target/pyvenv && target/pyvenv/bin/pip install pyserial, or set GCL_PYTHON");
    None
}

/// An example program of this package (`cargo build --examples`, as `cargo test` does), or
/// `None` after [`missing`].
pub fn example(name: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_BIN_EXE_gcl")).with_file_name("examples").join(name);
    if p.exists() {
        return Some(p);
    }
    missing(&format!("the example {}", p.display()), "cargo test --workspace builds the examples");
    None
}
