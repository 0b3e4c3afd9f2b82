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
        transcript: None,
    }
}
