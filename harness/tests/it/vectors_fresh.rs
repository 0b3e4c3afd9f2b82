//! The committed JSON vectors (`vectors/json/<profile>/<kind>.json`) are exactly what the
//! model generates now, and every file validates against its schema in `vectors/schema/`.
//! When the freshness test fails, the model, the generator or the goldens changed (each
//! file's header carries its profile's suite hash): run `cargo run -- suite regenerate`
//! (goldens and vectors) from the repository root and commit the result.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use gcl_harness::{suite, vectors};
use serde_json::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn vectors_dir() -> PathBuf {
    root().join(vectors::DEFAULT_DIR)
}

/// The committed goldens (`suite_fresh` keeps them equal to the generated ones); loading
/// them is cheaper than generating the suite again.
fn committed_cases() -> Vec<suite::Case> {
    suite::load_dir(&root().join(suite::DEFAULT_DIR)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn committed_vectors_are_fresh() {
    let want = vectors::expected_files(&committed_cases()).unwrap_or_else(|e| panic!("{e}"));
    let report = vectors::check(&vectors_dir(), &want).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        report.is_fresh(),
        "the committed JSON vectors under {} are stale:\n{}\n\nregenerate them with `cargo run -- suite regenerate` \
         (from the repository root; it writes the goldens and the vectors) and commit vectors/",
        vectors_dir().display(),
        report.lines().join("\n")
    );
}

#[test]
fn check_reports_stale_missing_and_extra_files_and_regenerate_fixes_them() {
    let p = gcl_model::Profile::builtin("seed").unwrap();
    let want = vectors::profile_files(&p, &"0".repeat(64)).unwrap();
    assert_eq!(want.len(), vectors::Kind::ALL.len());
    let dir = tempfile::tempdir().unwrap();
    let before = vectors::regenerate(dir.path(), &want).unwrap();
    assert_eq!(before.missing.len(), want.len());
    assert!(vectors::check(dir.path(), &want).unwrap().is_fresh());

    let stale = PathBuf::from("seed/grammar.json");
    std::fs::write(dir.path().join(&stale), "{}").unwrap();
    std::fs::remove_file(dir.path().join("seed/host.json")).unwrap();
    std::fs::write(dir.path().join("seed/old.json"), "{}").unwrap();
    let r = vectors::check(dir.path(), &want).unwrap();
    assert_eq!(r.stale, vec![stale]);
    assert_eq!(r.missing, vec![PathBuf::from("seed/host.json")]);
    assert_eq!(r.extra, vec![PathBuf::from("seed/old.json")]);
    vectors::regenerate(dir.path(), &want).unwrap();
    assert!(vectors::check(dir.path(), &want).unwrap().is_fresh());

    // The header carries the suite hash: another suite makes every file stale.
    let other = vectors::profile_files(&p, &"1".repeat(64)).unwrap();
    assert_eq!(vectors::check(dir.path(), &other).unwrap().stale.len(), want.len());
}

fn validator(kind: &str) -> jsonschema::Validator {
    let path = root().join("vectors/schema").join(format!("{kind}.schema.json"));
    let schema: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    jsonschema::validator_for(&schema).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn committed_files() -> Vec<(PathBuf, Value)> {
    let mut out = Vec::new();
    for p in std::fs::read_dir(vectors_dir()).unwrap() {
        let p = p.unwrap().path();
        for f in std::fs::read_dir(&p).unwrap() {
            let f = f.unwrap().path();
            let v: Value = serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
            out.push((f, v));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

/// What the schema cannot say: counts, unique ids, flags that name listed decisions, and
/// `acceptable` exactly when a flagged decision is open (INFO).
fn check_consistency(path: &Path, v: &Value) {
    let tests = v["tests"].as_array().unwrap();
    assert_eq!(v["number_of_tests"].as_u64(), Some(tests.len() as u64), "{}", path.display());
    let mut ids = BTreeSet::new();
    for t in tests {
        let id = t["id"].as_str().unwrap();
        assert!(ids.insert(id), "{}: duplicate id {id}", path.display());
        let open = t["flags"].as_array().unwrap().iter().any(|f| {
            let d = &v["decisions"][f.as_str().unwrap()];
            assert!(d.is_object(), "{}: {id} flags {f}, which the header does not list", path.display());
            d["level"] == "INFO"
        });
        assert_eq!(t["result"] == "acceptable", open, "{}: {id}", path.display());
    }
}

#[test]
fn every_committed_file_validates_against_its_schema() {
    let files = committed_files();
    let kinds: BTreeSet<&str> = files.iter().map(|(_, v)| v["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds.len(), vectors::Kind::ALL.len(), "every kind is committed: {kinds:?}");
    assert_eq!(files.len(), vectors::Kind::ALL.len() * gcl_model::Profile::builtin_names().count());
    for (path, v) in &files {
        let kind = v["kind"].as_str().unwrap_or_else(|| panic!("{}: no kind", path.display()));
        assert_eq!(path.file_stem().and_then(|s| s.to_str()), Some(kind), "{}", path.display());
        let errors: Vec<String> =
            validator(kind).iter_errors(v).take(5).map(|e| format!("{e} at {}", e.instance_path())).collect();
        assert!(errors.is_empty(), "{}: {errors:#?}", path.display());
        check_consistency(path, v);
    }
}

#[test]
fn the_schemas_reject_what_they_should() {
    let p = gcl_model::Profile::builtin("bh8-262-4.4").unwrap();
    for kind in vectors::Kind::ALL {
        let good = vectors::generate_kind(&p, kind, &"a".repeat(64)).unwrap();
        let v = validator(kind.name());
        assert!(v.is_valid(&good), "{}", kind.name());
        let mut bad = good.clone();
        bad["tests"][0]["result"] = "maybe".into();
        assert!(!v.is_valid(&bad), "{}: an unknown result is refused", kind.name());
        let mut bad = good.clone();
        bad["tests"][0].as_object_mut().unwrap().remove("comment");
        assert!(!v.is_valid(&bad), "{}: a test without its comment is refused", kind.name());
        let mut bad = good.clone();
        bad["suite_hash"] = "abc".into();
        assert!(!v.is_valid(&bad), "{}: a malformed suite hash is refused", kind.name());
    }
}

#[test]
fn gcl_vectors_check_and_regenerate_from_the_command_line() {
    let gcl = env!("CARGO_BIN_EXE_gcl");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let out = std::process::Command::new(gcl).args(["vectors", "check", "--dir", d]).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("missing seed/host.json") && stdout.contains("gcl suite regenerate"), "{stdout}");
    let out = std::process::Command::new(gcl).args(["vectors", "regenerate", "--dir", d]).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let out = std::process::Command::new(gcl).args(["vectors", "check", "--dir", d]).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
    // What the command wrote is what the committed files are.
    let want = vectors::expected_files(&committed_cases()).unwrap();
    assert!(vectors::check(dir.path(), &want).unwrap().is_fresh());
}
