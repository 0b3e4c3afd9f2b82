//! The necessity report: is every case needed? Runs every fault against the seed and
//! bh8-262-4.4 suites in-process and sorts each case into one of three groups:
//! - necessary: it is the only case that catches some fault;
//! - covered: every fault it catches is also caught elsewhere;
//! - unguarded: no fault reaches its clauses yet (the list of clauses without a fault).
//!
//! Faults that fail most of the suite (a broken prompt, echo or line ending) are left out of
//! the sorting: every case catches them.
//!
//! A report, not a gate: `cargo test -p gcl-harness --test it -- --ignored --nocapture conform_necessity::`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use gcl_harness::conform::{self, ConformOptions};
use gcl_harness::suite;
use gcl_model::{Fault, Profile};

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");

fn failing(p: &std::sync::Arc<Profile>, cases: &[suite::Case], fault: Fault) -> BTreeSet<String> {
    let opts = ConformOptions::in_process(p.clone(), vec![fault]);
    let r = conform::run(cases, &opts, None, &mut |_, _, _| {}).unwrap().report;
    r.cases.iter().filter(|c| c.verdict.fails_run()).map(|c| c.id.clone()).collect()
}

#[test]
#[ignore = "a report, not a gate: run with --ignored --nocapture"]
fn necessity_report() {
    for name in ["seed", "bh8-262-4.4"] {
        let p = Profile::builtin(name).unwrap();
        let cases = suite::load_profile(Path::new(SUITE), &p.id).unwrap();
        let mut caught_by: BTreeMap<&str, BTreeSet<String>> = BTreeMap::new();
        for f in Fault::ALL {
            caught_by.insert(f.name(), failing(&p, &cases, *f));
        }
        // A fault that fails most of the suite (a broken prompt or echo) says nothing about
        // any one case: it is reported, but does not make a case necessary.
        let global: Vec<&str> =
            caught_by.iter().filter(|(_, cs)| cs.len() * 2 > cases.len()).map(|(f, _)| *f).collect();
        let mut catches: BTreeMap<String, BTreeSet<&str>> = BTreeMap::new();
        for (f, cs) in caught_by.iter().filter(|(f, _)| !global.contains(f)) {
            for c in cs {
                catches.entry(c.clone()).or_default().insert(f);
            }
        }
        // Clauses some fault reaches (through any case bearing the clause).
        let mut guarded: BTreeSet<String> = BTreeSet::new();
        for c in &cases {
            if catches.contains_key(c.id()) {
                guarded.extend(c.header().clauses.iter().cloned());
            }
        }
        let (mut necessary, mut covered, mut unguarded) = (Vec::new(), Vec::new(), Vec::new());
        let mut bare: BTreeSet<String> = BTreeSet::new();
        for c in &cases {
            let only: Vec<&str> =
                catches.get(c.id()).into_iter().flatten().filter(|f| caught_by[**f].len() == 1).copied().collect();
            if !only.is_empty() {
                necessary.push(format!("{} (only catch of {})", c.id(), only.join(", ")));
            } else if catches.contains_key(c.id()) {
                covered.push(c.id().to_string());
            } else {
                let mine: Vec<&String> = c.header().clauses.iter().filter(|k| !guarded.contains(*k)).collect();
                if mine.is_empty() {
                    covered.push(format!("{} (its clauses have faults caught by other cases)", c.id()));
                } else {
                    bare.extend(mine.iter().map(|s| s.to_string()));
                    unguarded.push(c.id().to_string());
                }
            }
        }
        println!("== {name}: {} cases, {} faults", cases.len(), Fault::ALL.len());
        for (f, cs) in &caught_by {
            println!("fault {f}: fails {} cases", cs.len());
        }
        println!("faults failing most of the suite (left out below): {}", global.join(", "));
        println!("-- necessary ({}):", necessary.len());
        necessary.iter().for_each(|l| println!("  {l}"));
        println!("-- covered by other cases ({}):", covered.len());
        covered.iter().for_each(|l| println!("  {l}"));
        println!("-- no fault reaches their clauses yet ({} cases):", unguarded.len());
        unguarded.iter().for_each(|l| println!("  {l}"));
        println!("-- clauses without a fault ({}):", bare.len());
        bare.iter().for_each(|l| println!("  {l}"));
        assert_eq!(necessary.len() + covered.len() + unguarded.len(), cases.len());
    }
}
