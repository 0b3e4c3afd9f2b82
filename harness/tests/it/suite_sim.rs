//! The unmutated in-process simulator passes every committed golden transcript of every
//! profile, and the suite covers what the issue asks of it.

use std::path::PathBuf;

use gcl_harness::suite::{self, Case};
use gcl_host::SimLink;
use gcl_model::Profile;
use gcl_transcript::{Level, Requirement};

fn suite_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(suite::DEFAULT_DIR)
}

fn committed() -> Vec<Case> {
    let cases = suite::load_dir(&suite_dir()).unwrap_or_else(|e| panic!("loading the committed suite: {e}"));
    assert!(!cases.is_empty(), "no committed suite under {}", suite_dir().display());
    cases
}

#[test]
fn the_simulator_passes_every_committed_case() {
    let mut failures = Vec::new();
    let cases = committed();
    for case in &cases {
        let profile = Profile::builtin(&case.profile).unwrap();
        let mut link = SimLink::new(profile, suite::model_config(case.header()));
        let out = suite::run_case(case, &mut link, &suite::replay_options());
        if !out.is_pass() {
            failures.push(format!("{}: {}", case.rel_path().display(), out.render()));
        }
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n{}", failures.len(), cases.len(), failures.join("\n"));
}

#[test]
fn every_profile_has_a_suite_with_every_level_it_needs() {
    let cases = committed();
    for name in Profile::builtin_names() {
        let mine: Vec<&Case> = cases.iter().filter(|c| c.profile == name).collect();
        assert!(mine.len() > 100, "{name}: only {} cases", mine.len());
        for l in [Level::Must, Level::Should, Level::Info] {
            assert!(mine.iter().any(|c| c.level() == l), "{name}: no {l} case");
        }
        let p = Profile::builtin(name).unwrap();
        for c in &p.commands {
            let id = format!("cmd-{}-prefix", c.name.to_ascii_lowercase().replace("a?", "a-help").replace('?', "help"));
            assert!(mine.iter().any(|k| k.id() == id), "{name}: no {id}");
        }
        for x in &p.params {
            let id = format!("param-{}-default", x.name.to_ascii_lowercase());
            assert!(mine.iter().any(|k| k.id() == id), "{name}: no {id}");
        }
        for s in p.status.iter().filter(|s| s.sent && s.bit != 2) {
            let prefix = format!("status-{}-", s.bit);
            assert!(mine.iter().any(|k| k.id().starts_with(&prefix)), "{name}: no case for status {}", s.bit);
        }
        // A case is never stronger than a decision it checks: [open] points stay INFO.
        for c in &mine {
            for cl in &c.header().clauses {
                let Some(d) = cl.strip_prefix("decision:") else { continue };
                let d = p
                    .decisions
                    .iter()
                    .find(|x| x.id == d)
                    .unwrap_or_else(|| panic!("{name}/{}: no decision {d}", c.id()));
                let l: Level = d.level;
                assert!(c.level() >= l, "{name}/{}: level {} but it checks {} ({})", c.id(), c.level(), d.id, d.level);
            }
        }
        // A case that writes the EEPROM leaves the factory values in it.
        for c in mine.iter().filter(|c| c.requires(&Requirement::Eeprom)) {
            let mut link = SimLink::new(p.clone(), suite::model_config(c.header()));
            assert!(suite::run_case(c, &mut link, &suite::replay_options()).is_pass());
            let nv = link.device().nv();
            assert!(nv.writes > 0, "{name}/{}: requires eeprom but never writes it", c.id());
            for id in p.param_ids().filter(|id| !p.param(*id).persist.is_empty()) {
                for m in 1..=4 {
                    assert_eq!(
                        nv.load(&p, id, m),
                        p.default_for(id, m),
                        "{name}/{}: the EEPROM keeps {} {} for motor {m}",
                        c.id(),
                        p.param(id).name,
                        nv.load(&p, id, m)
                    );
                }
            }
        }
    }
}
