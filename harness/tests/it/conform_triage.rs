//! Root causes first: against every `--fault` mutant of the simulator, the largest group of
//! failures names the clause the fault breaks.

use std::path::Path;

use gcl_harness::conform::{self, ConformOptions};
use gcl_harness::report::RunReport;
use gcl_harness::suite;
use gcl_model::{Fault, Profile};

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");

fn run(profile: &str, faults: Vec<Fault>) -> RunReport {
    let p = Profile::builtin(profile).unwrap();
    let cases = suite::load_profile(Path::new(SUITE), &p.id).unwrap();
    let opts = ConformOptions::in_process(p, faults);
    conform::run(&cases, &opts, None, &mut |_, _, _| {}).unwrap().report
}

/// The clause each fault breaks, as the groups should name it (after the profile's `seed: `
/// or `bh8-262: ` prefix). Where two clauses state the broken rule, either is right.
const FAULT_CLAUSES: &[(&str, &[&str])] = &[
    // ^C at idle answers LF CR then `=> `: decision framing-abort-idle states both.
    // Framing faults take the clause the pre-flight names.
    ("crlf", &["decision:framing-line-ending"]),
    ("no-echo", &["decision:framing-echo"]),
    ("prompt-no-space", &["decision:framing-prompt"]),
    ("lfap-little-endian", &["RealTime Control", "Parameter LFAP"]),
    ("read-only-status", &["Status codes 256"]),
    ("lfdp-not-clipped", &["RealTime Control", "Parameter LFDP"]),
    ("mpe-ignored", &["Status codes 16", "Parameter MPE"]),
    ("stay-in-loop", &["Status codes 2048"]),
    ("range-off-by-one", &["Parameter *", "Status codes 128"]),
    ("fdef-skips-mcv", &["Command FDEF"]),
    ("lowercase-rejected", &["decision:framing-case"]),
    ("fget-reversed", &["Command FGET"]),
    ("abort-silent", &["Command ^C", "Status codes 16384", "decision:framing-abort-idle"]),
    ("loop-ack-newline", &["Command LOOP"]),
    ("reset-no-banner", &["Command RESET", "decision:seed-banner-text", "decision:bh8-banner-text"]),
    // A parameter the hand ignores: its own effect case, or the RealTime clause that states
    // what the field carries.
    ("dp-ignored", &["Parameter DP"]),
    ("ds-ignored", &["Parameter DS"]),
    ("ct-ignored", &["Parameter CT"]),
    ("ot-ignored", &["Parameter OT"]),
    ("mcv-ignored", &["Parameter MCV"]),
    // MOV sets how fast HI opens: the stall case sees it first.
    ("mov-ignored", &["Parameter MOV", "Command HI"]),
    ("accel-ignored", &["Parameter ACCEL"]),
    ("mpe-default", &["Parameter MPE", "Status codes 16"]),
    ("tstop-ignored", &["Parameter TSTOP"]),
    // MSG is HSG's alias in the seed's words.
    ("hsg-ignored", &["Parameter HSG", "Parameter MSG"]),
    ("lsg-ignored", &["Parameter LSG"]),
    ("hold-ignored", &["Parameter HOLD"]),
    ("bs-ignored", &["Parameter BS"]),
    ("en-ignored", &["Parameter EN"]),
    ("sgflip-ignored", &["Parameter SGFLIP"]),
    ("otemp-ignored", &["Parameter OTEMP", "Status codes 8192"]),
    ("lcvc-ignored", &["Parameter LCVC", "RealTime Control*"]),
    ("lfvc-ignored", &["Parameter LFVC", "RealTime Control*"]),
    ("lfdpc-ignored", &["Parameter LFDPC", "RealTime Control*"]),
    ("lfdpd-ignored", &["Parameter LFDPD", "RealTime Control*"]),
    ("lcv-ignored", &["Parameter LCV", "RealTime Control*"]),
    ("lcpg-ignored", &["Parameter LCPG", "RealTime Control*"]),
    ("lfv-ignored", &["Parameter LFV", "RealTime Control*"]),
    ("lfs-ignored", &["Parameter LFS", "RealTime Control*"]),
    ("lfap-ignored", &["Parameter LFAP", "RealTime Control*"]),
    ("lfdp-ignored", &["Parameter LFDP", "RealTime Control*"]),
    ("lct-ignored", &["Parameter LCT", "RealTime Control*"]),
    ("lfbp-ignored", &["Parameter LFBP", "RealTime Control*"]),
    ("lfain-ignored", &["Parameter LFAIN", "RealTime Control*"]),
    ("lft-ignored", &["Parameter LFT", "RealTime Control*"]),
    ("lcv-unsigned", &["Parameter LCV", "RealTime Control*"]),
    ("fget-p-keeps-reported", &["Parameter LFDP", "RealTime Control*"]),
    // Argument counts and prefixes: the command's own clause or the status it must give.
    ("too-many-args-silent", &["Command *", "Status codes 1024"]),
    ("missing-value-ignored", &["Command FSET", "Command PSET", "decision:framing-missing-value"]),
    ("prefix-not-refused", &["Status codes 4096", "Command *"]),
    ("g-includes-spread", &["Command FGET", "Motor prefixes*"]),
    // Persistence.
    ("reset-keeps-ram", &["Command RESET"]),
    ("fdef-writes-eeprom", &["Command FDEF"]),
    // Status and framing: the status the hand should have given, or the framing decision.
    ("uninitialized-moves", &["Status codes 4"]),
    ("unknown-command-64", &["Status codes 32"]),
    ("unknown-param-128", &["Status codes 64"]),
    ("partial-set-applied", &["decision:framing-line-atomic"]),
    ("tab-not-separator", &["decision:framing-whitespace"]),
    ("empty-line-error", &["decision:framing-empty-line"]),
    ("overlong-line-runs", &["decision:framing-max-line"]),
    ("empty-line-two-prompts", &["decision:framing-empty-line"]),
    // VERS answered with a status: the command's clause, or its text decision.
    ("vers-unknown", &["Command VERS", "decision:seed-vers-text", "decision:bh8-vers-text"]),
];

fn matches(clause: &str, want: &str) -> bool {
    let bare =
        if clause.starts_with("decision:") { clause } else { clause.split_once(": ").map_or(clause, |(_, c)| c) };
    match want.strip_suffix('*') {
        Some(prefix) => bare.starts_with(prefix),
        None => bare == want,
    }
}

/// The most clauses one fault may leave failing (not blocked): one bug is one group, and the
/// cases it blocks on the way (read-backs through a broken command) do not count against
/// their own clauses.
const MOST_FAILING_CLAUSES: usize = 3;

#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace -- --include-ignored)"]
fn the_largest_group_of_failures_names_the_clause_each_fault_breaks() {
    let mut unlisted = Vec::new();
    let mut too_many = Vec::new();
    for f in Fault::ALL {
        // The seed suite first; a fault it cannot see (abort timing) on bh8-262-4.4.
        let mut r = run("seed", vec![*f]);
        if r.groups.is_empty() {
            r = run("bh8-262-4.4", vec![*f]);
        }
        let top = r.groups.first().unwrap_or_else(|| panic!("{f}: no failure groups"));
        assert!(top.cases.len() >= r.groups.iter().map(|g| g.cases.len()).max().unwrap(), "{f}: largest first");
        let grouped: usize = r.groups.iter().map(|g| g.cases.len()).sum();
        let failing = r.cases.iter().filter(|c| c.verdict.fails_run()).count();
        assert_eq!(grouped, failing, "{f}: every failing case is in exactly one group");
        assert!(top.cases.contains(&top.representative) && top.diff.is_some(), "{f}: {top:?}");
        match FAULT_CLAUSES.iter().find(|(n, _)| *n == f.name()) {
            Some((_, want)) => assert!(
                want.iter().any(|w| matches(&top.clause, w)),
                "{f}: the top group names `{}`, expected one of {want:?}: {}",
                top.clause,
                top.summary
            ),
            None => unlisted.push(format!("{f}: top group {}", top.summary)),
        }
        // Blocked cases are those of a group that do not check its clause; they are apart
        // from the failing ones in the clause table.
        for g in &r.groups {
            assert!(g.blocked.iter().all(|b| g.cases.contains(b)), "{f}: blocked cases are the group's");
        }
        let failing_clauses = r.clauses.iter().filter(|c| c.verdict.fails_run() && !c.blocked).count();
        let blocked_clauses = r.clauses.iter().filter(|c| c.blocked).count();
        eprintln!(
            "{:<24} {:>3} failing clauses, {:>3} blocked, {:>2} groups; top: {}",
            f.name(),
            failing_clauses,
            blocked_clauses,
            r.groups.len(),
            top.summary
        );
        if failing_clauses > MOST_FAILING_CLAUSES {
            too_many.push(format!("{f}: {failing_clauses} failing clauses"));
        }
    }
    assert!(too_many.is_empty(), "more than {MOST_FAILING_CLAUSES} failing clauses: {too_many:#?}");
    // A fault added without a line in the table above fails here: a person judges the clause
    // its top group names and records it.
    assert!(unlisted.is_empty(), "no expected clause recorded for:\n{}", unlisted.join("\n"));
}

#[test]
fn fget_reversed_leads_with_one_group_of_reordered_fget_answers() {
    let r = run("seed", vec![Fault::FgetReversed]);
    let top = &r.groups[0];
    assert_eq!((top.command.as_str(), top.kind.as_str()), ("FGET", "order"), "{}", top.summary);
    assert!(top.cases.len() > 100, "{}", top.summary);
    assert!(top.summary.starts_with(&format!("{} cases: FGET: the values come in another order", top.cases.len())));
}

/// With FGET reversed, the cases that read their results back with FGET are blocked by
/// FGET's group: the failing clauses are FGET's alone (they were 86 of 107).
#[test]
fn fget_reversed_fails_fgets_clause_and_blocks_the_read_backs() {
    let r = run("seed", vec![Fault::FgetReversed]);
    let failing: Vec<&str> =
        r.clauses.iter().filter(|c| c.verdict.fails_run() && !c.blocked).map(|c| c.clause.as_str()).collect();
    // (the MCV and MOV effect cases hold motor 2's position as a relation to motor 1's:
    // reversed, the capture takes another motor's value, and the answer is still an order)
    assert!(failing.iter().all(|c| c.contains("FGET")), "{failing:?}");
    assert!(!failing.is_empty());
    assert_eq!(r.groups.len(), 1, "one bug, one group: {:#?}", r.groups.iter().map(|g| &g.summary).collect::<Vec<_>>());
    assert!(r.groups[0].command == "FGET" && r.groups[0].blocked.len() > 100, "{}", r.groups[0].summary);
}

#[test]
fn an_unmutated_hand_has_no_groups() {
    let r = run("seed", vec![]);
    assert!(r.passed() && r.groups.is_empty(), "{:?}", r.groups);
}

/// Blocked cases are shown apart in the console, the JSON report and the HTML page.
#[test]
fn blocked_cases_are_shown_apart_in_console_json_and_html() {
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gcl"))
        .args(["conform", "--target", "sim:seed", "--fault", "fget-reversed", "-q", "--report"])
        .arg(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("blocked cases ("), "{stdout}");
    assert!(stdout.contains("by `seed: Command FGET`: "), "{stdout}");
    let failing = stdout.split("  failing cases:\n").nth(1).unwrap_or_default();
    let failing = failing.split("  blocked cases").next().unwrap_or_default();
    assert!(failing.lines().count() < 10, "the failing list holds FGET's own cases only: {failing}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap()).unwrap();
    assert!(json["groups"][0]["blocked"].as_array().is_some_and(|b| b.len() > 100), "{}", json["groups"][0]);
    assert!(json["clauses"].as_array().unwrap().iter().any(|c| c["blocked"] == true));
    let html = std::fs::read_to_string(dir.path().join("report.html")).unwrap();
    assert!(html.contains("blocked by this group"), "the HTML shows them");
    assert!(html.contains("(blocked)"), "the clause table marks blocked clauses");
}
