//! Tools outside Rust that some tests need (Python, pyserial, junitparser, a C compiler with
//! AddressSanitizer, an example binary): one way to find each, and one way to say a test did
//! not run.
//!
//! Python is `GCL_PYTHON`, else the virtual environment at `target/pyvenv`, else `python3`
//! (README). The first test that needs Python makes `target/pyvenv` with the packages the tests
//! use ([`VENV_PACKAGES`], from PyPI), once for every test process of the run: under a lock
//! (`flock` on `target/pyvenv.lock`), so that parallel test binaries wait for the one making it.
//! Where that fails (no network), it is tried again by the next `cargo test`, not by every test
//! of this one. A tool still missing is:
//! - under CI (`CI=true`, where `.ci/run` installs what the tests use): a failure;
//! - elsewhere: a skip that shows in `cargo test`'s default output, never a silent pass.
//!   libtest keeps what a test prints with `eprintln!` (and `io::stderr()`) to itself unless
//!   the test fails, so the line is written to a duplicate of file descriptor 2, which it does
//!   not capture: `SKIPPED <test>: <what is missing> (<how to get it>)`. libtest counts such a
//!   test as passed, so when the test binary ends (after its `test result:` line) one line
//!   says how many of its tests did not run, and how many this run has skipped so far (the
//!   skips of the run's test binaries are kept in `target/test-skips/`, one file per run): the
//!   last such line of a run is its total.

#![allow(dead_code)] // each test file uses a part

use std::io::Write;
use std::os::fd::AsFd;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

/// What the tests' venv holds: pyserial (hosts and clients over a serial port) and
/// junitparser (a real JUnit consumer for the reports).
pub const VENV_PACKAGES: &[&str] = &["pyserial", "junitparser"];
/// The modules those packages give, to check that a venv has them.
const VENV_MODULES: &[&str] = &["serial", "junitparser"];

/// How to get what the tests' Python needs by hand.
pub const VENV_HOW: &str =
    "python3 -m venv target/pyvenv && target/pyvenv/bin/pip install pyserial junitparser, or set GCL_PYTHON";

/// Whether this is a CI run (`CI=true`), where nothing may be skipped.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// The repository's `target/`.
fn target() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap_or(Path::new("..")).join("target")
}

/// The test under way: libtest names each test's thread after it.
fn test_name() -> String {
    std::thread::current().name().unwrap_or("a test").to_string()
}

/// A line on the test process's real stderr, past libtest's capture.
fn say(line: &str) {
    match std::io::stderr().as_fd().try_clone_to_owned() {
        Ok(fd) => {
            let _ = std::fs::File::from(fd).write_all(line.as_bytes());
        }
        Err(_) => eprint!("{line}"),
    }
}

/// The run this test process is part of: its parent (`cargo test`, or `cargo nextest`, which
/// start every test binary or test) and the time that parent started, so that what an
/// earlier run left under the same process id is not taken for this run's.
fn run_key() -> String {
    let parent = nix::unistd::getppid();
    let started = std::fs::read_to_string(format!("/proc/{parent}/stat"))
        .ok()
        .and_then(|s| s.rsplit_once(')').and_then(|(_, rest)| rest.split_whitespace().nth(19).map(str::to_string)))
        .unwrap_or_default();
    format!("{parent}-{started}")
}

/// The test under way cannot run for want of `what` (`how` says how to get it): a failure
/// under CI, else a visible line, counted in the summary the test binary prints as it ends.
pub fn missing(what: &str, how: &str) {
    let test = test_name();
    assert!(!under_ci(), "CI: {test} needs {what} ({how})");
    say(&format!("SKIPPED {test}: {what} is missing ({how})\n"));
    record_skip(&test, what, how);
}

/// The skips of this run, one line each: `pid TAB test TAB what TAB how`.
fn skips_file() -> PathBuf {
    target().join("test-skips").join(format!("{}.tsv", run_key()))
}

fn record_skip(test: &str, what: &str, how: &str) {
    static FILE: Mutex<()> = Mutex::new(());
    let _one_at_a_time = FILE.lock().unwrap_or_else(|e| e.into_inner());
    let path = skips_file();
    let dir = path.parent().unwrap();
    let _ = std::fs::create_dir_all(dir);
    // The files of runs a day old go.
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let old = e
                .metadata()
                .and_then(|m| m.modified())
                .is_ok_and(|t| t.elapsed().is_ok_and(|age| age > std::time::Duration::from_secs(24 * 3600)));
            if old {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    let clean = |s: &str| s.replace(['\t', '\n'], " ");
    let line = format!("{}\t{}\t{}\t{}\n", std::process::id(), clean(test), clean(what), clean(how));
    if let Ok(mut f) = std::fs::OpenOptions::new().create(true).append(true).open(&path) {
        let _ = f.write_all(line.as_bytes());
    }
    static SUMMARY: OnceLock<()> = OnceLock::new();
    SUMMARY.get_or_init(at_exit_say_summary);
}

/// Has [`summary`] run as the process exits (libtest has no hook after its last line).
#[allow(unsafe_code)]
fn at_exit_say_summary() {
    // SAFETY: `summary` is an `extern "C"` function that takes no arguments, returns nothing
    // and does not unwind, as `atexit` requires; it runs once, as the process exits.
    unsafe {
        nix::libc::atexit(summary);
    }
}

/// Said as the test binary exits (after libtest's `test result:` line): how many of its tests
/// were skipped and so counted as passed, and how many the run has skipped so far.
extern "C" fn summary() {
    let text = std::fs::read_to_string(skips_file()).unwrap_or_default();
    let me = std::process::id().to_string();
    let rows: Vec<Vec<&str>> =
        text.lines().map(|l| l.split('\t').collect::<Vec<&str>>()).filter(|r| r.len() == 4).collect();
    let here = rows.iter().filter(|r| r[0] == me).count();
    if here == 0 {
        return;
    }
    let mut whats: Vec<(&str, usize)> = Vec::new();
    let mut hows: Vec<&str> = Vec::new();
    for r in &rows {
        match whats.iter_mut().find(|(w, _)| *w == r[2]) {
            Some((_, n)) => *n += 1,
            None => whats.push((r[2], 1)),
        }
        if !hows.contains(&r[3]) {
            hows.push(r[3]);
        }
    }
    let whats: Vec<String> = whats.iter().map(|(w, n)| format!("{w} ({n})")).collect();
    say(&format!(
        "SKIPPED: {here} of the tests above did not run (libtest counts them as passed); {} tests skipped so far \
in this run, for want of: {}; run: {}\n",
        rows.len(),
        whats.join(", "),
        hows.join("; ")
    ));
}

/// The Python interpreter: `GCL_PYTHON`, else `target/pyvenv/bin/python` (made with
/// [`VENV_PACKAGES`] the first time it is needed), else `python3`.
pub fn python() -> String {
    if let Ok(p) = std::env::var("GCL_PYTHON")
        && !p.is_empty()
    {
        return p;
    }
    let venv = target().join("pyvenv/bin/python");
    static MADE: OnceLock<()> = OnceLock::new();
    MADE.get_or_init(make_venv);
    if venv.exists() { venv.display().to_string() } else { "python3".into() }
}

/// Whether `python` runs and imports every module of `modules`.
fn imports(python: &Path, modules: &[&str]) -> bool {
    let imports = if modules.is_empty() { "pass".to_string() } else { format!("import {}", modules.join(", ")) };
    Command::new(python).args(["-c", &imports]).output().is_ok_and(|o| o.status.success())
}

/// Makes `target/pyvenv` with [`VENV_PACKAGES`] unless it has them, under a lock that other
/// test processes wait on; a failure is said once and not tried again in this run.
fn make_venv() {
    let target = target();
    let venv = target.join("pyvenv");
    let py = venv.join("bin/python");
    if imports(&py, VENV_MODULES) {
        return;
    }
    let failed = target.join("pyvenv.failed");
    let key = run_key();
    let tried = || std::fs::read_to_string(&failed).is_ok_and(|t| t.lines().next() == Some(key.as_str()));
    if tried() {
        return;
    }
    let _ = std::fs::create_dir_all(&target);
    let Ok(file) = std::fs::File::create(target.join("pyvenv.lock")) else { return };
    let Ok(_lock) = nix::fcntl::Flock::lock(file, nix::fcntl::FlockArg::LockExclusive) else { return };
    // Another test process may have made it (or failed to) while this one waited.
    if imports(&py, VENV_MODULES) || tried() {
        return;
    }
    say(&format!("making target/pyvenv (Python with {}) for the tests that need it, once\n", VENV_PACKAGES.join(", ")));
    let run = |program: &Path, args: &[&str]| -> Result<(), String> {
        let o = Command::new(program)
            .args(args)
            .output()
            .map_err(|e| format!("{} {}: {e}", program.display(), args.join(" ")))?;
        if o.status.success() {
            return Ok(());
        }
        let err = String::from_utf8_lossy(&o.stderr);
        let last = err.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("").trim().to_string();
        Err(format!("{} {} failed: {last}", program.display(), args.join(" ")))
    };
    let made = (|| {
        if !py.exists() {
            run(Path::new("python3"), &["-m", "venv", &venv.display().to_string()])?;
        }
        let mut args = vec!["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--retries", "1"];
        args.extend(["--timeout", "15"]);
        args.extend(VENV_PACKAGES);
        run(&py, &args)
    })();
    match made {
        Ok(()) => {
            let _ = std::fs::remove_file(&failed);
        }
        Err(why) => {
            say(&format!("could not make target/pyvenv: {why}\n"));
            let _ = std::fs::write(&failed, format!("{key}\n{why}\n"));
        }
    }
}

/// [`python`] when it runs and imports every module of `modules`; `None` after [`missing`]
/// otherwise.
pub fn python_with(modules: &[&str]) -> Option<String> {
    let py = python();
    if imports(Path::new(&py), modules) {
        return Some(py);
    }
    let what = if modules.is_empty() {
        format!("a Python interpreter ({py})")
    } else {
        format!("{py} with the Python module(s) {}", modules.join(", "))
    };
    missing(&what, VENV_HOW);
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

/// How to get AFL++'s compiler (issue 42: hosts built with coverage instrumentation).
pub const AFL_HOW: &str = "apt-get install afl++ (Debian/Ubuntu)";

/// `afl-cc` (AFL++'s compiler wrapper) when it is on `PATH` and builds a program; `None` after
/// [`missing`] otherwise.
pub fn afl_cc() -> Option<String> {
    let works = Command::new("afl-cc").arg("--version").output().is_ok_and(|o| o.status.success());
    if works {
        return Some("afl-cc".into());
    }
    missing("afl-cc (AFL++)", AFL_HOW);
    None
}

/// How to get python-afl by hand.
pub const PYTHON_AFL_HOW: &str =
    "target/pyvenv/bin/python -m pip install python-afl, or set GCL_PYTHON to a Python with it";

/// [`python`] with pyserial and python-afl (the `afl` module), which is installed into
/// `target/pyvenv` the first time it is needed (under the venv's lock; it builds a C
/// extension); `None` after [`missing`] when that fails.
pub fn python_afl() -> Option<String> {
    let py = python();
    let has = |py: &str| imports(Path::new(py), &["serial", "afl"]);
    if has(&py) {
        return Some(py);
    }
    let venv = target().join("pyvenv/bin/python");
    if std::env::var("GCL_PYTHON").map_or(true, |p| p.is_empty()) && venv.exists() {
        static TRIED: OnceLock<()> = OnceLock::new();
        TRIED.get_or_init(|| {
            let Ok(file) = std::fs::File::create(target().join("pyvenv.lock")) else { return };
            let Ok(_lock) = nix::fcntl::Flock::lock(file, nix::fcntl::FlockArg::LockExclusive) else { return };
            if has(&py) {
                return;
            }
            say("installing python-afl into target/pyvenv for the coverage tests, once\n");
            let _ = Command::new(&venv)
                .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--retries", "1"])
                .args(["--timeout", "15", "python-afl"])
                .output();
        });
        if has(&py) {
            return Some(py);
        }
    }
    missing(&format!("{py} with the Python modules serial, afl (python-afl)"), PYTHON_AFL_HOW);
    None
}
