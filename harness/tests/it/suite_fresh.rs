//! The committed golden transcripts are exactly what the reference model generates now.
//! When this fails, the model or the catalogue changed: look at the diff, then run
//! `cargo run -- suite regenerate` and commit the result.

use std::path::PathBuf;

use gcl_harness::suite;

fn suite_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(suite::DEFAULT_DIR)
}

#[test]
fn committed_goldens_are_fresh() {
    let cases = suite::generate_all().unwrap_or_else(|e| panic!("{e}"));
    let report = suite::check(&suite_dir(), &cases).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        report.is_fresh(),
        "the committed suite under {} is stale:\n{}\n\nregenerate it with `cargo run -- suite regenerate` \
         (from the repository root) and commit vectors/suite",
        suite_dir().display(),
        report.lines().join("\n")
    );
}

#[test]
fn check_reports_stale_missing_and_extra_files_and_regenerate_fixes_them() {
    let cases: Vec<suite::Case> =
        suite::generate(&gcl_model::Profile::builtin("seed").unwrap()).unwrap().into_iter().take(5).collect();
    let dir = tempfile::tempdir().unwrap();
    let before = suite::regenerate(dir.path(), &cases).unwrap();
    assert_eq!(before.missing.len(), 6, "5 cases and the index");
    assert!(suite::check(dir.path(), &cases).unwrap().is_fresh());

    let stale = dir.path().join(cases[0].rel_path());
    std::fs::write(&stale, cases[0].text().replace("FDEF", "FDEF ")).unwrap();
    std::fs::remove_file(dir.path().join(cases[1].rel_path())).unwrap();
    std::fs::write(dir.path().join("seed").join("old-case.gcl"), "stale").unwrap();
    let r = suite::check(dir.path(), &cases).unwrap();
    assert_eq!(r.stale, vec![cases[0].rel_path()]);
    assert_eq!(r.missing, vec![cases[1].rel_path()]);
    assert_eq!(r.extra, vec![PathBuf::from("seed").join("old-case.gcl")]);
    assert_eq!(r.lines().len(), 3);

    suite::regenerate(dir.path(), &cases).unwrap();
    assert!(suite::check(dir.path(), &cases).unwrap().is_fresh());
    let loaded = suite::load_dir(dir.path()).unwrap();
    let mut want = cases.clone();
    want.sort_by(|a, b| a.id().cmp(b.id()));
    let loaded: Vec<_> = loaded
        .into_iter()
        .map(|mut c| {
            c.transcript = c.transcript.without_lines();
            c
        })
        .collect();
    assert_eq!(loaded, want);
}

#[test]
fn a_misplaced_file_is_an_error() {
    let cases: Vec<suite::Case> =
        suite::generate(&gcl_model::Profile::builtin("seed").unwrap()).unwrap().into_iter().take(1).collect();
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("seed")).unwrap();
    std::fs::write(dir.path().join("seed").join("renamed.gcl"), cases[0].text()).unwrap();
    let e = suite::load_dir(dir.path()).unwrap_err();
    assert!(e.to_string().contains("its id is"), "{e}");
    std::fs::remove_file(dir.path().join("seed").join("renamed.gcl")).unwrap();
    std::fs::create_dir_all(dir.path().join("bh8-262-4.4")).unwrap();
    std::fs::write(dir.path().join("bh8-262-4.4").join(format!("{}.gcl", cases[0].id())), cases[0].text()).unwrap();
    let e = suite::load_dir(dir.path()).unwrap_err();
    assert!(e.to_string().contains("its profiles are seed"), "{e}");
    std::fs::write(dir.path().join("bh8-262-4.4").join(format!("{}.gcl", cases[0].id())), "gcl-transcript 1\nid: x\n")
        .unwrap();
    let e = suite::load_dir(dir.path()).unwrap_err();
    assert!(e.to_string().contains("line 3"), "{e}");
}
