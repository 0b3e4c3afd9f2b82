//! Issue 19, "on a hand that already differs, new bugs hide": an independent seed hand
//! (`hands/seed_hand.py`, written from the seed document alone, so it differs from the model
//! where the seed is silent) is fuzzed once as it is, and its findings become the baseline.
//! The same campaign with one planted bug must report that bug, and only it, as new.
//! That holds for the RealTime clauses that are ratios too (a wrong LCVC scaling, LFDPC
//! ignored): positions are uncertain once a block moves a hand outside this process, so the
//! fuzzer judges them as relations between feedback fields (`fuzz::device::relate`).

use crate::deps;

use std::path::{Path, PathBuf};

use gcl_harness::fuzz::device::{Budget, FuzzOptions, FuzzSummary, run};
use gcl_host::target::Target;
use gcl_model::Profile;

/// Cases per campaign: enough for each planted bug's case, short enough for a test (with seed
/// 1 the RealTime bugs' first breaking sessions are cases 10 and 11).
const RUNS: u64 = 12;

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
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn a_planted_bug_in_a_hand_that_already_differs_is_the_only_new_finding() {
    let Some(py) = deps::python_with(&[]) else { return };
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base");
    let clean = campaign(&py, None, None, &base);
    // The hand differs from the model where the seed is silent: that is the baseline.
    assert!(!clean.findings.is_empty(), "the independent hand should already differ from the model");
    // It scales as the seed says: the relations between its feedback fields hold, whatever
    // its velocity units and its clock (it moves 2.5 times as fast as the model).
    let rt: Vec<String> = clean
        .findings
        .iter()
        .filter(|f| f.signature.command == "RealTime block")
        .map(|f| f.signature.to_string())
        .collect();
    assert!(rt.is_empty(), "no RealTime finding on a hand that scales right: {rt:?}");
    // Where it differs it decided an open point otherwise, and each finding names it.
    let must: Vec<String> = clean
        .findings
        .iter()
        .filter(|f| f.level == gcl_model::Level::Must || f.rests_on.is_empty())
        .map(|f| format!("{} [{:?}: {:?}]", f.signature, f.level, f.rests_on))
        .collect();
    assert!(must.is_empty(), "a finding of the clean hand names no open decision: {must:?}");

    // FGET reversed; the LCV datum divided by LCVC (another velocity ratio between motors with
    // other LCVCs); LFDPC ignored (another LFDP ratio between motors with other LFDPCs).
    for (bug, want) in [
        ("fget-reversed", ("FGET", "order", None)),
        ("lcvc-scaling", ("RealTime block", "value", Some("LFV"))),
        ("lfdpc-ignored", ("RealTime block", "value", Some("LFDP"))),
    ] {
        let s = campaign(&py, Some(bug), Some(&base), &dir.path().join(bug));
        let new: Vec<String> = s.findings.iter().filter(|f| f.is_new()).map(|f| f.signature.to_string()).collect();
        assert_eq!(new.len(), 1, "{bug}: one new finding, the planted bug: {new:?}");
        let sig = &s.findings.iter().find(|f| f.is_new()).unwrap().signature;
        let got = (sig.command.as_str(), sig.kind.as_str(), want.2.map(|_| sig.detail.as_str()));
        assert_eq!(got, want, "{bug}: {new:?}");
    }
}

/// A hand outside this process answers with its own noise and timing, so a hypothesis about it
/// is tried as a case built anew on a model that holds it, shaped for such a hand: the
/// independent hand applies the valid pairs of a set it refuses (its own choice on the open
/// decision framing-line-atomic), and the position read back after M is named so, not `after M`.
#[test]
fn a_hand_outside_this_process_is_named_by_a_model_that_behaves_as_it_does() {
    let Some(py) = deps::python_with(&[]) else { return };
    let argv = vec![py, hand().display().to_string()];
    let o = FuzzOptions::new(Target::Exec { argv }, Profile::builtin("seed").unwrap());
    let line = |l: &str| gcl_harness::fuzz::device::action::HostAction::Line(l.to_string());
    let actions = [line("FSET DP 1000 MCV"), line("M"), line("FGET P")];
    let sig = gcl_harness::fuzz::device::judge_once(&o, &actions).unwrap().unwrap().expect("the hand moves to 1000");
    assert_eq!(sig.explanation, "set refused but applied in part", "{sig}");
}

/// The independent hand with `args` (`--bug NAME`, `--decide NAME`), over exec.
fn hand_options(py: &str, args: &[&str]) -> FuzzOptions {
    let mut argv = vec![py.to_string(), hand().display().to_string()];
    argv.extend(args.iter().map(|a| a.to_string()));
    let mut o = FuzzOptions::new(Target::Exec { argv }, Profile::builtin("seed").unwrap());
    o.seed = 1;
    o
}

fn line(l: &str) -> gcl_harness::fuzz::device::action::HostAction {
    gcl_harness::fuzz::device::action::HostAction::Line(l.to_string())
}

fn block(header: u8, values: &[i64], pause_ms: u64) -> gcl_harness::fuzz::device::action::HostAction {
    gcl_harness::fuzz::device::action::HostAction::Block { header, values: values.to_vec(), extra: 0, pause_ms }
}

/// Issue 31, "a known deviation hides a different bug on the same field". The independent hand
/// decides where LFDP counts from otherwise than the model (`--decide lfdp-counts-from-home`:
/// from home, not from where LOOP finds the motor; the seed names only "the last reported
/// position"), so its baseline has `value at RealTime block (LFDP)`. LFDPC ignored, planted in
/// the same hand, shows on the same field; it was that key, known, and hid behind the
/// baseline. It is named by the parameter whose value made the difference, `LFDPC set without
/// effect` (a model that holds it, the case built anew on it and answered so by the hand), so
/// it is new.
#[test]
fn a_known_deviation_on_a_field_does_not_hide_another_bug_on_it() {
    let Some(py) = deps::python_with(&[]) else { return };
    let judge = |args: &[&str], actions: &[gcl_harness::fuzz::device::action::HostAction]| {
        gcl_harness::fuzz::device::judge_once(&hand_options(&py, args), actions).unwrap().unwrap()
    };
    let decided = ["--decide", "lfdp-counts-from-home"];
    // The deviation: motor 1 moved before LOOP; the model's first LFDP counts from where LOOP
    // found it (0), this hand's from home (clipped at 127).
    let deviation = [line("1FSET LFDP 1 LFS 0 LFAP 0 LFV 0"), line("1M 1000"), line("1LOOP"), block(b'A', &[], 0)];
    let known = judge(&decided, &deviation).expect("the hand counts LFDP from home");
    assert_eq!(known.key(), "value at RealTime block LFDP", "{known}");
    let mut baseline = gcl_harness::fuzz::device::Baseline::default();
    baseline.keys.insert(known.key());
    // LFDPC: two motors at one velocity, motor 2 dividing its movement by 2; LOOP right after
    // HI, where both ways of counting agree.
    let lfdpc = [
        line("12FSET LCV 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1"),
        line("2FSET LFDPC 2"),
        line("12LOOP"),
        block(b'C', &[5, 5], 0),
        block(b'C', &[5, 5], 0),
        block(b'A', &[], 20),
        block(b'A', &[], 20),
    ];
    assert_eq!(judge(&decided, &lfdpc), None, "without the plant the hand passes the LFDPC case");
    let planted = [decided[0], decided[1], "--bug", "lfdpc-ignored"];
    let sig = judge(&planted, &lfdpc).expect("the planted bug shows");
    assert_eq!(sig.explanation, "LFDPC set without effect", "{sig}");
    let id = gcl_harness::fuzz::device::finding_id(&sig);
    assert_eq!(baseline.explains("seed", &id, &sig), None, "new against the baseline: {sig}");
}

/// Issue 31, "a case that rests on a second clause hides the first": rt-lcvc-scaling reads
/// LCVC's effect through LFV, which another clause defines. On the independent hand with its
/// feedback velocity broken (`--bug lfv-zero`) that case fails already, so an LCVC ignored on
/// top of it (`--bug lcvc-ignored`) added no failure. Its behavioural twin, rt-lcvc-positions,
/// reads where the motors went (FGET P after the loop): it passes the hand with LFV broken,
/// and fails once LCVC is ignored too. The clean hand passes both.
#[test]
fn a_hand_whose_feedback_velocity_is_broken_still_fails_a_case_when_it_ignores_lcvc() {
    use gcl_harness::conform::{self, ConformOptions};
    use std::collections::BTreeSet;
    let Some(py) = deps::python_with(&[]) else { return };
    let p = Profile::builtin("seed").unwrap();
    let cases = gcl_harness::suite::generate(&p).unwrap();
    let failing = |bugs: &[&str]| -> BTreeSet<String> {
        let mut argv = vec![py.clone(), hand().display().to_string()];
        for b in bugs {
            argv.extend(["--bug".to_string(), b.to_string()]);
        }
        let opts = ConformOptions {
            target: Target::Exec { argv },
            open: Default::default(),
            only: vec!["rt-lcvc-*".into()],
            ..ConformOptions::in_process(p.clone(), vec![])
        };
        let r = conform::run(&cases, &opts, None, &mut |_, _, _| {}).unwrap().report;
        let ran: BTreeSet<String> = r.cases.iter().map(|c| c.id.clone()).collect();
        assert!(ran.contains("rt-lcvc-scaling") && ran.contains("rt-lcvc-positions"), "{bugs:?}: ran {ran:?}");
        r.cases.iter().filter(|c| c.verdict.fails_run()).map(|c| c.id.clone()).collect()
    };
    assert_eq!(failing(&[]), BTreeSet::new(), "the clean hand scales by LCVC");
    let lfv_broken = failing(&["lfv-zero"]);
    assert!(lfv_broken.contains("rt-lcvc-scaling"), "LFV reads 0: the case that reads LCVC through it fails");
    assert!(!lfv_broken.contains("rt-lcvc-positions"), "the twin does not read LFV");
    let both = failing(&["lfv-zero", "lcvc-ignored"]);
    let added: Vec<&String> = both.difference(&lfv_broken).collect();
    assert_eq!(added, vec!["rt-lcvc-positions"], "LCVC ignored on top of a broken LFV fails a case of its own");
}
