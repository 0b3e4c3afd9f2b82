//! Relations in goldens: a case whose clause is a ratio or an effect holds one answer to
//! another (a captured value and a relation to it), so that it checks its clause and nothing
//! else.
//!
//! - A hand whose velocity units differ from the model's (the seed profile with its RealTime
//!   velocity units patched) passes every scaling case and fails only the cases that rest on
//!   the units decision.
//! - A hand whose motors run twice as slow or twice as fast passes the MCV, MOV, ACCEL and
//!   TSTOP effect cases.
//! - A hand that ignores LCVC fails the LCVC case, even when the units decision is skipped.
//! - Every relation in a golden states its evidence in a note, and holds on the model's answers.

use std::path::Path;
use std::sync::Arc;

use gcl_harness::conform::{self, ConformOptions};
use gcl_harness::report::Verdict;
use gcl_harness::suite::{self, Case};
use gcl_host::SimLink;
use gcl_model::{Fault, Profile};
use gcl_transcript::Piece;

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");
const SPEC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../spec");

/// The seed's velocity-units decision: what the control and feedback velocities count in.
const UNITS: &str = "seed-rt-velocity";

/// The cases whose clause is a ratio or an effect between two motors, written as relations.
const SCALING: &[&str] = &["rt-lcvc-scaling", "rt-lfvc-scaling", "rt-lfv-formula", "rt-lcpg-zero-gain"];

/// The seed profile with other RealTime velocity units: the control velocity counts half the
/// model's (LCV x LCVC x 0.05 counts/ms) and the feedback velocity twice as coarse (LFV in
/// 0.2 counts/ms), so every LFV reads a quarter of the model's.
fn seed_with_other_units() -> Arc<Profile> {
    seed_patched(&[
        ("rt_velocity_counts_per_ms = 0.1\n", "rt_velocity_counts_per_ms = 0.05\n"),
        ("lfv_counts_per_ms = 0.1\n", "lfv_counts_per_ms = 0.2\n"),
    ])
}

/// The seed profile with lines of `seed.toml` replaced (each must be there).
fn seed_patched(patch: &[(&str, &str)]) -> Arc<Profile> {
    let resolve = |f: &str| {
        let mut text = std::fs::read_to_string(Path::new(SPEC).join(f)).ok()?;
        if f == "seed.toml" {
            for (from, to) in patch {
                assert!(text.contains(from), "seed.toml no longer has `{}`", from.trim());
                text = text.replace(from, to);
            }
        }
        Some(text)
    };
    Arc::new(Profile::load_with("seed.toml", &resolve).unwrap())
}

#[test]
fn a_hand_whose_motors_run_at_another_speed_passes_the_speed_effect_cases() {
    // Motors twice as slow and twice as fast (MCV, MOV and ACCEL in other units: the velocity
    // unit is 0.05 or 0.2 counts/ms instead of 0.1, and the acceleration scales with it): the
    // effects are ratios between two motors, so the cases pass; their absolute bands did not.
    let cases = seed_cases();
    let mut failed = Vec::new();
    for unit in ["0.05", "0.2"] {
        let to = format!("counts_per_ms_per_velocity_unit = {unit}\n");
        let hand = seed_patched(&[("counts_per_ms_per_velocity_unit = 0.1\n", &to)]);
        for id in ["param-mcv-effect", "param-mov-effect", "param-accel-effect", "param-tstop-effect"] {
            let c = cases.iter().find(|c| c.id() == id).unwrap_or_else(|| panic!("no case {id}"));
            let mut link = SimLink::new(hand.clone(), suite::model_config(c.header()));
            let out = suite::run_case(c, &mut link, &suite::replay_options());
            if !out.is_pass() {
                failed.push(format!("{unit}: {id}: {}", out.render()));
            }
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

fn seed_cases() -> Vec<Case> {
    suite::load_profile(Path::new(SUITE), "seed").unwrap()
}

#[test]
fn a_hand_with_other_velocity_units_fails_only_the_unit_cases() {
    let hand = seed_with_other_units();
    let cases = seed_cases();
    let mut failed = Vec::new();
    for c in &cases {
        let mut link = SimLink::new(hand.clone(), suite::model_config(c.header()));
        let out = suite::run_case(c, &mut link, &suite::replay_options());
        if !out.is_pass() {
            failed.push(c.id().to_string());
        }
    }
    let unit_cases: Vec<String> =
        cases.iter().filter(|c| c.decisions().iter().any(|d| d == UNITS)).map(|c| c.id().to_string()).collect();
    assert!(unit_cases.contains(&"rt-velocity-units".to_string()), "{unit_cases:?}");
    // The patch is a real difference: the unit case fails.
    assert!(failed.contains(&"rt-velocity-units".to_string()), "the patched hand passed the units case");
    for s in SCALING {
        assert!(cases.iter().any(|c| c.id() == *s), "no case {s}");
        assert!(!failed.iter().any(|f| f == s), "{s} failed on a hand that only has other velocity units");
    }
    let wrongly: Vec<&String> = failed.iter().filter(|f| !unit_cases.contains(f)).collect();
    assert!(wrongly.is_empty(), "cases that do not rest on {UNITS} failed on other velocity units: {wrongly:?}");
}

#[test]
fn a_hand_that_ignores_lcvc_fails_the_lcvc_case_even_with_the_units_skipped() {
    let p = Profile::builtin("seed").unwrap();
    let cases = seed_cases();
    let mut opts = ConformOptions::in_process(p, vec![Fault::LcvcIgnored]);
    opts.only = vec!["rt-*".into()];
    opts.known.skip_decision(UNITS, "our hand counts velocities in other units");
    let r = conform::run(&cases, &opts, None, &mut |_, _, _| {}).unwrap().report;
    let verdict = |id: &str| r.cases.iter().find(|c| c.id == id).map(|c| c.verdict);
    assert_eq!(verdict("rt-velocity-units"), Some(Verdict::Skip), "the units case is skipped");
    assert_eq!(verdict("rt-lcvc-scaling"), Some(Verdict::Fail), "the LCVC case still runs, and fails");
    // Without the fault the same selection passes: the failure is LCVC's.
    let mut clean = ConformOptions::in_process(Profile::builtin("seed").unwrap(), vec![]);
    clean.only = opts.only.clone();
    clean.known = opts.known.clone();
    let r = conform::run(&cases, &clean, None, &mut |_, _, _| {}).unwrap().report;
    assert!(r.passed(), "{:?}", r.cases.iter().filter(|c| c.verdict.fails_run()).map(|c| &c.id).collect::<Vec<_>>());
}

#[test]
fn every_relation_states_its_evidence_and_holds_on_the_model() {
    let mut relations = 0;
    let mut windows = 0;
    for name in Profile::builtin_names() {
        let p = Profile::builtin(name).unwrap();
        for c in suite::load_profile(Path::new(SUITE), &p.id).unwrap() {
            let t = &c.transcript;
            let notes = &t.header.notes;
            let mut has = false;
            for step in &t.steps {
                for r in step.expect.relations() {
                    has = true;
                    relations += 1;
                    let head = format!("relation `{}`: ", r.text());
                    let note = notes.iter().find(|n| n.starts_with(&head));
                    assert!(
                        note.is_some_and(|n| n.len() > head.len() + 40 && n.contains("model")),
                        "{}/{}: relation {} has no note giving its evidence from the model",
                        p.id,
                        c.id(),
                        r.text()
                    );
                }
                if step.earliest.is_some() {
                    has = true;
                    windows += 1;
                    assert!(
                        notes.iter().any(|n| n.starts_with("timing window: ") && n.contains("model")),
                        "{}/{}: a timing window without its evidence",
                        p.id,
                        c.id()
                    );
                }
                // A captured value is read with a range or a whole field, never left free of
                // what the clause needs (a relation is only as good as its anchor).
                for (_, piece) in step.expect.pieces() {
                    if let Piece::Value(v) = piece {
                        assert!(
                            v.capture.is_none() || v.relation.is_some() || v.range.is_some(),
                            "{}/{}: a capture without a range",
                            p.id,
                            c.id()
                        );
                    }
                }
            }
            if has {
                // The model's own answers satisfy every relation and window of the case.
                let mut link = SimLink::new(p.clone(), suite::model_config(c.header()));
                let out = suite::run_case(&c, &mut link, &suite::replay_options());
                assert!(out.is_pass(), "{}/{}: {}", p.id, c.id(), out.render());
            }
        }
    }
    assert!(relations >= 20, "only {relations} relations in the goldens");
    assert!(windows >= 3, "only {windows} timing windows in the goldens");
}
