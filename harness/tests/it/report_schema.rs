//! `report.json` is what CI systems read: every report `gcl conform` writes must validate
//! against the schema committed in `reports/report.schema.json`, failures and all.

use std::str::FromStr;

use gcl_harness::conform::{self, ConformOptions, KnownFailures, LevelFilter};
use gcl_harness::report::{self, Verdict};
use gcl_harness::suite;
use gcl_host::target::{OpenOptions, Target};
use gcl_model::{Fault, Profile};

fn validator() -> jsonschema::Validator {
    let schema: serde_json::Value = serde_json::from_str(report::SCHEMA).unwrap();
    jsonschema::validator_for(&schema).unwrap()
}

#[test]
fn reports_with_every_kind_of_verdict_validate_against_the_schema() {
    let p = Profile::builtin("bh8-262-4.4").unwrap();
    let cases = suite::generate(&p).unwrap();
    let opts = ConformOptions {
        target: Target::Sim { profile: None },
        open: OpenOptions { faults: vec![Fault::from_str("fget-reversed").unwrap()], ..Default::default() },
        profile: p,
        level: LevelFilter::Should,
        only: vec![],
        skip: vec!["rt-*".into()],
        known: KnownFailures::parse("[[failure]]\ncase = \"cmd-fget\"\nreason = \"r\"\n").unwrap(),
        step_timeout: None,
        refuse: vec![],
        fixtures: vec![],
        baud: Some(38400),
        keep_transcripts: false,
        control: Default::default(),
    };
    let r = conform::run(&cases, &opts, None, &mut |_, _, _| {}).unwrap().report;
    for v in [Verdict::Pass, Verdict::Fail, Verdict::Skip, Verdict::Xfail] {
        assert!(r.summary[&v] > 0, "the sample run has a {v}");
    }
    assert!(r.wire.is_some());
    assert!(r.preflight.is_some() && !r.groups.is_empty());
    let v = validator();
    let check = |r: &report::RunReport| {
        let json = serde_json::to_value(r).unwrap();
        let errors: Vec<String> = v.iter_errors(&json).map(|e| format!("{e} at {}", e.instance_path())).collect();
        assert!(errors.is_empty(), "{errors:#?}");
    };
    check(&r);
    // A certificate's report: its verdict line, where its profile came from, what it adds.
    let mut c = r.clone();
    c.kind = report::ReportKind::Certify;
    c.verdict = c.outcome().verdict;
    assert!(c.verdict.starts_with("FAIL (PARTIAL: "), "{}", c.verdict);
    c.profile_spec = Some(report::ProfileSpec::of("bh8-262-4.4", &Profile::builtin("bh8-262-4.4").unwrap()));
    c.certificate = Some(report::CertificateFacts {
        cases_total: 300,
        firmware_version: vec!["BarrettHand".into()],
        signed_by: Some("0123456789abcdef".into()),
    });
    check(&c);
    // A run that ends early says so, and still validates.
    let opts = ConformOptions { control: conform::RunControl { max_failures: Some(2), ..Default::default() }, ..opts };
    let r = conform::run(&cases, &opts, None, &mut |_, _, _| {}).unwrap().report;
    assert!(r.stopped.is_some());
    check(&r);
}

#[test]
fn the_schema_rejects_what_it_should() {
    let v = validator();
    let good = serde_json::to_value(sample_case()).unwrap();
    let mut bad = good.clone();
    bad["verdict"] = "MAYBE".into();
    let report = |case: serde_json::Value| {
        serde_json::json!({
            "format": 1, "tool": "gcl", "target": "sim", "profile": "seed", "level": "all",
            "started": "2026-11-22T00:00:00Z", "duration_ms": 1.0, "suite_hash": "0".repeat(64),
            "liveness": {"before": true, "after": true}, "summary": {"PASS": 1}, "clauses": [], "cases": [case]
        })
    };
    assert!(v.is_valid(&report(good)));
    assert!(!v.is_valid(&report(bad)), "an unknown verdict is refused");
    // The golden is in the form of expected and actual, never a quoted string (issue 21 item 4).
    let diff =
        |golden: &str| serde_json::json!({"step": 1, "offset": 0, "expected": "x", "actual": "y", "golden": golden});
    let mut failed = serde_json::to_value(sample_case()).unwrap();
    failed["verdict"] = "FAIL".into();
    failed["diff"] = diff("FGET DP\\n\\r{int 990..1010}");
    assert!(v.is_valid(&report(failed.clone())));
    failed["diff"] = diff("\"FGET DP\\n\\r{int 990..1010}\"");
    assert!(!v.is_valid(&report(failed)), "a quoted golden is refused");
}

fn sample_case() -> report::CaseResult {
    report::CaseResult {
        id: "framing-echo".into(),
        title: "t".into(),
        clauses: vec!["decision:framing-echo".into()],
        decisions: vec!["framing-echo".into()],
        level: "MUST".into(),
        verdict: Verdict::Pass,
        duration_ms: 0.1,
        message: None,
        diff: None,
        failure: None,
        transcript: None,
    }
}

/// `gcl fuzz host --report DIR` writes `fuzz.json` beside `report.json`: it validates against
/// `reports/fuzz-host.schema.json`, as written by a real campaign and in every form a finding
/// can take (issue 21 item 4).
#[test]
fn fuzz_host_campaigns_validate_against_their_schema() {
    use gcl_harness::fuzz::host::{self, Campaign, FindingKind, HostEnd};
    use gcl_harness::sim::misbehave::{Fired, Operator, Planned, Schedule};
    let schema: serde_json::Value = serde_json::from_str(host::SCHEMA).unwrap();
    let v = jsonschema::validator_for(&schema).unwrap();
    let check = |json: &serde_json::Value| {
        let errors: Vec<String> = v.iter_errors(json).map(|e| format!("{e} at {}", e.instance_path())).collect();
        assert!(errors.is_empty(), "{errors:#?}\n{json:#}");
    };
    // The schema names every misbehaviour, and nothing else.
    let names: Vec<&str> =
        schema["$defs"]["operator"]["enum"].as_array().unwrap().iter().map(|o| o.as_str().unwrap()).collect();
    assert_eq!(names, Operator::ALL.iter().map(|o| o.name()).collect::<Vec<_>>());

    // A real campaign: a host that sends HI and exits 3 is an exit-code finding in run 0.
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gcl"))
        .args(["fuzz", "host", "--profile", "seed", "--runs", "3", "--report"])
        .arg(dir.path().join("r"))
        .arg("--out")
        .arg(dir.path().join("b"))
        .args(["--", "sh", "-c", "printf 'HI\\r' > \"$GCL_PORT\"; sleep 0.2; exit 3"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("r/fuzz.json")).unwrap()).unwrap();
    assert_eq!(json["findings"][0]["verdict"]["kind"], "exit-code", "{json:#}");
    check(&json);

    // Every way a host ends, a schedule and what fired, as serde writes them.
    let mut c: Campaign = serde_json::from_value(json).unwrap();
    let planned = Planned { answer: 2, op: Operator::Truncate, arg: 5 };
    let f = &mut c.findings[0];
    f.schedule = Schedule { planned: vec![planned] };
    f.original = Schedule { planned: vec![planned, Planned { answer: 0, op: Operator::Silence, arg: 0 }] };
    f.fired =
        vec![Fired { index: 0, answer: 2, op: Operator::Truncate, state: "answer to HI".into(), what: "cut".into() }];
    for end in [
        HostEnd::Exit(-1),
        HostEnd::Signal(11),
        HostEnd::Hung("abort".into()),
        HostEnd::OverBudget("answer to C".into()),
    ] {
        c.findings[0].end = end;
        check(&serde_json::to_value(&c).unwrap());
    }
    for kind in [FindingKind::Crash, FindingKind::Hang, FindingKind::Violation] {
        c.findings[0].verdict.kind = kind;
        check(&serde_json::to_value(&c).unwrap());
    }
    // The host's code coverage (issue 42): the shell wrote no AFL map, so a note; and an
    // instrumented host's account, with its rise and the runs that added edges.
    assert_eq!(c.coverage.as_ref().and_then(|k| k.note.as_deref()), Some(host::coverage::NOT_INSTRUMENTED));
    c.coverage = Some(host::coverage::CoverageAccount {
        instrumented: true,
        edges: 5,
        host_edges: Some(9),
        map_size: 65536,
        kept: 1,
        over_time: vec![host::coverage::CoveragePoint { ms: 12, runs: 1, edges: 3 }],
        added_by: vec![host::coverage::Added {
            run: 1,
            new_edges: 2,
            schedule: "truncate@2".into(),
            planned: Schedule { planned: vec![planned] },
        }],
        note: None,
    });
    check(&serde_json::to_value(&c).unwrap());
    // And it refuses what it should: an unknown field, an unknown misbehaviour.
    let mut bad = serde_json::to_value(&c).unwrap();
    bad["surprise"] = 1.into();
    assert!(!v.is_valid(&bad));
    let mut bad = serde_json::to_value(&c).unwrap();
    bad["findings"][0]["schedule"]["planned"][0]["op"] = "teleport".into();
    assert!(!v.is_valid(&bad));
}
