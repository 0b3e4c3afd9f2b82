//! One clause per case, and grades from evidence: every committed case rests only on the
//! decisions it checks plus the short framing list, and binds no more strongly than the
//! evidence of the weakest decision it rests on.

use std::path::Path;

use gcl_harness::suite::{self, Case};
use gcl_model::Profile;
use gcl_transcript::Level;

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");

fn profiles() -> Vec<(std::sync::Arc<Profile>, Vec<Case>)> {
    Profile::builtin_names()
        .map(|n| {
            let p = Profile::builtin(n).unwrap();
            let cases = suite::load_profile(Path::new(SUITE), &p.id).unwrap();
            assert!(!cases.is_empty(), "{n}: no committed cases");
            (p, cases)
        })
        .collect()
}

#[test]
fn every_case_rests_only_on_the_decisions_it_checks_and_the_framing_list() {
    let mut wrong = Vec::new();
    for (p, cases) in profiles() {
        for c in &cases {
            let checked = c.checked_decisions();
            let all = c.decisions();
            assert!(!all.is_empty(), "{}/{}: no decisions", p.id, c.id());
            for d in &all {
                assert!(p.decisions.iter().any(|x| &x.id == d), "{}/{}: unknown decision {d}", p.id, c.id());
                if !checked.contains(d) && !suite::FRAMING.contains(&d.as_str()) {
                    wrong.push(format!("{}/{}: rests on {d}, which it does not check", p.id, c.id()));
                }
            }
        }
    }
    assert!(wrong.is_empty(), "{} cases also rest on unrelated decisions:\n{}", wrong.len(), wrong.join("\n"));
}

#[test]
fn the_framing_list_is_short_and_every_framing_decision_is_a_must() {
    assert!(suite::FRAMING.len() <= 12);
    for (p, _) in profiles() {
        for d in p.decisions.iter().filter(|d| suite::FRAMING.contains(&d.id.as_str())) {
            assert_eq!(
                d.level,
                gcl_model::Level::Must,
                "{}: framing decision {} must be MUST, or no case could be",
                p.id,
                d.id
            );
        }
    }
}

#[test]
fn a_case_binds_no_more_than_the_weakest_evidence_it_rests_on() {
    for (p, cases) in profiles() {
        for c in &cases {
            let level = c.level();
            for d in c.decisions() {
                let dec = p.decisions.iter().find(|x| x.id == d).unwrap();
                let grade = dec.grade();
                assert!(level >= dec.level, "{}/{} is {} but rests on {} ({})", p.id, c.id(), c.level(), d, dec.level);
                if grade.is_open() {
                    assert_ne!(c.level(), Level::Must, "{}/{} is MUST but rests on [open] {d}", p.id, c.id());
                }
                assert!(level >= grade.strongest_level(), "{}/{}: {d}", p.id, c.id());
            }
        }
    }
}

#[test]
fn index_json_lists_every_case_decisions() {
    let text = std::fs::read_to_string(Path::new(SUITE).join(suite::INDEX_FILE)).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let cases = v["cases"].as_array().unwrap();
    assert!(!cases.is_empty());
    for c in cases {
        let d = c["decisions"].as_array().unwrap_or_else(|| panic!("no decisions: {c}"));
        assert!(d.iter().any(|x| x == "framing-echo"), "{c}");
    }
}
