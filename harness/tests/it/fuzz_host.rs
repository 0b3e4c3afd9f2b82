//! `gcl fuzz host` and `gcl check-host` against deliberately buggy host programs
//! (`host_mutants/`, listed in its README): the fuzzer finds each within a bounded number of
//! runs and names the right kind of finding; `check-host` flags each protocol violation; the
//! correct hosts (our own client's example program and a pyserial script) have no finding.
//!
//! Python mutants need a Python with pyserial (found as every test finds Python: `deps`), C
//! mutants a C compiler with AddressSanitizer; each group is skipped when its tools are
//! missing, with a line in `cargo test`'s output, and fails under CI (`CI=true`). The time to the
//! first finding of each mutant is printed (`cargo test --test it -- --nocapture fuzz_host::`).

use crate::deps;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use gcl_harness::fuzz::host::{
    Event, FindingKind, FuzzOptions, HostClause, HostEnd, HostRun, Transport, Weights, fuzz, run_once,
};
use gcl_harness::host_check::{CheckHostOptions, check_host};
use gcl_harness::report::Verdict;
use gcl_harness::sim::misbehave::{Operator, Planned, Schedule};
use gcl_harness::sim::{Pace, TimeMode};

fn mutants() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/host_mutants")
}

fn python_ready() -> bool {
    deps::python_with(&["serial"]).is_some()
}

/// Compiles a C mutant with AddressSanitizer into `dir`; `None` (and a line) without a compiler.
fn compile_c(name: &str, dir: &Path) -> Option<PathBuf> {
    let out = dir.join(name);
    let src = mutants().join(format!("{name}.c"));
    let built = Command::new("cc")
        .args(["-fsanitize=address", "-fno-omit-frame-pointer", "-g", "-O0", "-o"])
        .arg(&out)
        .arg(&src)
        .output();
    match built {
        Ok(o) if o.status.success() => Some(out),
        Ok(o) => {
            deps::missing(
                &format!("cc -fsanitize=address ({})", String::from_utf8_lossy(&o.stderr).trim()),
                "apt-get install gcc",
            );
            None
        }
        Err(e) => {
            deps::missing(&format!("a C compiler ({e})"), "apt-get install gcc");
            None
        }
    }
}

fn host_run(command: Vec<String>) -> HostRun {
    HostRun {
        command,
        transport: Transport::Pty,
        profile: gcl_model::Profile::builtin("seed").unwrap(),
        time: TimeMode::Fast,
        pace: Pace::Unpaced,
        hand_seed: 0,
        // Above every timeout the hosts use (at most 2 s), so waiting out its own timeout is
        // never a hang.
        timeout_hang: Duration::from_millis(2500),
        // Also how long a hang's confirmation waits.
        budget: Duration::from_secs(12),
        link: None,
        coverage: Default::default(),
        env: Vec::new(),
    }
}

fn python(file: &str) -> Vec<String> {
    vec![deps::python(), mutants().join(file).display().to_string()]
}

/// A campaign of `runs` runs against `command` with the test's usual options: exit codes 0
/// and 1 accepted, up to 3 misbehaviours a run, guided, no minimization, no calibration.
fn options(command: Vec<String>, seed: u64, runs: u64, jobs: usize) -> FuzzOptions {
    FuzzOptions {
        run: host_run(command),
        seed,
        runs: Some(runs),
        duration: None,
        ok_exit_codes: vec![0, 1],
        jobs,
        weights: Weights::default(),
        max_planned: 3,
        minimize: false,
        guided: true,
        calibrate: false,
        shard: None,
    }
}

/// Fuzzes until a finding of `kind` whose signature holds `needle` (or `runs` runs); returns
/// its signature and the time to it.
fn first_finding(
    command: Vec<String>,
    ops: &str,
    kind: FindingKind,
    needle: &str,
    runs: u64,
) -> Option<(String, Duration)> {
    let opts = FuzzOptions { weights: Weights::parse(ops).unwrap(), ..options(command, 7, runs, 2) };
    first_finding_of(&opts, kind, needle)
}

/// [`first_finding`] of a campaign with these options.
fn first_finding_of(opts: &FuzzOptions, kind: FindingKind, needle: &str) -> Option<(String, Duration)> {
    let stop = AtomicBool::new(false);
    let found = Mutex::new(None);
    let started = Instant::now();
    fuzz(opts, &stop, &|e| {
        if let Event::Found(f) = e
            && f.verdict.kind == kind
            && f.verdict.signature.contains(needle)
        {
            found.lock().unwrap().get_or_insert((f.verdict.signature.clone(), started.elapsed()));
            stop.store(true, Ordering::Relaxed);
        }
    })
    .unwrap();
    found.into_inner().unwrap()
}

/// (file, operators it is fuzzed with, the kind of finding it must give, what its signature names).
const PYTHON_MUTANTS: [(&str, &str, FindingKind, &str); 9] = [
    // A hang is named by the host's stack (faulthandler): blocked in pyserial, by the call.
    (
        "py_prompt_forever.py",
        "no-prompt,truncate,bad-prompt,silence",
        FindingKind::Hang,
        "hang in py_prompt_forever.py, blocked in serialposix.py:read",
    ),
    ("py_err_table.py", "err-bits,garbage", FindingKind::Crash, "python KeyError"),
    ("py_sends_lf.py", "truncate", FindingKind::Violation, "line-ending"),
    ("py_pipelines.py", "truncate", FindingKind::Violation, "waits-for-answer"),
    ("py_parse_values.py", "crlf,garbage,restart", FindingKind::Crash, "python ValueError"),
    ("py_rt_length.py", "rt-block-length,rt-err", FindingKind::Crash, "python IndexError"),
    ("py_banner_version.py", "banner-variant,restart", FindingKind::Crash, "python ValueError"),
    ("py_loop_no_abort.py", "truncate", FindingKind::Violation, "leaves-cleanly"),
    ("py_rt_short_block.py", "truncate", FindingKind::Violation, "realtime-blocks"),
];

/// A default campaign, no misbehaviour steered (`gcl fuzz host -- HOST`: every misbehaviour at
/// its default weight, one job, seed 0), finds the bugs that need one misbehaviour at one
/// kind of answer, or the timing of a real line, early: its systematic pass puts each
/// misbehaviour at each kind of answer before any random draw, and makes one run at the
/// hand's line rate. py_banner_version needs a banner variant after RESET (the one answer with
/// a banner); py_echo_is_ack sends on once the echo has come, which only a line that takes
/// time to carry the rest of the answer shows. 60 random runs found neither.
#[test]
fn a_default_campaign_finds_what_needs_one_misbehaviour_at_one_kind_of_answer() {
    if !python_ready() {
        return;
    }
    let default = |file: &str, runs: u64| options(python(file), 0, runs, 1);
    // Run 1 is the line-rate run.
    let (sig, _) = first_finding_of(&default("py_echo_is_ack.py", 2), FindingKind::Violation, "waits-for-answer")
        .expect("py_echo_is_ack: no waits-for-answer violation in the first 2 runs of a default campaign");
    println!("py_echo_is_ack.py: {sig}");
    // banner-variant is the tenth misbehaviour of the first round here (the nine of weight 3
    // that apply to a supervisory host go first); after the line-rate run, run 11.
    let (sig, _) = first_finding_of(&default("py_banner_version.py", 12), FindingKind::Crash, "python ValueError")
        .expect("py_banner_version: no ValueError in the first 12 runs of a default campaign");
    println!("py_banner_version.py: {sig}");
}

#[test]
fn python_mutants_are_found_with_the_right_kind() {
    if !python_ready() {
        return;
    }
    for (file, ops, kind, needle) in PYTHON_MUTANTS {
        let (sig, t) = first_finding(python(file), ops, kind, needle, 60)
            .unwrap_or_else(|| panic!("{file}: no {} finding naming `{needle}` in 60 runs", kind.name()));
        println!("{file}: {} after {:.2} s: {sig}", kind.name(), t.as_secs_f64());
    }
}

#[test]
fn c_mutants_are_found_with_the_right_kind() {
    let dir = tempfile::tempdir().unwrap();
    for (name, ops, kind, needle) in [
        ("c_line_buffer", "overlong-line,truncate", FindingKind::Crash, "asan stack-buffer-overflow in read_line"),
        ("c_err_bits", "err-bits", FindingKind::Crash, "asan global-buffer-overflow in main"),
        ("c_status_exit", "err-bits", FindingKind::ExitCode, "exit-code: not an accepted code, in supervisory mode"),
    ] {
        let Some(exe) = compile_c(name, dir.path()) else { return };
        let (sig, t) = first_finding(vec![exe.display().to_string(), "{port}".into()], ops, kind, needle, 60)
            .unwrap_or_else(|| panic!("{name}: no {} finding naming `{needle}` in 60 runs", kind.name()));
        println!("{name}: {} after {:.2} s: {sig}", kind.name(), t.as_secs_f64());
    }
}

#[test]
fn a_rust_mutant_panic_is_found() {
    let dir = tempfile::tempdir().unwrap();
    let exe = dir.path().join("rs_unwrap_values");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let built = Command::new(rustc)
        .args(["--edition", "2021", "-O", "-o"])
        .arg(&exe)
        .arg(mutants().join("rs_unwrap_values.rs"))
        .output();
    if !built.is_ok_and(|o| o.status.success()) {
        deps::missing("a rustc that builds the Rust mutant", "set RUSTC");
        return;
    }
    let (sig, t) = first_finding(
        vec![exe.display().to_string()],
        "garbage,truncate,err-bits",
        FindingKind::Crash,
        "crash: panic at ",
        60,
    )
    .expect("rs_unwrap_values: no panic in 60 runs");
    println!("rs_unwrap_values: crash after {:.2} s: {sig}", t.as_secs_f64());
    assert!(sig.contains("rs_unwrap_values.rs:"), "{sig}");
}

#[test]
fn check_host_flags_each_protocol_violation_and_passes_correct_hosts() {
    if !python_ready() {
        return;
    }
    let grade = |file: &str| {
        let opts = CheckHostOptions { run: host_run(python(file)), ok_exit_codes: vec![0, 1], golden: None };
        let report = check_host(&opts).unwrap().report;
        report.cases.iter().filter(|c| c.verdict.fails_run()).map(|c| c.id.clone()).collect::<Vec<_>>()
    };
    let id = |c: HostClause| format!("host-{}", c.id());
    assert_eq!(grade("py_sends_lf.py"), vec![id(HostClause::LineEnding)]);
    assert_eq!(grade("py_pipelines.py"), vec![id(HostClause::WaitsForAnswer)]);
    assert_eq!(grade("py_loop_no_abort.py"), vec![id(HostClause::LeavesCleanly)]);
    // Misaligned blocks also send bytes before their feedback: the size is the root.
    assert!(grade("py_rt_short_block.py").contains(&id(HostClause::RealtimeBlocks)));
    // A host that never enters RealTime has not shown it sends blocks well: "not exercised".
    let opts = CheckHostOptions { run: host_run(python("py_sends_lf.py")), ok_exit_codes: vec![0, 1], golden: None };
    let report = check_host(&opts).unwrap().report;
    let rt = report.cases.iter().find(|c| c.id == id(HostClause::RealtimeBlocks)).unwrap();
    assert_eq!(rt.verdict, Verdict::Skip, "{rt:?}");
    assert!(rt.message.as_deref().is_some_and(|m| m.starts_with("not exercised")), "{rt:?}");
    for correct in ["gclhost.py", "py_rt_length.py", "py_err_table.py"] {
        assert_eq!(grade(correct), Vec::<String>::new(), "{correct} talks correctly to a perfect hand");
    }
}

/// "Nothing is sent while an answer is still coming" is judged when the answer's last byte is
/// handed to the line: on a paced line, a host that sends its next command once it has the
/// echo sends it while the values and the prompt are still crossing; on an unpaced line the
/// whole answer was there already. A pipelining host is caught either way.
#[test]
fn waiting_for_the_answer_is_judged_when_its_last_byte_is_delivered() {
    if !python_ready() {
        return;
    }
    let grade = |file: &str, pace: Pace| {
        let mut run = host_run(python(file));
        run.pace = pace;
        // Exit 1 is a host that gave up on the hand with a message: no crash.
        let opts = CheckHostOptions { run, ok_exit_codes: vec![0, 1], golden: None };
        let report = check_host(&opts).unwrap().report;
        for c in report.cases.iter().filter(|c| c.verdict.fails_run()) {
            println!("{file} at {pace}: {}: {}", c.id, c.message.as_deref().unwrap_or_default());
        }
        report.cases.iter().filter(|c| c.verdict.fails_run()).map(|c| c.id.clone()).collect::<Vec<_>>()
    };
    let waits = vec![format!("host-{}", HostClause::WaitsForAnswer.id())];
    // At 1200 bit/s (the mutant's own port speed) the 25 bytes after an echo take some 200 ms,
    // far longer than the host's turn.
    assert_eq!(grade("py_echo_is_ack.py", Pace::Fixed(1200)), waits, "paced");
    assert_eq!(grade("py_echo_is_ack.py", Pace::Unpaced), Vec::<String>::new(), "unpaced");
    // The other hosts open the port at 9600 bit/s.
    assert_eq!(grade("py_pipelines.py", Pace::Fixed(9600)), waits, "a pipelining host, paced");
    assert_eq!(grade("gclhost.py", Pace::Fixed(9600)), Vec::<String>::new(), "the correct host, paced");
}

/// `silence` (a pulled cable: the port stays open, nothing more comes) is a hang for a host
/// that waits without a deadline, and nothing for one that gives up in time.
#[test]
fn silence_hangs_a_host_without_a_deadline_only() {
    if !python_ready() {
        return;
    }
    let silence = Schedule { planned: vec![Planned { answer: 3, op: Operator::Silence, arg: 0 }] };
    let mut run = host_run(python("py_prompt_forever.py"));
    run.timeout_hang = Duration::from_millis(1500);
    let r = run_once(&run, &silence).unwrap();
    assert_eq!(r.fired.len(), 1, "{:?}", r.fired);
    assert!(matches!(&r.end, HostEnd::Hung(s) if s.contains("awaiting the answer")), "{:?}", r.end);
    let r = run_once(&host_run(python("gclhost.py")), &silence).unwrap();
    assert_eq!(r.end, HostEnd::Exit(1), "gave up with a message: {}", r.stderr);
    assert!(r.stderr.contains("no b'=> '"), "{}", r.stderr);
}

/// With `--jobs` above 1 the schedules do not depend on which thread ends first: two
/// campaigns with the same seed against the same (deterministic) host keep the same
/// schedules and find the same findings at the same runs, minimized the same way.
#[test]
fn parallel_campaigns_are_reproducible_run_for_run() {
    if !python_ready() {
        return;
    }
    let campaign = || {
        let opts = FuzzOptions {
            weights: Weights::parse("crlf,garbage,err-bits,wrong-echo,extra-bytes").unwrap(),
            minimize: true,
            ..options(python("py_parse_values.py"), 11, 24, 3)
        };
        let mut c = fuzz(&opts, &AtomicBool::new(false), &|_| {}).unwrap();
        assert_eq!(c.runs, 24);
        c.elapsed_ms = 0;
        for f in &mut c.findings {
            f.found_after_ms = 0;
        }
        serde_json::to_value(&c).unwrap()
    };
    let (a, b) = (campaign(), campaign());
    assert!(!a["findings"].as_array().unwrap().is_empty(), "{a}");
    assert_eq!(a, b);
}

fn example(name: &str) -> Option<PathBuf> {
    deps::example(name)
}

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn correct_hosts_have_no_finding_in_a_longer_run() {
    let mut hosts = Vec::new();
    if let Some(p) = example("host_scenario") {
        hosts.push(vec![
            p.display().to_string(),
            "--target".into(),
            "serial:{port}".into(),
            "--profile".into(),
            "seed".into(),
        ]);
    }
    if python_ready() {
        hosts.push(python("gclhost.py"));
    }
    for command in hosts {
        let opts = options(command.clone(), 3, 80, 2);
        let c = fuzz(&opts, &AtomicBool::new(false), &|_| {}).unwrap();
        assert_eq!(c.runs, 80);
        assert!(c.fired_at.len() > 5, "misbehaviours fired: {:?}", c.fired_at);
        let found: Vec<&str> = c.findings.iter().map(|f| f.verdict.signature.as_str()).collect();
        assert!(found.is_empty(), "{command:?}: {found:?}");
    }
}

/// The report validates against `reports/report.schema.json`, like `conform`'s.
fn schema_valid(path: &Path) {
    let schema: serde_json::Value = serde_json::from_str(gcl_harness::report::SCHEMA).unwrap();
    let v = jsonschema::validator_for(&schema).unwrap();
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let errors: Vec<String> = v.iter_errors(&report).map(|e| format!("{} at {}", e, e.instance_path())).collect();
    assert!(errors.is_empty(), "{}: {errors:?}", path.display());
}

fn gcl(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_gcl")).args(args).output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn the_cli_writes_minimized_bundles_that_replay_and_junit_reports() {
    if !python_ready() {
        return;
    }
    let py = deps::python();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bundles");
    let report = dir.path().join("report");
    let host = mutants().join("py_err_table.py").display().to_string();
    let (code, _, err) = gcl(&[
        "fuzz",
        "host",
        "--profile",
        "seed",
        "--seed",
        "5",
        "--runs",
        "12",
        "--timeout-hang",
        "2500ms",
        "--ops",
        "err-bits,crlf",
        "--max-misbehaviours",
        "3",
        "--out",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "--",
        &py,
        &host,
    ]);
    assert_eq!(code, 1, "{err}");
    let bundle = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.file_name().unwrap().to_str().unwrap().starts_with("crash-"));
    let bundle = bundle.unwrap_or_else(|| panic!("no crash bundle: {err}"));
    let finding = std::fs::read_to_string(bundle.join("finding.json")).unwrap();
    assert!(finding.contains("KeyError"), "{finding}");
    // Minimized: one ERR with odd bits is all it takes.
    let schedule: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(bundle.join("schedule.json")).unwrap()).unwrap();
    let planned = schedule["planned"].as_array().unwrap();
    assert_eq!(planned.len(), 1, "{schedule}");
    assert_eq!(planned[0]["op"], "err-bits");
    let transcript = std::fs::read_to_string(bundle.join("transcript.gcl")).unwrap();
    assert!(transcript.contains("# misbehaviour err-bits"), "{transcript}");
    gcl_transcript::parse(&transcript).unwrap();
    let junit = std::fs::read_to_string(report.join("junit.xml")).unwrap();
    assert!(junit.contains("<failure"), "{junit}");
    schema_valid(&report.join("report.json"));
    assert!(report.join("fuzz.json").exists() && report.join("report.html").exists());
    // Replay gives the same finding, twice.
    for _ in 0..2 {
        let (code, _, err) = gcl(&["fuzz", "host", "--replay", bundle.to_str().unwrap(), "--", &py, &host]);
        assert_eq!(code, 1, "{err}");
        assert!(err.contains("reproduced: crash: python KeyError"), "{err}");
    }
    // A clean host replayed against the bundle has no finding.
    let clean = mutants().join("gclhost.py").display().to_string();
    let (code, _, err) = gcl(&["fuzz", "host", "--replay", bundle.to_str().unwrap(), "--", &py, &clean]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("NOT reproduced"), "{err}");
}

#[test]
fn check_host_cli_compares_with_a_golden_and_exits_like_conform() {
    if !python_ready() {
        return;
    }
    let py = deps::python();
    let dir = tempfile::tempdir().unwrap();
    let golden = dir.path().join("golden.gcl");
    let mut text = String::from(
        "gcl-transcript 1\nid: pyserial-host\ntitle: the pyserial host's scenario\nclause: host: golden transcript\nlevel: INFO\nprofile: seed\n\nsend \"\\x03\"\nexpect \"\"\n",
    );
    for line in ["HI", "FGET DP", "1M 5000", "1FGET P", "C", "O", "FGET P", "2M 1000", "123FGET P"] {
        text.push_str(&format!("\nsend \"{line}\\r\"\nexpect \"\"\n"));
    }
    std::fs::write(&golden, text).unwrap();
    let report = dir.path().join("r");
    let good = mutants().join("gclhost.py").display().to_string();
    let (code, out, err) = gcl(&[
        "check-host",
        "--profile",
        "seed",
        "--golden",
        golden.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "--",
        &py,
        &good,
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("PASS    host-golden"), "{out}");
    assert!(report.join("junit.xml").exists());
    schema_valid(&report.join("report.json"));
    let lf = mutants().join("py_sends_lf.py").display().to_string();
    let (code, out, _) =
        gcl(&["check-host", "--profile", "seed", "--golden", golden.to_str().unwrap(), "--", &py, &lf]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("FAIL    host-golden") && out.contains("FAIL    host-line-ending"), "{out}");
    // A saved session is a golden for the next run of the same host.
    let session = dir.path().join("session.gcl");
    let (code, out, err) =
        gcl(&["check-host", "--profile", "seed", "--save-session", session.to_str().unwrap(), "--", &py, &good]);
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, _) =
        gcl(&["check-host", "--profile", "seed", "--golden", session.to_str().unwrap(), "--", &py, &good]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("PASS    host-golden"), "{out}");
    let (code, out, _) =
        gcl(&["check-host", "--profile", "seed", "--golden", session.to_str().unwrap(), "--", &py, &lf]);
    assert_eq!(code, 1, "{out}");
    // Usage errors are 2.
    assert_eq!(gcl(&["check-host", "--profile", "nope", "--", "true"]).0, 2);
    assert_eq!(gcl(&["fuzz", "host", "--ops", "nonsense", "--", "true"]).0, 2);
    assert_eq!(gcl(&["fuzz", "host", "--", "/nonexistent/host"]).0, 2);
}

/// A host that never talks to the hand (it could not open the port it was given, and exits
/// with an accepted code) tests nothing: the campaign ends after its first run and says so,
/// exit 2, instead of printing host timeouts it never measured. One that talks but takes no
/// answer (it sends a ^C and leaves) is warned about: it tried little.
#[test]
fn a_host_that_never_takes_an_answer_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let (code, _, err) = gcl(&["fuzz", "host", "--runs", "2", "--out", dir.path().to_str().unwrap(), "--", "true"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("nothing tested: the host never opened the port: `true` exited with code 0"), "{err}");
    assert!(!err.contains("host timeouts (silence at"), "{err}");
    let host = "exec 3<>\"$GCL_PORT\"; printf '\\003' >&3";
    let (code, _, err) =
        gcl(&["fuzz", "host", "--runs", "2", "--out", dir.path().to_str().unwrap(), "--", "sh", "-c", host]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning: host timeouts not measured: the host took no answer"), "{err}");
}

/// Issue 39 items 2 and 3, as a user runs them: `gcl fuzz host --runs 1` on a host that polls
/// for ever (killed at the run budget) and on one that floods a line and never reads (killed
/// as hung) has its finding and exits 1; it said NO FINDING and exited 0 on both (the second
/// with the note `hang not reproduced`, its violation gone with the hang).
#[test]
fn a_single_run_keeps_a_host_that_never_ends_and_a_violation_whose_hang_went() {
    if deps::python_with(&["select"]).is_none() {
        return;
    }
    let hosts = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hosts");
    let dir = tempfile::tempdir().unwrap();
    for (host, budget, want) in [
        ("py_polls_forever.py", "4s", gcl_harness::fuzz::host::OVER_BUDGET_SENDING),
        ("py_floods_unread.py", "6s", "violation: line-ending: unterminated line"),
    ] {
        let report = dir.path().join(host);
        let bundles = dir.path().join(format!("{host}-findings"));
        let host = hosts.join(host);
        let (code, out, err) = gcl(&[
            "fuzz",
            "host",
            "--runs",
            "1",
            "--run-budget",
            budget,
            "--timeout-hang",
            "2s",
            "--out",
            bundles.to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
            "--",
            &deps::python(),
            host.to_str().unwrap(),
        ]);
        assert_eq!(code, 1, "{}: {out}{err}", host.display());
        // The progress line counts the finding told after the run (it said `0 findings`).
        let last = err.lines().find(|l| l.ends_with("(done)")).unwrap_or_default();
        assert!(last.starts_with("gcl fuzz host: 1/1 runs, 1 findings"), "{err}");
        let fuzz: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(report.join("fuzz.json")).unwrap()).unwrap();
        let found: Vec<&str> =
            fuzz["findings"].as_array().unwrap().iter().map(|f| f["verdict"]["signature"].as_str().unwrap()).collect();
        assert!(found.contains(&want), "{}: {found:?}", host.display());
    }
}

/// A campaign that ends inside its systematic pass says how much of it ran, on the console,
/// in fuzz.json and on the page, and claims "every misbehaviour at every kind of answer" only
/// when the whole pass ran (issue 38 item 3, issue 39 item 5: `--runs 12` said `41 runs,
/// every misbehaviour at every kind of answer` after 11).
#[test]
fn a_short_campaign_says_how_much_of_the_systematic_pass_it_made() {
    if !python_ready() {
        return;
    }
    let py = deps::python();
    let host = mutants().join("gclhost.py").display().to_string();
    let dir = tempfile::tempdir().unwrap();
    let campaign = |runs: &str, jobs: &str, name: &str| {
        let report = dir.path().join(name);
        let (code, _, err) = gcl(&[
            "fuzz",
            "host",
            "--profile",
            "seed",
            "--runs",
            runs,
            "--jobs",
            jobs,
            "--timeout-hang",
            "2500ms",
            "--out",
            dir.path().join(format!("{name}-out")).to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
            "--",
            &py,
            &host,
        ]);
        assert_eq!(code, 0, "{err}");
        let fuzz: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(report.join("fuzz.json")).unwrap()).unwrap();
        let page = std::fs::read_to_string(report.join("report.html")).unwrap();
        (err, fuzz, page)
    };
    // Run 0 has no misbehaviour: runs 1 to 11 are the first 11 of the pass.
    let (err, fuzz, page) = campaign("12", "1", "short");
    let total = fuzz["pass_runs"].as_u64().unwrap();
    assert!(total > 11, "{fuzz}");
    let line = err.lines().find(|l| l.starts_with("systematic pass:")).unwrap_or_else(|| panic!("{err}"));
    assert!(line.starts_with(&format!("systematic pass: 11 of {total} runs ({} not reached: ", total - 11)), "{line}");
    assert!(line.contains("a complete pass needs about ") && line.ends_with(" at --jobs 1"), "{line}");
    assert!(!err.contains("every misbehaviour at every kind of answer"), "{err}");
    assert_eq!(fuzz["pass"]["made"], 11, "{fuzz}");
    assert_eq!(fuzz["pass"]["not_reached"].as_array().unwrap().len() as u64, total - 11, "{fuzz}");
    assert!(page.contains(&format!("11 of {total} runs ({} not reached", total - 11)), "the page says it too");
    // At --jobs 2 too the pass starts at run 1 (every run waits for run 0): 3 of 4 runs.
    let (err, fuzz, _) = campaign("4", "2", "jobs");
    assert_eq!(fuzz["pass"]["made"], 3, "{fuzz}");
    assert!(err.contains(&format!("systematic pass: 3 of {total} runs")), "{err}");
    // The whole pass: the claim, and nothing not reached.
    let (err, fuzz, page) = campaign(&(total + 1).to_string(), "1", "whole");
    assert!(
        err.contains(&format!("systematic pass: {total} of {total} runs, every misbehaviour at every kind of answer")),
        "{err}"
    );
    assert_eq!(fuzz["pass"]["made"], total, "{fuzz}");
    assert!(fuzz["pass"].get("not_reached").is_none(), "{fuzz}");
    assert!(page.contains("every misbehaviour at every kind of answer"));
}

/// A host that ends its lines with LF is one finding, `LF sent` (it was also `unterminated
/// line`), and where it did not wait for an answer calibration says so, not `gave up after
/// 0.0 s` (issue 38 item 6).
#[test]
fn a_host_that_ends_lines_with_lf_is_one_finding_and_no_wait_is_no_timeout() {
    if !python_ready() {
        return;
    }
    let py = deps::python();
    let dir = tempfile::tempdir().unwrap();
    let host = mutants().join("py_sends_lf.py").display().to_string();
    let out = dir.path().join("out");
    let (code, _, err) =
        gcl(&["fuzz", "host", "--profile", "seed", "--runs", "1", "--out", out.to_str().unwrap(), "--", &py, &host]);
    assert_eq!(code, 1, "{err}");
    let found: Vec<&str> = err.lines().filter(|l| l.starts_with("  finding: ")).collect();
    assert_eq!(found.len(), 1, "{err}");
    assert!(found[0].contains("violation: line-ending: LF sent"), "{err}");
    assert!(!err.contains("gave up after 0.0 s"), "{err}");
    assert!(err.contains(": did not wait: sent or left within 0.1 s"), "{err}");
}

/// `--link` is refused where a link could serve two hosts (no `{slot}` at more than one job)
/// or has no pty to point at (`--tcp`), and with `{slot}` every slot's link is made for its
/// runs and removed after them.
#[test]
fn link_patterns_are_one_link_per_slot_or_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let fixed = dir.path().join("ttyUSB0").display().to_string();
    let host = ["--", "sh", "-c", "exec 3<>\"$GCL_PORT\"; printf '\\003' >&3"];
    let with = |extra: &[&str]| {
        let mut args = vec!["fuzz", "host", "--runs", "2", "--timeout-hang", "2s", "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        args.extend_from_slice(&host);
        gcl(&args)
    };
    let (code, _, err) = with(&["--jobs", "2", "--link", &fixed]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("would share one link; put {slot} in it"), "{err}");
    let pattern = dir.path().join("ttyUSB{slot}").display().to_string();
    let (code, _, err) = with(&["--tcp", "--link", &pattern]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot go with --tcp"), "{err}");
    let (code, _, err) = with(&["--jobs", "2", "--link", &pattern]);
    assert_eq!(code, 0, "{err}");
    assert!(!dir.path().join("ttyUSB1").exists() && !dir.path().join("ttyUSB2").exists(), "links removed");
    let (code, _, err) = with(&["--jobs", "1", "--link", &fixed]);
    assert_eq!(code, 0, "one job, one link: {err}");
}

/// Issue 40: a hang's confirmation waits up to the run budget (`--timeout-hang 1s` took 62 s,
/// 59.9 s of it a confirmation said nowhere): the console says so before it waits.
#[test]
fn a_hang_confirmation_says_how_long_it_may_wait() {
    if !python_ready() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bundles");
    let mut args = vec![
        "fuzz",
        "host",
        "--ops",
        "silence",
        "--runs",
        "2",
        "--jobs",
        "1",
        "--timeout-hang",
        "1s",
        "--run-budget",
        "4s",
        "--no-minimize",
        "--out",
        out.to_str().unwrap(),
        "--",
    ];
    let host = python("py_prompt_forever.py");
    args.extend(host.iter().map(String::as_str));
    args.push("{port}");
    let (code, _, stderr) = gcl(&args);
    assert_eq!(code, 1, "{stderr}");
    let line = stderr.lines().find(|l| l.contains("confirming hang")).unwrap_or_else(|| panic!("{stderr}"));
    assert!(line.contains("waiting up to 4.0 s for the host to act"), "{line}");
    let at = stderr.find("confirming hang").unwrap();
    assert!(stderr[at..].contains("finding: hang"), "said before the finding: {stderr}");
}
