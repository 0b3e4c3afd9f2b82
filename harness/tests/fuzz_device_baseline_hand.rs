//! Issue 19, "on a hand that already differs, new bugs hide": an independent seed hand
//! (`hands/seed_hand.py`, written from the seed document alone, so it differs from the model
//! where the seed is silent) is fuzzed once as it is, and its findings become the baseline.
//! The same campaign with one planted bug must report that bug, and only it, as new.

mod deps;

use std::path::{Path, PathBuf};

use gcl_harness::fuzz::device::{Budget, FuzzOptions, FuzzSummary, run};
use gcl_host::target::Target;
use gcl_model::Profile;

/// Cases per campaign: enough for the planted bug's case, short enough for a test.
const RUNS: u64 = 20;

fn hand() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hands/seed_hand.py")
}

fn campaign(py: &str, bug: Option<&str>, baseline: Option<&Path>, out: &Path) -> FuzzSummary {
    let mut argv = vec![py.to_string(), hand().display().to_string()];
    if let Some(b) = bug {
        argv.extend(["--bug".to_string(), b.to_string()]);
    }
    let mut o = FuzzOptions::new(Target::Exec { argv }, Profile::builtin("seed").unwrap());
    o.seed = 1;
    o.budget = Budget::Runs(RUNS);
    o.out = Some(out.to_path_buf());
    // Minimizing replays a finding's case many times, in the hand's real motion time.
    o.minimize = false;
    if let Some(dir) = baseline {
        o.baseline.add_dir(dir).unwrap();
    }
    run(&o, &|_| {}).unwrap()
}

#[test]
fn a_planted_bug_in_a_hand_that_already_differs_is_the_only_new_finding() {
    let Some(py) = deps::python_with(&[]) else { return };
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base");
    let clean = campaign(&py, None, None, &base);
    // The hand differs from the model where the seed is silent: that is the baseline.
    assert!(!clean.findings.is_empty(), "the independent hand should already differ from the model");

    let s = campaign(&py, Some("fget-reversed"), Some(&base), &dir.path().join("bug"));
    let new: Vec<String> = s.findings.iter().filter(|f| f.is_new()).map(|f| f.signature.to_string()).collect();
    assert_eq!(new.len(), 1, "one new finding, the planted bug: {new:?}");
    let f = s.findings.iter().find(|f| f.is_new()).unwrap();
    assert_eq!((f.signature.kind.as_str(), f.signature.command.as_str()), ("order", "FGET"), "{new:?}");
}
