//! The Python consumer in `vectors/python` (stdlib only) works from the files alone: its
//! unit tests pass (vector loader and schema check, transcript reader and matcher, the example
//! host parser against the host vectors), its transcript runner passes the seed suite
//! against `gcl sim --stdio --time real` by the very command `vectors/README.md` gives, and it fails against simulator faults naming the same cases
//! `gcl conform` names (six faults). Python is found as every test finds it (`deps`); without one the tests
//! say so in `cargo test`'s output, and fail under CI.

use crate::deps;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const GCL: &str = env!("CARGO_BIN_EXE_gcl");

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn python_dir() -> PathBuf {
    root().join("vectors/python")
}

struct Ran {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs a command in `dir` with a deadline; the child is killed when it passes.
fn run(dir: &Path, program: &str, args: &[&str], limit: Duration) -> Ran {
    let out = tempfile::NamedTempFile::new().unwrap();
    let err = tempfile::NamedTempFile::new().unwrap();
    let mut child = Command::new(program)
        .args(args)
        .current_dir(dir)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::from(out.reopen().unwrap()))
        .stderr(Stdio::from(err.reopen().unwrap()))
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let read = |f: &tempfile::NamedTempFile| std::fs::read_to_string(f.path()).unwrap_or_default();
    let ran = Ran { code: status.and_then(|s| s.code()), stdout: read(&out), stderr: read(&err) };
    assert!(status.is_some(), "{program} {args:?} ran past {limit:?}:\n{}\n{}", ran.stdout, ran.stderr);
    ran
}

/// The committed goldens of a profile, every one of them.
fn suite_files(profile: &str) -> Vec<String> {
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root().join("vectors/suite/index.json")).unwrap()).unwrap();
    index["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["profile"] == profile)
        .map(|c| format!("../suite/{}", c["path"].as_str().unwrap()))
        .collect()
}

/// The replay `vectors/README.md` gives (section 6), run from `vectors/python` as written; the
/// simulator in real time, as the cases that send ^C during a motion need.
const DOCUMENTED_REPLAY: &str =
    r#"python3 -m gcl_vectors replay --target "exec:gcl sim --stdio --time real --profile seed" ../suite/seed/*.gcl"#;

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn the_python_package_tests_pass() {
    let Some(py) = deps::python_with(&[]) else {
        return;
    };
    let r =
        run(&python_dir(), &py, &["-m", "unittest", "discover", "-s", "tests", "-t", "."], Duration::from_secs(120));
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("OK"), "{}", r.stderr);
    let r = run(&python_dir(), &py, &["-m", "gcl_vectors", "check", "-q"], Duration::from_secs(60));
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
}

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn the_python_runner_passes_the_seed_suite_against_the_simulator() {
    let Some(py) = deps::python_with(&[]) else {
        return;
    };
    let files = suite_files("seed");
    assert!(files.len() > 150, "{}", files.len());
    let readme = std::fs::read_to_string(root().join("vectors/README.md")).unwrap();
    assert!(readme.contains(DOCUMENTED_REPLAY), "vectors/README.md no longer gives `{DOCUMENTED_REPLAY}`");
    // The command as written, by a shell whose `python3` and `gcl` are the tests'.
    let bin = tempfile::tempdir().unwrap();
    let word = "python3"; // the documented command's word for deps::python_with's interpreter
    std::os::unix::fs::symlink(&py, bin.path().join(word)).unwrap();
    std::os::unix::fs::symlink(GCL, bin.path().join("gcl")).unwrap();
    let script = format!("PATH='{}':\"$PATH\"; {DOCUMENTED_REPLAY}", bin.path().display());
    let r = run(&python_dir(), "sh", &["-c", &script], Duration::from_secs(900));
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    // Every case ran, the five that send ^C during a motion among them.
    let aborts = files.iter().filter(|f| f.contains("abort-motion")).count();
    assert!(aborts >= 2, "{files:?}");
    // A case whose setup places an object cannot run on this runner's hand without the object
    // declared in place: it is SKIP, and every other case passes.
    let placed: Vec<&String> = files
        .iter()
        .filter(|f| std::fs::read_to_string(python_dir().join(f)).unwrap().contains("\nsetup: object "))
        .collect();
    assert!(!placed.is_empty(), "the seed suite has a case with a setup (param-hold-effect)");
    let skipped: Vec<&str> = r.stdout.lines().filter(|l| l.starts_with("SKIP ")).collect();
    assert_eq!(skipped.len(), placed.len(), "{}", r.stdout);
    assert!(placed.iter().all(|f| skipped.iter().any(|l| l.contains(f.as_str()))), "{}", r.stdout);
    assert_eq!(r.stdout.lines().filter(|l| l.starts_with("PASS ")).count(), files.len() - placed.len(), "{}", r.stdout);
    assert_eq!(
        r.stdout.lines().last(),
        Some(format!("{} passed, 0 failed, {} skipped", files.len() - placed.len(), placed.len()).as_str()),
        "{}",
        r.stdout
    );
}

/// Cases named for each fault (as in `conform_mutants`), and others that must still pass.
const FAULTS: &[(&str, &[&str])] = &[
    ("no-echo", &["framing-echo"]),
    ("read-only-status", &["status-256-read-only", "param-p-read-only"]),
    ("lfap-little-endian", &["rt-lfap-byte-order"]),
    // Relations: the Python runner carries captures from value to value.
    ("lcvc-ignored", &["rt-lcvc-scaling"]),
    ("lfvc-ignored", &["rt-lfvc-scaling"]),
    // {text}: VERS answered with a status line is no version text.
    ("vers-unknown", &["cmd-vers"]),
];
const BYSTANDERS: &[&str] = &["framing-empty-line", "cmd-fget", "param-dp-default", "status-32-unknown-command"];

#[test]
fn the_python_runner_fails_against_faults_naming_the_cases_gcl_conform_names() {
    let Some(py) = deps::python_with(&[]) else {
        return;
    };
    let profile = "bh8-262-4.4";
    let mut ids: Vec<&str> = FAULTS.iter().flat_map(|(_, c)| c.iter().copied()).collect();
    ids.extend(BYSTANDERS);
    for id in &ids {
        assert!(root().join(format!("vectors/suite/{profile}/{id}.gcl")).is_file(), "no case {id}");
    }
    for (fault, catchers) in FAULTS {
        // gcl conform, in process, over the same cases.
        let dir = tempfile::tempdir().unwrap();
        let rep = dir.path().to_str().unwrap();
        let sim = format!("sim:{profile}");
        let mut args = vec!["conform", "--target", &sim, "--fault", fault, "-q", "--report", rep];
        for id in &ids {
            args.extend(["--only", id]);
        }
        let c = run(&root(), GCL, &args, Duration::from_secs(120));
        assert_eq!(c.code, Some(1), "{fault}: {}", c.stdout);
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
        let by_conform: BTreeSet<String> = report["cases"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["verdict"] == "FAIL" || c["verdict"] == "TIMEOUT")
            .map(|c| c["id"].as_str().unwrap().to_string())
            .collect();

        // The Python runner over exec, against a simulator with the same fault.
        let target = format!("exec:{GCL} sim --stdio --profile {profile} --fault {fault}");
        let files: Vec<String> = ids.iter().map(|id| format!("../suite/{profile}/{id}.gcl")).collect();
        let mut args = vec!["-m", "gcl_vectors", "replay", "-q", "--target", &target];
        args.extend(files.iter().map(String::as_str));
        let p = run(&python_dir(), &py, &args, Duration::from_secs(300));
        assert_eq!(p.code, Some(1), "{fault}: {}\n{}", p.stdout, p.stderr);
        let by_python: BTreeSet<String> = p
            .stdout
            .lines()
            .filter(|l| l.starts_with("FAIL ") || l.starts_with("TIMEOUT "))
            .filter_map(|l| l.split_whitespace().nth(1))
            .filter_map(|f| Path::new(f.trim_end_matches(':')).file_stem()?.to_str().map(str::to_string))
            .collect();
        for c in *catchers {
            assert!(by_conform.contains(*c), "{fault}: gcl conform should name {c}: {by_conform:?}");
        }
        assert_eq!(by_python, by_conform, "{fault}: the Python runner and gcl conform name the same cases");
    }
}

#[test]
fn the_python_runner_exits_2_on_bad_files_and_targets() {
    let Some(py) = deps::python_with(&[]) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.gcl");
    std::fs::write(&bad, "gcl-transcript 1\nid: x\n").unwrap();
    let target = format!("exec:{GCL} sim --stdio --profile seed");
    let r = run(
        &python_dir(),
        &py,
        &["-m", "gcl_vectors", "replay", "--target", &target, bad.to_str().unwrap()],
        Duration::from_secs(60),
    );
    assert_eq!(r.code, Some(2), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("bad.gcl"), "{}", r.stderr);
    let good = "../suite/seed/framing-echo.gcl";
    for t in ["bogus:x", "sim:seed", "tcp://127.0.0.1", "exec:"] {
        let r = run(&python_dir(), &py, &["-m", "gcl_vectors", "replay", "--target", t, good], Duration::from_secs(60));
        assert_eq!(r.code, Some(2), "{t}: {}\n{}", r.stdout, r.stderr);
    }
    // A hand that is gone before the first step (as `gcl replay` says of it: exit 2).
    let r = run(
        &python_dir(),
        &py,
        &["-m", "gcl_vectors", "replay", "--target", "exec:true", good],
        Duration::from_secs(60),
    );
    assert_eq!(r.code, Some(2), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("the process ended"), "{}", r.stderr);
}
