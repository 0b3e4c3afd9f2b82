//! The sessions under `testdata/sessions/`: each `.gcl` file is a conversation with a fresh
//! hand, checked answer by answer (see `support::run_session` for the format).

use crate::support;

#[test]
fn every_session_file_holds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/sessions");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "gcl"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "sessions in {}: {files:?}", dir.display());
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        support::run_session(&f.display().to_string(), &text);
    }
}

#[test]
fn check_fails_on_a_wrong_answer() {
    let wrong = std::panic::catch_unwind(|| support::check("seed", &["FGET DP"], &["FGET DP\\n\\r1 1 1 1\\n\\r=> "]));
    assert!(wrong.is_err(), "a wrong expected answer must fail the check");
}
