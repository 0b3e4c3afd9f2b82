//! `gcl fuzz host` guided by the host's own code coverage (issue 42): hosts built with AFL++'s
//! `afl-cc`, or Python hosts with python-afl, write the edges they reach to the map `gcl` gives
//! each run (`__AFL_SHM_ID`); a schedule whose run reached a new edge is kept and mutated.
//!
//! The hosts are `hosts/c_deep_parser.c` and `hosts/py_deep_parser.py`: the same commands
//! whatever they read, and a bug behind four misbehaviours in order (err-bits, garbage,
//! overlong-line, then err-bits of a large code). They need `afl-cc` (`apt-get install afl++`)
//! and python-afl (installed into `target/pyvenv` on first use); without them the tests are
//! skipped with a line, and fail under CI (`CI=true`).

use crate::deps;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use gcl_harness::fuzz::host::coverage::{CoverageAccount, CoverageUse, NOT_INSTRUMENTED};
use gcl_harness::fuzz::host::{Campaign, FindingKind, FuzzOptions, HostRun, Slots, Transport, Weights, fuzz};
use gcl_harness::sim::{Pace, TimeMode};

fn hosts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hosts")
}

/// The misbehaviours the deep hosts' bug needs, and one more: every answer still ends in a
/// prompt (but where garbage lands in it), so no run waits out the host's 1 s deadline often.
const OPS: &str = "err-bits,garbage,overlong-line,crlf";

/// `hosts/c_deep_parser.c` built into `dir` with `compiler` (`afl-cc` or `cc`).
fn build(compiler: &str, dir: &Path) -> Option<String> {
    let out = dir.join(format!("deep-{}", compiler.replace('-', "_")));
    let o = Command::new(compiler)
        .args(["-O0", "-g", "-o"])
        .arg(&out)
        .arg(hosts().join("c_deep_parser.c"))
        .env("AFL_QUIET", "1")
        .output();
    match o {
        Ok(o) if o.status.success() => Some(out.display().to_string()),
        Ok(o) => {
            deps::missing(
                &format!("{compiler} building c_deep_parser.c ({})", String::from_utf8_lossy(&o.stderr).trim()),
                deps::AFL_HOW,
            );
            None
        }
        Err(e) => {
            deps::missing(&format!("{compiler} ({e})"), deps::AFL_HOW);
            None
        }
    }
}

fn afl_host(dir: &Path) -> Option<Vec<String>> {
    deps::afl_cc()?;
    Some(vec![build("afl-cc", dir)?, "{port}".into()])
}

fn python_host() -> Option<Vec<String>> {
    let py = deps::python_afl()?;
    Some(vec![py, hosts().join("py_deep_parser.py").display().to_string()])
}

fn options(command: Vec<String>, coverage: CoverageUse, seed: u64, runs: u64, jobs: usize) -> FuzzOptions {
    FuzzOptions {
        run: HostRun {
            command,
            transport: Transport::Pty,
            profile: gcl_model::Profile::builtin("seed").unwrap(),
            time: TimeMode::Fast,
            pace: Pace::Unpaced,
            hand_seed: 0,
            // Above the hosts' 1 s deadline: waiting it out is never a hang.
            timeout_hang: Duration::from_secs(3),
            budget: Duration::from_secs(30),
            link: None,
            coverage,
            env: Vec::new(),
        },
        seed,
        runs: Some(runs),
        duration: None,
        ok_exit_codes: vec![0],
        jobs,
        weights: Weights::parse(OPS).unwrap(),
        max_planned: 3,
        minimize: false,
        guided: true,
        calibrate: false,
        shard: None,
    }
}

fn campaign(opts: &FuzzOptions) -> Campaign {
    fuzz(opts, &AtomicBool::new(false), &|_| {}).expect("campaign")
}

/// SysV segments this process made that still exist (`/proc/sysvipc/shm`'s `cpid`, the fifth
/// column).
/// Runs a `gcl fuzz host` campaign to its end: it exits 0 or 1 (findings), and no
/// shared-memory segment it made outlives it (counted by its pid: tests beside this one in the
/// process make maps of their own).
fn run_campaign(cmd: &mut Command) -> std::process::Output {
    let child = cmd.stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    let pid = child.id();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(segments_made_by(pid), 0, "no shared-memory segment outlives the campaign");
    out
}

fn segments_made_by(pid: u32) -> usize {
    let pid = pid.to_string();
    std::fs::read_to_string("/proc/sysvipc/shm")
        .unwrap_or_default()
        .lines()
        .skip(1)
        .filter(|l| l.split_whitespace().nth(4) == Some(pid.as_str()))
        .count()
}

/// The deep bug's crash, if the campaign found it.
fn deep_crash(c: &Campaign) -> Option<u64> {
    c.findings.iter().find(|f| f.verdict.kind == FindingKind::Crash).map(|f| f.run)
}

/// Each schedule that added coverage, run again: the union of their edges is the campaign's.
fn replayed_edges(command: &[String], cov: &CoverageAccount) -> usize {
    let run = options(command.to_vec(), CoverageUse::Measure, 0, 1, 1).run;
    let slots = Slots::new(1);
    let mut union = BTreeSet::new();
    for a in &cov.added_by {
        let r = slots.run(&run, &a.planned, &AtomicBool::new(false)).expect("replay");
        union.extend(r.edges.expect("a map was read"));
    }
    union.len()
}

/// An afl-cc host writes its edges to the map of each run: they rise over the campaign (a
/// point each time they rose), its edge count is read from the binary, each schedule that
/// added edges is named, and those schedules run again reach the same edges.
#[test]
fn an_afl_cc_host_reports_its_edges_rising_and_the_schedules_that_added_them_replay_to_them() {
    let dir = tempfile::tempdir().unwrap();
    let Some(host) = afl_host(dir.path()) else { return };
    let c = campaign(&options(host.clone(), CoverageUse::Guide, 1, 40, 2));
    let cov = c.coverage.clone().expect("a coverage account");
    assert!(cov.instrumented && cov.note.is_none(), "{cov:?}");
    let host_edges = cov.host_edges.expect("afl-cc binaries say their map size");
    assert!(cov.edges > 0 && cov.edges <= host_edges, "{cov:?}");
    let first = cov.over_time.first().unwrap();
    let last = cov.over_time.last().unwrap();
    assert_eq!(first.runs, 1, "run 0 reaches the host's code");
    assert!(last.edges > first.edges, "edges rise past run 0's: {:?}", cov.over_time);
    assert_eq!(last.runs, c.runs, "the last point is the campaign's end");
    assert!(cov.added_by.len() >= 2 && cov.added_by[0].schedule == "no misbehaviour", "{:?}", cov.added_by);
    assert!(cov.kept >= 1, "{cov:?}");
    assert_eq!(replayed_edges(&host, &cov), cov.edges as usize, "the schedules that added edges reach them again");
}

/// The instrumentation `cargo afl build` gives a crate (cargo-afl 0.18's flags, less
/// `-C target-cpu=native`), for `rustc` by hand: sanitizer coverage's pc-guard edges, linked
/// with the runtime `afl-cc` links (Debian's `afl++`), which maps `__AFL_SHM_ID` at start.
const CARGO_AFL_FLAGS: &[&str] = &[
    "-C",
    "debug-assertions",
    "-C",
    "overflow_checks",
    "-C",
    "codegen-units=1",
    "-C",
    "opt-level=3",
    "-C",
    "passes=sancov-module",
    "-C",
    "llvm-args=-sanitizer-coverage-level=3",
    "-C",
    "llvm-args=-sanitizer-coverage-trace-pc-guard",
    "-C",
    "llvm-args=-sanitizer-coverage-prune-blocks=0",
    "-C",
    "llvm-args=-sanitizer-coverage-trace-compares",
    "--cfg",
    "fuzzing",
];

/// AFL++'s runtime as Debian's `afl++` installs it.
const AFL_RUNTIME: &str = "/usr/lib/afl/afl-compiler-rt.o";

/// `hosts/rust_host` (a crate outside the workspace) built into `dir`: by hand with `rustc`
/// and [`CARGO_AFL_FLAGS`] (what CI can build: it installs `afl++`, not cargo-afl, whose install
/// compiles AFL++ for minutes), and with `cargo afl build` where cargo-afl is installed. Each
/// binary with the way it was built.
fn rust_hosts(dir: &Path) -> Vec<(&'static str, String)> {
    let mut built = Vec::new();
    let src = hosts().join("rust_host");
    if deps::afl_cc().is_some() {
        let out = dir.join("rust_host_by_hand");
        let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
        let o = Command::new(rustc)
            .args(["--edition", "2021", "-g"])
            .args(CARGO_AFL_FLAGS)
            .arg(format!("-Clink-arg={AFL_RUNTIME}"))
            .arg("-o")
            .arg(&out)
            .arg(src.join("src/main.rs"))
            .output();
        match o {
            Ok(o) if o.status.success() => built.push(("rustc by hand", out.display().to_string())),
            Ok(o) => panic!("rustc with cargo-afl's flags: {}", String::from_utf8_lossy(&o.stderr)),
            Err(e) => deps::missing(&format!("rustc ({e})"), "rustup"),
        }
    }
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let has_cargo_afl = Command::new(&cargo).args(["afl", "--version"]).output().is_ok_and(|o| o.status.success());
    if has_cargo_afl {
        // `--locked`: the crate's Cargo.lock is committed, so the build writes nothing beside
        // the sources; its target directory is the test's.
        let o = Command::new(&cargo)
            .args(["afl", "build", "--locked", "--quiet", "--manifest-path"])
            .arg(src.join("Cargo.toml"))
            .arg("--target-dir")
            .arg(dir.join("cargo-afl-target"))
            .output()
            .unwrap();
        assert!(o.status.success(), "cargo afl build: {}", String::from_utf8_lossy(&o.stderr));
        built.push(("cargo afl build", dir.join("cargo-afl-target/debug/rust_host").display().to_string()));
    } else if !deps::under_ci() {
        // Not a failure under CI, which does not install cargo-afl: the build by hand above
        // is the same instrumentation and runtime.
        deps::missing("cargo-afl (the build by hand ran)", "cargo install cargo-afl --locked");
    }
    built
}

/// A Rust host built as `cargo afl build` builds it writes its edges to the map: the campaign
/// reads the host's edge count from the binary, and its edges rise as the misbehaviours
/// change what its answers hold (hosts/rust_host/src/main.rs sorts them), with schedules kept
/// for them; the host is correct: no finding.
#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn a_rust_host_built_as_cargo_afl_builds_it_reports_its_edges_rising() {
    let dir = tempfile::tempdir().unwrap();
    for (how, exe) in rust_hosts(dir.path()) {
        let c = campaign(&options(vec![exe, "{port}".into()], CoverageUse::Guide, 1, 40, 2));
        let cov = c.coverage.clone().expect("a coverage account");
        assert!(cov.instrumented && cov.note.is_none(), "{how}: {cov:?}");
        let host_edges = cov.host_edges.expect("the runtime says the map size");
        assert!(cov.edges > 0 && cov.edges <= host_edges, "{how}: {cov:?}");
        let (first, last) = (cov.over_time.first().unwrap(), cov.over_time.last().unwrap());
        assert_eq!(first.runs, 1, "{how}: run 0 reaches the host's code");
        assert!(last.edges > first.edges, "{how}: edges rise past run 0's: {:?}", cov.over_time);
        assert!(cov.kept >= 1, "{how}: {cov:?}");
        assert!(c.findings.is_empty(), "{how}: {:?}", c.findings);
        eprintln!("{how}: {} edges of {host_edges}, {} kept for edges", cov.edges, cov.kept);
    }
}

/// A host built without instrumentation runs as it did before coverage: the same runs, paths,
/// kept schedules and findings as with coverage off, and a note.
#[test]
fn an_uninstrumented_host_runs_as_before_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let Some(plain) = build("cc", dir.path()) else { return };
    let host = vec![plain, "{port}".into()];
    let on = campaign(&options(host.clone(), CoverageUse::Guide, 3, 30, 1));
    let off = campaign(&options(host, CoverageUse::Off, 3, 30, 1));
    assert_eq!(on.coverage.as_ref().and_then(|c| c.note.as_deref()), Some(NOT_INSTRUMENTED));
    assert!(off.coverage.is_none());
    assert_eq!((on.runs, on.paths, on.corpus), (off.runs, off.paths, off.corpus));
    assert_eq!(on.fired_at, off.fired_at, "the same misbehaviours at the same states");
    let sigs = |c: &Campaign| c.findings.iter().map(|f| (f.run, f.verdict.signature.clone())).collect::<Vec<_>>();
    assert_eq!(sigs(&on), sigs(&off));
}

/// The deep bug, four misbehaviours in order, is found by the campaign guided by the host's
/// coverage, and not in the same runs by the campaign that sees only the wire (the same seed:
/// `measure` makes the runs of `off`, reading the edges they reach).
#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn the_deep_bug_of_an_afl_cc_host_is_found_with_coverage_and_not_by_wire_paths_alone() {
    let dir = tempfile::tempdir().unwrap();
    let Some(host) = afl_host(dir.path()) else { return };
    let guided = campaign(&options(host.clone(), CoverageUse::Guide, 2, 400, 2));
    let wire = campaign(&options(host, CoverageUse::Measure, 2, 400, 2));
    let found = deep_crash(&guided).expect("coverage finds the deep bug");
    assert_eq!(deep_crash(&wire), None, "wire paths alone do not, in the same 400 runs");
    let (g, w) = (guided.coverage.unwrap(), wire.coverage.unwrap());
    assert!(g.edges > w.edges, "more edges with coverage: {} against {}", g.edges, w.edges);
    eprintln!("deep bug at run {found}; edges {} with coverage, {} wire paths only", g.edges, w.edges);
}

/// A Python host with python-afl writes the lines it runs to the same map: edges rise, the
/// deep bug is found with coverage, and the schedules that added edges replay to them, but for
/// a few: python-afl maps every module's lines, and which lines of pyserial's read a run takes
/// depends on how the bytes arrived (a run of the campaign reached 380 edges, their replays
/// 378).
#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn a_python_afl_host_reports_its_edges_and_its_deep_bug_is_found_with_coverage() {
    let Some(host) = python_host() else { return };
    let c = campaign(&options(host.clone(), CoverageUse::Guide, 2, 400, 2));
    let cov = c.coverage.clone().unwrap();
    assert!(cov.instrumented && cov.host_edges.is_none(), "python-afl's map does not say its size: {cov:?}");
    assert!(cov.over_time.last().unwrap().edges > cov.over_time[0].edges, "{:?}", cov.over_time);
    let crash = c.findings.iter().find(|f| f.verdict.kind == FindingKind::Crash).expect("the deep bug");
    assert!(crash.verdict.signature.contains("retry_slot"), "{}", crash.verdict.signature);
    let again = replayed_edges(&host, &cov) as u64;
    assert!(again * 100 >= cov.edges * 97, "{again} edges replayed of {}", cov.edges);
}

/// What a user sees of an afl-cc host's coverage: the console's line (edges of the host's
/// edges, schedules kept for them), the report page's plots (edges over time beside runs over
/// time) and table of the runs that added edges, and `fuzz.json`'s account. `--no-coverage`
/// reads no map: none of them.
#[test]
fn the_console_the_report_page_and_fuzz_json_show_the_edges_reached() {
    let dir = tempfile::tempdir().unwrap();
    let Some(host) = afl_host(dir.path()) else { return };
    let gcl = |report: &str, extra: &[&str]| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_gcl"));
        cmd.args(["fuzz", "host", "--profile", "seed", "--runs", "20", "--jobs", "2", "--timeout-hang", "3s"])
            .args(["--ops", OPS, "--no-minimize"])
            .args(extra)
            .arg("--report")
            .arg(dir.path().join(report))
            .arg("--out")
            .arg(dir.path().join(format!("{report}-bundles")))
            .arg("--")
            .args(&host);
        let out = run_campaign(&mut cmd);
        let html = std::fs::read_to_string(dir.path().join(report).join("report.html")).unwrap();
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join(report).join("fuzz.json")).unwrap()).unwrap();
        (String::from_utf8_lossy(&out.stderr).to_string(), html, json)
    };
    let (console, html, json) = gcl("on", &[]);
    let line = console.lines().find(|l| l.starts_with("coverage: ")).unwrap_or_else(|| panic!("{console}"));
    assert!(
        line.contains(" edges of ") && line.contains("%) reached") && line.contains("kept for new edges"),
        "{line}"
    );
    let cov = &json["coverage"];
    assert_eq!(cov["instrumented"], true, "{json:#}");
    assert!(cov["over_time"].as_array().unwrap().len() >= 2, "{cov:#}");
    assert_eq!(cov["added_by"][0]["schedule"], "no misbehaviour");
    for needle in ["Edges of the host", "Runs over time", "fuzz-host-edges", "fuzz-host-runs", "code coverage"] {
        assert!(html.contains(needle), "the page has {needle}");
    }
    let (console, html, json) = gcl("off", &["--no-coverage"]);
    assert!(!console.contains("coverage: "), "{console}");
    assert!(json.get("coverage").is_none(), "{json:#}");
    assert!(!html.contains("fuzz-host-edges"));
}

/// `--corpus DIR` keeps the schedules a campaign kept: a second campaign runs them right after
/// its systematic pass, so in no more runs than run 0, the pass and those schedules it reaches
/// every edge the first campaign reached, and finds the deep bug the first found at run 105
/// (seed 2: a campaign's first runs are the same whatever its length, and without the corpus
/// the first 30 or so find nothing).
#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn a_corpus_carries_the_edges_and_the_deep_bug_to_the_next_campaign() {
    let dir = tempfile::tempdir().unwrap();
    let Some(host) = afl_host(dir.path()) else { return };
    let corpus = dir.path().join("corpus");
    let gcl = |report: &str, runs: u64| -> serde_json::Value {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_gcl"));
        cmd.args(["fuzz", "host", "--seed", "2", "--jobs", "2", "--timeout-hang", "3s", "--no-minimize"])
            .args(["--ops", OPS, "--runs", &runs.to_string(), "--corpus"])
            .arg(&corpus)
            .arg("--report")
            .arg(dir.path().join(report))
            .arg("--out")
            .arg(dir.path().join(format!("{report}-bundles")))
            .arg("--")
            .args(&host);
        run_campaign(&mut cmd);
        serde_json::from_slice(&std::fs::read(dir.path().join(report).join("fuzz.json")).unwrap()).unwrap()
    };
    let crash = |j: &serde_json::Value| {
        j["findings"].as_array().unwrap().iter().find(|f| f["verdict"]["kind"] == "crash").map(|f| f["run"].as_u64())
    };
    let first = gcl("first", 200);
    assert!(crash(&first).is_some(), "the first campaign finds the deep bug: {first:#}");
    let kept = std::fs::read_dir(&corpus).unwrap().count() as u64;
    assert_eq!(kept, first["corpus"].as_u64().unwrap(), "every kept schedule is in the corpus");
    let pass = first["pass_runs"].as_u64().unwrap();
    let second = gcl("second", 1 + pass + kept);
    assert_eq!(second["seeds"].as_u64(), Some(kept));
    let edges = |j: &serde_json::Value| j["coverage"]["edges"].as_u64().unwrap();
    assert!(edges(&second) >= edges(&first), "{} edges, then {}", edges(&first), edges(&second));
    assert!(crash(&second).is_some(), "the corpus's crashing schedule runs again: {second:#}");
}
