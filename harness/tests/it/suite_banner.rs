//! The banner decisions (`bh8-banner-text`, `seed-banner-text`) promise what host libraries
//! rely on after RESET. This test proves, on every profile, that a case cites the decision
//! and that the case fails on a hand that breaks the promise: the old one-line banner, a
//! banner whose text is not followed by the line ending, and one with nothing after it.

use std::path::Path;
use std::sync::Arc;

use gcl_harness::suite::{self, Case};
use gcl_host::SimLink;
use gcl_model::Profile;

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");

fn decision(p: &Profile) -> &'static str {
    if p.id == "seed" { "decision:seed-banner-text" } else { "decision:bh8-banner-text" }
}

fn with_banner(p: &Arc<Profile>, lines: &[&str]) -> Arc<Profile> {
    let mut q = Profile::clone(p);
    q.banner = lines.iter().map(|l| l.to_string()).collect();
    Arc::new(q)
}

fn passes(case: &Case, profile: &Arc<Profile>) -> bool {
    let mut link = SimLink::new(profile.clone(), suite::model_config(case.header()));
    suite::run_case(case, &mut link, &suite::replay_options()).is_pass()
}

#[test]
fn the_banner_decision_is_cited_by_a_case_that_fails_without_it() {
    for name in Profile::builtin_names() {
        let p = Profile::builtin(name).unwrap();
        let cases = suite::load_profile(Path::new(SUITE), &p.id).unwrap();
        let citing: Vec<&Case> =
            cases.iter().filter(|c| c.header().clauses.iter().any(|k| k == decision(&p))).collect();
        assert!(!citing.is_empty(), "{name}: no case cites {}", decision(&p));
        let banner_case = citing.iter().find(|c| c.id() == "banner-lines").expect("the banner-lines case");
        assert!(passes(banner_case, &p), "{name}: the model fails its own banner case");
        for broken in [
            &["BarrettHand Firmware Version 4.4x (one line)"][..],
            &["BarrettHand Firmware"][..],
            &["Barrett Technology", "BarrettHand Firmware: version 4"][..],
        ] {
            let q = with_banner(&p, broken);
            assert!(!passes(banner_case, &q), "{name}: banner {broken:?} passes the banner case");
        }
    }
}
