//! `gcl fuzz host` guided by the host's own code coverage (issue 42): hosts built with AFL++'s
//! `afl-cc`, or Python hosts with python-afl, write the edges they reach to the map `gcl` gives
//! each run (`__AFL_SHM_ID`); a schedule whose run reached a new edge is kept and mutated.
//!
//! The hosts are `hosts/c_deep_parser.c` and `hosts/py_deep_parser.py`: the same commands
//! whatever they read, and a bug behind four misbehaviours in order (err-bits, garbage,
//! overlong-line, then err-bits of a large code). They need `afl-cc` (`apt-get install afl++`)
//! and python-afl (installed into `target/pyvenv` on first use), or the wheel's `gcl.afl_cov`
//! (from `python/`); without them the tests are skipped with a line, and fail under CI
//! (`CI=true`). Also here: minimization keeping a finding's edges, and shards sharing a corpus.

use crate::deps;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use gcl_harness::fuzz::host::coverage::{CoverageAccount, CoverageUse, NOT_INSTRUMENTED};
use gcl_harness::fuzz::host::{
    Campaign, Event, FindingKind, FuzzOptions, HostRun, Slots, Transport, Weights, fuzz, fuzz_seeded, judge,
};
use gcl_harness::sim::misbehave::{Operator, Planned, Schedule};
use gcl_harness::sim::{Pace, TimeMode};

fn hosts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hosts")
}

/// The misbehaviours the deep hosts' bug needs, and one more: every answer still ends in a
/// prompt (but where garbage lands in it), so no run waits out the host's 1 s deadline often.
const OPS: &str = "err-bits,garbage,overlong-line,crlf";

/// `hosts/c_deep_parser.c` built into `dir` with `compiler` (`afl-cc` or `cc`).
fn build(compiler: &str, dir: &Path) -> Option<String> {
    build_with(compiler, dir, &[])
}

/// `hosts/c_deep_parser.c` built into `dir` with `compiler` and `flags` (`-DSHALLOW_TOO`).
fn build_with(compiler: &str, dir: &Path, flags: &[&str]) -> Option<String> {
    let out = dir.join(format!("deep-{}{}", compiler.replace('-', "_"), flags.concat().replace('-', "_")));
    let o = Command::new(compiler)
        .args(["-O0", "-g"])
        .args(flags)
        .arg("-o")
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
    replayed_edges_with(command, &[], cov)
}

/// [`replayed_edges`] of a host run with `env`.
fn replayed_edges_with(command: &[String], env: &[(String, String)], cov: &CoverageAccount) -> usize {
    let mut run = options(command.to_vec(), CoverageUse::Measure, 0, 1, 1).run;
    run.env = env.to_vec();
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

/// The deep hosts' bug, answer by answer (answer 1 is the prompt after the host's ^C, then one
/// per `1FGET P`): `ERR 32768`, a vertical tab, an 81-byte line, `ERR 2147483648`.
fn deep_schedule() -> Schedule {
    let at = |answer: u32, op: Operator, arg: u32| Planned { answer, op, arg };
    Schedule {
        planned: vec![
            at(2, Operator::ErrBits, 0),
            at(3, Operator::Garbage, 0),
            at(4, Operator::OverlongLine, 0),
            at(5, Operator::ErrBits, 2),
        ],
    }
}

/// Minimization keeps a finding's coverage: the edges its run reached first in the campaign.
/// The deep host built with `-DSHALLOW_TOO` crashes with the same signal by a shallower way too
/// (err-bits then overlong-line, the deep schedule without its garbage), so minimizing by the
/// signature alone would trade the deep bug for that one (it did: `err-bits@2
/// overlong-line@4`). Given the deep schedule as a corpus, the campaign finds the deep crash
/// right after its systematic pass (one misbehaviour per run: no crash), and its minimized
/// schedule still takes the host to `retry_slot`: every step is needed for that, so it stays
/// whole.
#[test]
fn minimization_keeps_the_edges_a_finding_reached_first_not_a_shallower_crash_of_the_same_signal() {
    let dir = tempfile::tempdir().unwrap();
    if deps::afl_cc().is_none() {
        return;
    }
    let Some(bin) = build_with("afl-cc", dir.path(), &["-DSHALLOW_TOO"]) else { return };
    let host = vec![bin, "{port}".to_string()];
    let mut opts = options(host, CoverageUse::Guide, 1, 300, 1);
    opts.minimize = true;
    // The shallower schedule crashes with the same signature (or the test could not fail).
    let shallow = Schedule { planned: vec![deep_schedule().planned[0], deep_schedule().planned[2]] };
    let r = Slots::new(1).run(&opts.run, &shallow, &AtomicBool::new(false)).expect("a run");
    let shallow_sig: Vec<String> = judge(&r, &[0]).into_iter().map(|v| v.signature).collect();
    assert!(shallow_sig.iter().any(|s| s == "crash: SIGSEGV"), "{shallow_sig:?}");
    let stop = AtomicBool::new(false);
    let on_event = |e: Event| {
        if let Event::Found(f) = e
            && f.verdict.kind == FindingKind::Crash
        {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    };
    let c = fuzz_seeded(&opts, vec![deep_schedule()], &stop, &on_event).expect("campaign");
    let crash = c.findings.iter().find(|f| f.verdict.kind == FindingKind::Crash).expect("the deep crash");
    assert_eq!(crash.original, deep_schedule(), "found by the corpus's schedule, after the pass");
    assert!(!crash.first_edges.is_empty(), "its run reached edges no run before it had");
    assert!(c.minimize_runs >= 4, "each misbehaviour was tried without: {} runs", c.minimize_runs);
    assert_eq!(crash.schedule, deep_schedule(), "minimized, it still reaches the deep bug's code");
}

/// The schedules of a corpus folder (not its subfolders), each with its misbehaviours and the
/// edges its file holds.
fn corpus_files(dir: &Path) -> Vec<(String, usize, Vec<u64>)> {
    let Ok(rd) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut out: Vec<(String, usize, Vec<u64>)> = rd
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .map(|p| {
            let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
            let edges =
                j["edges"].as_array().map(|a| a.iter().map(|e| e.as_u64().unwrap()).collect()).unwrap_or_default();
            let planned = j["planned"].as_array().unwrap().len();
            (p.file_name().unwrap().to_string_lossy().to_string(), planned, edges)
        })
        .collect();
    out.sort();
    out
}

/// Shards share a corpus: two shard processes of one campaign, started together on one folder,
/// each write the schedules that reached edges new to it (with those edges) to
/// `DIR/incoming`; `gcl fuzz merge-corpus DIR` folds them into the folder, keeping only
/// schedules that add edges and every edge they reached; and the next campaign's shards each
/// run their share of that base after their pass (its provenance names the base, so shards of
/// two bases do not merge).
#[test]
fn shards_write_a_shared_corpus_that_a_merge_keeps_to_the_schedules_adding_edges() {
    let dir = tempfile::tempdir().unwrap();
    let Some(host) = afl_host(dir.path()) else { return };
    let corpus = dir.path().join("corpus");
    let shard = |round: &str, k: u32| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_gcl"));
        cmd.args(["fuzz", "host", "--profile", "seed", "--seed", "1", "--runs", "60", "--jobs", "1"])
            .args(["--timeout-hang", "3s", "--no-minimize", "--ops", OPS, "--shard", &format!("{k}/2"), "--corpus"])
            .arg(&corpus)
            .arg("--report")
            .arg(dir.path().join(format!("{round}-{k}")))
            .arg("--out")
            .arg(dir.path().join(format!("{round}-{k}-bundles")))
            .arg("--")
            .args(&host)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        cmd.spawn().unwrap()
    };
    let fuzz_json = |name: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(dir.path().join(name).join("fuzz.json")).unwrap()).unwrap()
    };
    // Two processes at once, on one folder.
    let (a, b) = (shard("first", 1), shard("first", 2));
    for child in [a, b] {
        let out = child.wait_with_output().unwrap();
        assert!(out.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let incoming = corpus_files(&corpus.join("incoming"));
    assert!(corpus_files(&corpus).is_empty(), "no shard writes the base");
    for k in 1..=2 {
        let j = fuzz_json(&format!("first-{k}"));
        assert!(j["coverage"]["kept"].as_u64().unwrap() >= 1, "shard {k} kept schedules for new edges: {j:#}");
    }
    assert!(incoming.len() >= 2 && incoming.iter().all(|(_, _, e)| !e.is_empty()), "{incoming:?}");
    let all_edges: BTreeSet<u64> = incoming.iter().flat_map(|(_, _, e)| e.iter().copied()).collect();
    let out = Command::new(env!("CARGO_BIN_EXE_gcl")).args(["fuzz", "merge-corpus"]).arg(&corpus).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let base = corpus_files(&corpus);
    assert!(!corpus.join("incoming").exists(), "the incoming schedules were folded in");
    assert!(!base.is_empty() && base.len() < incoming.len(), "{} of {} kept", base.len(), incoming.len());
    let kept_edges: BTreeSet<u64> = base.iter().flat_map(|(_, _, e)| e.iter().copied()).collect();
    assert_eq!(kept_edges, all_edges, "every edge the shards reached is reached by a kept schedule");
    // Each kept schedule is, for an edge it reached, one of the smallest that reached it.
    for (name, planned, edges) in &base {
        let smallest_for = |e: &u64| !incoming.iter().any(|(_, p, es)| p < planned && es.contains(e));
        assert!(edges.iter().any(smallest_for), "{name} ({planned} misbehaviours) is the smallest for no edge");
    }
    // The next campaign's shards run the base after their pass, and say which base they ran.
    let (a, b) = (shard("second", 1), shard("second", 2));
    for child in [a, b] {
        let out = child.wait_with_output().unwrap();
        assert!(out.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&out.stderr));
    }
    for k in 1..=2 {
        let j = fuzz_json(&format!("second-{k}"));
        assert_eq!(j["seeds"].as_u64(), Some(base.len() as u64), "{j:#}");
        let named = j["provenance"]["options"]["corpus"].as_str().unwrap_or_default().to_string();
        assert!(named.starts_with(&format!("{} schedule(s), ", base.len())), "{:#}", j["provenance"]);
    }
}

/// A Python host without python-afl: run through `python -m gcl.afl_cov` (the wheel's module,
/// here from `python/` on `PYTHONPATH`), it writes the lines it runs to the map of each run.
/// `import afl` in the host is the module's stand-in, so python-afl is never imported, whether
/// or not the interpreter has it. Edges rise over the campaign, and the schedules that added
/// edges replay to nearly the same edges (pyserial's read loop takes lines that depend on how
/// the bytes arrived, as under python-afl).
#[test]
fn a_python_host_without_python_afl_records_its_lines_through_gcl_afl_cov() {
    let Some(py) = deps::python_with(&["serial"]) else { return };
    let python_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../python");
    let host = vec![py, "-m".into(), "gcl.afl_cov".into(), hosts().join("py_deep_parser.py").display().to_string()];
    let env = vec![("PYTHONPATH".to_string(), python_dir.display().to_string())];
    let mut opts = options(host.clone(), CoverageUse::Guide, 2, 40, 2);
    opts.run.env = env.clone();
    let c = campaign(&opts);
    let cov = c.coverage.clone().expect("a coverage account");
    assert!(cov.instrumented && cov.note.is_none(), "{cov:?}");
    let first = cov.over_time.first().unwrap();
    assert_eq!(first.runs, 1, "run 0 reaches the host's lines");
    assert!(cov.over_time.last().unwrap().edges > first.edges, "edges rise past run 0's: {:?}", cov.over_time);
    assert!(cov.kept >= 1, "{cov:?}");
    let again = replayed_edges_with(&host, &env, &cov) as u64;
    assert!(again * 100 >= cov.edges * 97, "{again} edges replayed of {}", cov.edges);
    eprintln!(
        "{} edges over {} runs ({:?}); the replays of the {} schedules that added edges: {again}",
        cov.edges,
        c.runs,
        cov.over_time.iter().map(|p| (p.runs, p.edges)).collect::<Vec<_>>(),
        cov.added_by.len()
    );
}
