//! Proof that the suite catches firmware bugs: `gcl conform` against every `--fault` mutant
//! of the simulator fails, and names the cases that should catch the bug; the unmutated
//! simulator passes 100%. Also: known failures (XFAIL/XPASS), the liveness probe, reports
//! and certificates, all through the real `gcl` binary.

use std::path::Path;
use std::process::{Command, Output};
use std::str::FromStr;

use gcl_harness::conform::{self, ConformOptions};
use gcl_harness::report::{RunReport, Verdict};
use gcl_harness::suite;
use gcl_model::{Fault, Profile};

const GCL: &str = env!("CARGO_BIN_EXE_gcl");

/// Each mutant, the profile it is tried on, and the cases named for it: each must fail.
const MUTANTS: &[(&str, &str, &[&str])] = &[
    ("crlf", B44, &["framing-echo", "framing-empty-line"]),
    ("no-echo", B44, &["framing-echo"]),
    ("prompt-no-space", B44, &["framing-empty-line"]),
    ("lfap-little-endian", B44, &["rt-lfap-byte-order"]),
    ("read-only-status", B44, &["status-256-read-only", "param-p-read-only"]),
    ("lfdp-not-clipped", B44, &["rt-lfdp-worked-example"]),
    ("mpe-ignored", B44, &["status-16-missed-position"]),
    ("stay-in-loop", B44, &["rt-bad-header-returns-to-supervisory"]),
    ("range-off-by-one", B44, &["param-dp-range"]),
    ("fdef-skips-mcv", B44, &["persist-fdef"]),
    ("lowercase-rejected", B44, &["framing-case"]),
    ("fget-reversed", B44, &["param-dp-default", "cmd-fget"]),
    ("abort-silent", B44, &["status-16384-abort", "abort-motion"]),
    ("loop-ack-newline", B44, &["cmd-loop"]),
    ("reset-no-banner", B44, &["cmd-reset"]),
    ("dp-ignored", B44, &["param-dp-effect"]),
    ("ds-ignored", B44, &["param-ds-effect"]),
    ("ct-ignored", B44, &["param-ct-effect"]),
    ("ot-ignored", B44, &["param-ot-effect"]),
    ("mcv-ignored", B44, &["param-mcv-effect"]),
    ("mov-ignored", B44, &["param-mov-effect"]),
    ("accel-ignored", SEED, &["param-accel-effect"]),
    ("mpe-default", B44, &["param-mpe-effect"]),
    ("tstop-ignored", B44, &["param-tstop-effect"]),
    ("hsg-ignored", B44, &["motion-strain-limit"]),
    ("lsg-ignored", B44, &["param-lsg-effect"]),
    ("hold-ignored", B44, &["param-hold-effect"]),
    ("bs-ignored", B44, &["param-bs-effect"]),
    ("en-ignored", B44, &["param-en-narrows-motion", "rt-loop-en-motors"]),
    ("sgflip-ignored", B44, &["param-sgflip-effect", "rt-lfs-sgflip"]),
    ("otemp-ignored", B44, &["status-8192-overtemperature", "cmd-m-overtemp"]),
    ("lcvc-ignored", B44, &["rt-lcvc-scaling", "rt-lcvc-positions"]),
    ("lfvc-ignored", B44, &["rt-lfvc-scaling", "rt-lfv-formula"]),
    ("lfdpc-ignored", B44, &["rt-lfdpc-scaling"]),
    ("lfdpd-ignored", B44, &["rt-lfdpd-discard"]),
    ("lcv-ignored", B44, &["rt-field-lcv"]),
    ("lcpg-ignored", B44, &["rt-field-lcpg"]),
    ("lfv-ignored", B44, &["rt-field-lfv"]),
    ("lfs-ignored", B44, &["rt-field-lfs"]),
    ("lfap-ignored", B44, &["rt-field-lfap"]),
    ("lfdp-ignored", B44, &["rt-field-lfdp"]),
    ("lct-ignored", B44, &["rt-field-lct"]),
    ("lfbp-ignored", B44, &["rt-field-lfbp"]),
    ("lfain-ignored", B44, &["rt-field-lfain"]),
    ("lft-ignored", B44, &["rt-field-lft"]),
    ("too-many-args-silent", B44, &["status-1024-too-many-arguments", "cmd-m-args"]),
    ("prefix-not-refused", B44, &["status-4096-prefix-not-allowed", "cmd-reset-prefix"]),
    ("g-includes-spread", B44, &["cmd-fget-prefix"]),
    ("reset-keeps-ram", B44, &["persist-reset-discards-ram"]),
    ("fdef-writes-eeprom", B44, &["persist-fdef-ram-only"]),
    ("lcv-unsigned", B44, &["example-realtime-seed"]),
    ("fget-p-keeps-reported", B44, &["rt-lfdp-worked-example"]),
    ("uninitialized-moves", B44, &["status-4-not-initialized", "cmd-m-before-hi"]),
    ("unknown-command-64", B44, &["status-32-unknown-command"]),
    ("unknown-param-128", B44, &["status-64-unknown-parameter", "param-unknown-name-fset"]),
    ("partial-set-applied", B44, &["framing-line-atomic"]),
    ("tab-not-separator", B44, &["framing-whitespace"]),
    ("missing-value-ignored", B44, &["cmd-fset-args", "cmd-pset-args"]),
    ("empty-line-error", B44, &["framing-empty-line"]),
    ("overlong-line-runs", B44, &["framing-max-line"]),
    ("empty-line-two-prompts", B44, &["framing-empty-line"]),
    ("vers-unknown", B44, &["cmd-vers"]),
];

const B44: &str = "bh8-262-4.4";
const SEED: &str = "seed";

/// The committed goldens (a separate test keeps them fresh); loading them is cheaper than
/// generating the suite in every run of a debug build.
const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");

fn cases(profile: &Profile) -> Vec<suite::Case> {
    suite::load_profile(Path::new(SUITE), &profile.id).unwrap()
}

fn in_process(profile: &str, faults: Vec<Fault>) -> RunReport {
    let p = Profile::builtin(profile).unwrap();
    let cases = cases(&p);
    let opts = ConformOptions::in_process(p, faults);
    conform::run(&cases, &opts, None, &mut |_, _, _| {}).unwrap().report
}

fn failed(r: &RunReport) -> Vec<&str> {
    r.cases.iter().filter(|c| c.verdict.fails_run()).map(|c| c.id.as_str()).collect()
}

#[test]
fn the_unmutated_simulator_passes_every_case_of_every_profile() {
    for name in Profile::builtin_names() {
        let r = in_process(name, vec![]);
        assert!(r.cases.len() > 150, "{name}: only {} cases", r.cases.len());
        assert!(r.passed(), "{name}: {:?}", failed(&r));
        assert_eq!(r.summary[&Verdict::Pass], r.cases.len(), "{name}: every case ran and passed");
    }
}

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn every_mutant_is_caught_in_process_by_the_cases_named_for_it() {
    assert!(Fault::ALL.len() >= 35, "only {} faults", Fault::ALL.len());
    for f in Fault::ALL {
        assert!(MUTANTS.iter().any(|(n, _, _)| *n == f.name()), "fault {f} has no expectation in MUTANTS");
    }
    // Two threads: the machines that run this have two cores.
    let (a, b) = MUTANTS.split_at(MUTANTS.len() / 2);
    let check = |part: &'static [(&'static str, &'static str, &'static [&'static str])]| {
        for (name, profile, catchers) in part {
            let r = in_process(profile, vec![Fault::from_str(name).unwrap()]);
            let f = failed(&r);
            assert!(!r.passed(), "mutant {name} survived the suite");
            for c in *catchers {
                assert!(f.contains(c), "mutant {name}: case {c} should fail; failing: {f:?}");
            }
        }
    };
    std::thread::scope(|s| {
        let h = s.spawn(|| check(a));
        check(b);
        h.join().unwrap();
    });
}

fn gcl(args: &[&str]) -> Output {
    Command::new(GCL).args(args).output().unwrap()
}

fn report(dir: &Path) -> RunReport {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

/// A `gcl sim --scenario` file in `dir` placing the objects of `setup`, or `None` without one.
fn scenario_of(setup: &[gcl_transcript::Setup], dir: &Path) -> Option<std::path::PathBuf> {
    if setup.is_empty() {
        return None;
    }
    let objects: Vec<String> =
        setup.iter().map(|gcl_transcript::Setup::Object { motor, at }| format!("{motor} = {at}")).collect();
    let f = dir.join("scenario.toml");
    std::fs::write(&f, format!("objects = {{ {} }}\n", objects.join(", "))).unwrap();
    Some(f)
}

/// One mutant through `gcl conform` over exec: the run fails and names each case named for it.
fn mutant_fails_over_exec(name: &str, profile: &str, catchers: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    // ^C during motion needs the hand to still be moving when it arrives: real time.
    let p = Profile::builtin(profile).unwrap();
    let timed =
        cases(&p).iter().any(|c| catchers.contains(&c.id()) && c.requires(&gcl_transcript::Requirement::AbortTiming));
    let time = if timed { "real" } else { "fast" };
    // A case that needs an object: the sim is started with it (a scenario file) and the run
    // declares the fixture in place, as an operator would with a real hand.
    let setup: Vec<gcl_transcript::Setup> =
        cases(&p).iter().filter(|c| catchers.contains(&c.id())).flat_map(|c| c.header().setup.clone()).collect();
    let with = scenario_of(&setup, dir.path()).map_or(String::new(), |f| format!(" --scenario {}", f.display()));
    let target = format!("exec:{GCL} sim --stdio --profile {profile} --time {time} --fault {name}{with}");
    let mut args =
        vec!["conform", "--target", &target, "--profile", profile, "-q", "--timeout", "1000", "--suite", SUITE];
    if !setup.is_empty() {
        args.extend(["--fixture", "object"]);
    }
    for c in catchers {
        args.extend(["--only", c]);
    }
    let rep = dir.path().to_str().unwrap().to_string();
    args.extend(["--report", &rep]);
    let out = gcl(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "mutant {name} must fail the run:\n{stdout}");
    let r = report(dir.path());
    for c in catchers {
        let case = r.cases.iter().find(|x| x.id == *c).unwrap_or_else(|| panic!("{name}: {c} did not run"));
        // A mismatch is FAIL; an answer that never completes (a prompt missing its space)
        // is TIMEOUT. Either way the case fails the run, with its diff and transcript.
        assert!(matches!(case.verdict, Verdict::Fail | Verdict::Timeout), "mutant {name}: {c}: {:?}", case.verdict);
        assert!(case.diff.is_some() && case.transcript.is_some(), "a failure carries its diff and transcript");
        assert!(stdout.contains(c), "the summary names {c}:\n{stdout}");
    }
}

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn every_mutant_fails_gcl_conform_over_exec() {
    // Four workers: the real-time mutants spend their time waiting for motion, not on a core.
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        let workers: Vec<_> = (0..4)
            .map(|_| {
                s.spawn(|| {
                    while let Some((name, profile, catchers)) =
                        MUTANTS.get(next.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
                    {
                        mutant_fails_over_exec(name, profile, catchers);
                    }
                })
            })
            .collect();
        for w in workers {
            w.join().unwrap();
        }
    });
}

#[test]
fn the_unmutated_simulator_passes_over_exec_with_reports() {
    let dir = tempfile::tempdir().unwrap();
    let target = format!("exec:{GCL} sim --stdio --profile seed");
    let rep = dir.path().to_str().unwrap();
    // A simulator in fast time finishes motion before a host's pause ends, so ^C-during-motion
    // cases cannot land: refuse them (they run in-process and against real-time hands).
    let out = gcl(&[
        "conform",
        "--target",
        &target,
        "--profile",
        "seed",
        "--no",
        "abort-timing",
        "--report",
        rep,
        "--suite",
        SUITE,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    // Exit 0, but the skipped cases make it PARTIAL, not PASS (issue 29 item 5).
    assert!(stdout.contains("result: PARTIAL: "), "{stdout}");
    let r = report(dir.path());
    assert!(r.liveness.before && r.liveness.after);
    assert!(r.summary[&Verdict::Skip] > 0 && r.summary[&Verdict::Fail] == 0);
    let junit = std::fs::read_to_string(dir.path().join("junit.xml")).unwrap();
    assert_eq!(junit.matches("<testcase ").count(), r.cases.len());
    let html = std::fs::read_to_string(dir.path().join("report.html")).unwrap();
    assert!(html.contains("Clause coverage"));
    let jsonl = std::fs::read_to_string(dir.path().join("results.jsonl")).unwrap();
    assert_eq!(jsonl.lines().count(), r.cases.len(), "every case was streamed as it ended");
}

/// A case whose `setup:` places an object runs on the in-process sim, which places it (the
/// unmutated-sim test above); on a hand gcl cannot set up it is SKIP with a reason that says
/// how to run it; with the object in place and `--fixture object` it runs and passes.
#[test]
fn a_case_that_needs_an_object_runs_where_it_is_placed_or_declared_and_is_skip_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    let p = Profile::builtin(B44).unwrap();
    let case = cases(&p).into_iter().find(|c| c.id() == "param-hold-effect").unwrap();
    let scenario = scenario_of(&case.header().setup, dir.path()).expect("the case has a setup");
    assert!(case.requires(&gcl_transcript::Requirement::Object));
    let bare = format!("exec:{GCL} sim --stdio --profile {B44}");
    let run = |target: &str, extra: &[&str], sub: &str| {
        let rep = dir.path().join(sub);
        let rep = rep.to_str().unwrap();
        let mut args = vec!["conform", "--target", target, "--profile", B44, "-q", "--suite", SUITE];
        args.extend(["--only", "param-hold-effect", "--report", rep]);
        args.extend(extra);
        let out = gcl(&args);
        let r = report(Path::new(rep));
        (out, r.cases.into_iter().find(|c| c.id == "param-hold-effect").unwrap())
    };
    let (out, c) = run(&bare, &[], "bare");
    assert_eq!(c.verdict, Verdict::Skip);
    // One line says so as the run starts.
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(said.contains("objects: param-hold-effect need an object"), "{said}");
    let why = c.message.unwrap_or_default();
    assert!(why.contains("object 1 ") && why.contains("--fixture object"), "{why}");

    let placed = format!("{bare} --scenario {}", scenario.display());
    let (out, c) = run(&placed, &["--fixture", "object"], "placed");
    assert_eq!(c.verdict, Verdict::Pass, "{}", String::from_utf8_lossy(&out.stdout));
    assert_eq!(out.status.code(), Some(0));
    // The report says the object was declared in place, as it says what was refused.
    assert_eq!(report(&dir.path().join("placed")).options.fixtures, ["object"]);
    assert!(report(&dir.path().join("bare")).options.fixtures.is_empty());
    // Declared but not there: the finger closes freely and the strains are alike.
    let (out, c) = run(&bare, &["--fixture", "object"], "absent");
    assert_eq!(c.verdict, Verdict::Fail);
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn known_failures_turn_into_xfail_and_stale_entries_into_xpass() {
    let dir = tempfile::tempdir().unwrap();
    let known = dir.path().join("known.toml");
    std::fs::write(
        &known,
        "[[failure]]\ncase = \"framing-case\"\nreason = \"firmware refuses lower case (ticket 12)\"\n",
    )
    .unwrap();
    let k = known.to_str().unwrap();
    // The bug is there: XFAIL, and the run passes.
    let out = gcl(&[
        "conform",
        "--target",
        "sim",
        "--fault",
        "lowercase-rejected",
        "--only",
        "framing-*",
        "--known-failures",
        k,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("XFAIL"));
    // The bug is fixed but still listed: XPASS fails the run.
    let out = gcl(&["conform", "--target", "sim", "--only", "framing-*", "--known-failures", k]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("XPASS") && stdout.contains("remove it from the list"), "{stdout}");
}

#[test]
fn a_silent_hand_is_an_infrastructure_error_not_a_hang() {
    let out = gcl(&["conform", "--target", "exec:sleep 30", "--timeout", "300"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("liveness probe"));
    let out = gcl(&["conform", "--target", "bogus:x"]);
    assert_eq!(out.status.code(), Some(2), "usage errors exit 2");
}

#[test]
fn certificates_are_written_and_tampering_is_caught() {
    let dir = tempfile::tempdir().unwrap();
    let cert = dir.path().join("cert");
    let c = cert.to_str().unwrap();
    let out = gcl(&["certify", "--target", "sim:seed", "--out", c]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
    // A certificate judges MUST and SHOULD: clauses with only INFO cases are out of its scope,
    // and the summary says so instead of calling them not fully judged (issue 21 item 4).
    let stdout = String::from_utf8_lossy(&out.stdout);
    let clauses = stdout.lines().find(|l| l.trim_start().starts_with("clauses:")).unwrap();
    assert!(clauses.contains(" 0 not fully judged"), "{clauses}");
    assert!(clauses.contains(" out of this run's scope (only INFO cases"), "{clauses}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cert.join("certificate.json")).unwrap()).unwrap();
    assert!(json["firmware_version"][0].as_str().unwrap().contains("seed"), "{json}");
    assert_eq!(json["verdict"], "PASS");
    assert_eq!(json["levels"], serde_json::json!(["MUST", "SHOULD"]));
    assert!(std::fs::read_dir(cert.join("transcripts")).unwrap().count() > 100);
    // Unsigned: intact, but its authenticity was not checked (exit 1 unless allowed).
    assert_eq!(gcl(&["certify", "--verify", c]).status.code(), Some(1));
    assert_eq!(gcl(&["certify", "--verify", c, "--allow-unverified"]).status.code(), Some(0));
    let t = cert.join("transcripts/framing-echo.gcl");
    let text = std::fs::read_to_string(&t).unwrap();
    std::fs::write(&t, text.replacen("=> ", "=>", 1)).unwrap();
    let out = gcl(&["certify", "--verify", c]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains("modified: transcripts/framing-echo.gcl"));
}

#[test]
fn skip_decision_drops_exactly_the_cases_resting_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let rep = dir.path().to_str().unwrap();
    // A hand whose lines hold 128 bytes fails framing-max-line; the implementer skips the
    // decision instead of the case, and every other case still runs.
    let out = gcl(&[
        "conform",
        "--target",
        "sim:seed",
        "--only",
        "framing-*",
        "--skip-decision",
        "framing-max-line",
        "--report",
        rep,
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
    let r = report(dir.path());
    for c in &r.cases {
        let rests = c.decisions.iter().any(|d| d == "framing-max-line");
        assert_eq!(c.verdict == Verdict::Skip, rests, "{}: {:?} {:?}", c.id, c.verdict, c.decisions);
        if rests {
            assert!(c.message.as_deref().unwrap_or_default().contains("framing-max-line"));
        }
    }
    assert!(r.cases.iter().any(|c| c.verdict == Verdict::Skip));
    // The same from a known-failures file, with its reason.
    let known = dir.path().join("known.toml");
    std::fs::write(&known, "[[skip-decision]]\nid = \"framing-case\"\nreason = \"upper case only\"\n").unwrap();
    let out = gcl(&[
        "conform",
        "--target",
        "sim:seed",
        "--fault",
        "lowercase-rejected",
        "--only",
        "framing-*",
        "--known-failures",
        known.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    // A decision the profile lacks is a usage error, not a silent no-op.
    let out = gcl(&["conform", "--target", "sim:seed", "--skip-decision", "no-such-decision"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no-such-decision"));
}
