//! `--shard K/N` and `gcl fuzz merge`: the shards of a campaign are disjoint slices of it, and
//! their merged folder says what one machine running the same runs says.
//!
//! The host campaign runs a Python mutant (python3 with pyserial; skipped with a line when
//! missing) under misbehaviours whose effect does not depend on timing, so that the same
//! schedule gives the same finding on any machine.

mod deps;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn gcl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_gcl")).args(args).output().unwrap()
}

fn python_ready() -> bool {
    deps::python_with(&["serial"]).is_some()
}

fn json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
}

/// `gcl fuzz host` over the err-table mutant, `extra` added; its folder's layout is the one
/// `gcl fuzz merge` reads (report/, bundles/).
fn host_campaign(dir: &Path, seed: &str, extra: &[&str]) -> std::process::Output {
    let mutant = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/host_mutants/py_err_table.py");
    let (report, out) = (dir.join("report"), dir.join("bundles"));
    let mut args = vec![
        "fuzz",
        "host",
        "--profile",
        "seed",
        "--seed",
        seed,
        "--runs",
        "16",
        // Misbehaviours whose effect on this host does not depend on timing.
        "--ops",
        "err-bits,wrong-echo,garbage",
        // Exit 1 (the host reports a broken hand) is a finding too, so that there are several.
        "--ok-exit-codes",
        "0",
        "--timeout-hang",
        "5s",
        "--report",
        report.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let py = deps::python();
    args.extend_from_slice(&["--", &py, mutant.to_str().unwrap()]);
    gcl(&args)
}

/// A report with what differs between machines (when, how long) taken out.
/// A report without its times, and with the folder it was written under (`root`) replaced by
/// `<out>`: bundle paths and replay commands name the machine's own folder.
fn comparable(r: Value, root: &Path) -> Value {
    let text = serde_json::to_string(&r).unwrap().replace(&root.display().to_string(), "<out>");
    let mut r: Value = serde_json::from_str(&text).unwrap();
    let o = r.as_object_mut().unwrap();
    o.remove("started");
    o.remove("duration_ms");
    // Known gap: the page facts of a host report (`host`: the command as given, ops, paths,
    // minimization runs) are rebuilt by the merge from the shards' fuzz.json, which does not
    // keep them all; the cases, verdicts and transcripts above are compared in full.
    o.remove("host");
    // A finding's time is how long its campaign took to find it, which differs by machine.
    for c in o.get_mut("cases").and_then(Value::as_array_mut).into_iter().flatten() {
        c.as_object_mut().unwrap().remove("duration_ms");
    }
    r
}

fn findings_of(campaign: &Value) -> Vec<Value> {
    campaign["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let mut f = f.clone();
            f.as_object_mut().unwrap().remove("found_after_ms");
            f
        })
        .collect()
}

#[test]
fn merged_host_shards_equal_one_machine_running_the_same_runs() {
    if !python_ready() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    // One machine: the same runs, unguided (what a sharded campaign is).
    let o = host_campaign(&one, "5", &["--no-guidance"]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let shards: Vec<PathBuf> = (1..=4).map(|k| tmp.path().join(format!("shard-{k}"))).collect();
    for (k, dir) in shards.iter().enumerate() {
        let shard = format!("{}/4", k + 1);
        let o = host_campaign(dir, "5", &["--shard", &shard]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{}", String::from_utf8_lossy(&o.stderr));
        // Disjoint: each shard made its share of the runs, and only runs of its own.
        let c = json(&dir.join("report/fuzz.json"));
        assert_eq!(c["runs"], 4, "shard {shard}");
        for f in c["findings"].as_array().unwrap() {
            assert_eq!(f["run"].as_u64().unwrap() % 4, k as u64, "shard {shard} reports run {}", f["run"]);
        }
    }
    let merged = tmp.path().join("merged");
    let mut args = vec!["fuzz", "merge"];
    args.extend(shards.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--out", merged.to_str().unwrap()]);
    let o = gcl(&args);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));

    let (want, got) = (json(&one.join("report/fuzz.json")), json(&merged.join("report/fuzz.json")));
    assert!(want["findings"].as_array().unwrap().len() >= 2, "the campaign should find several things: {want:#}");
    assert_eq!(got["runs"], want["runs"]);
    assert_eq!(findings_of(&got), findings_of(&want));
    assert_eq!(got["fired_at"], want["fired_at"]);
    assert_eq!(
        comparable(json(&merged.join("report/report.json")), &merged),
        comparable(json(&one.join("report/report.json")), &one)
    );
    // The same bundles, each with the merged hit count.
    let names = |d: &Path| {
        let mut v: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    assert_eq!(names(&merged.join("bundles")), names(&one.join("bundles")));
    for b in names(&one.join("bundles")) {
        let (w, g) = (
            json(&one.join("bundles").join(&b).join("finding.json")),
            json(&merged.join("bundles").join(&b).join("finding.json")),
        );
        assert_eq!(g["hits"], w["hits"], "{b}");
        assert_eq!(g["run"], w["run"], "{b}");
        for f in ["schedule.json", "transcript.gcl"] {
            assert_eq!(
                std::fs::read_to_string(merged.join("bundles").join(&b).join(f)).unwrap(),
                std::fs::read_to_string(one.join("bundles").join(&b).join(f)).unwrap(),
                "{b}/{f}"
            );
        }
    }

    // Folders of another campaign are refused, and the same shard twice is caught.
    let other = tmp.path().join("other");
    host_campaign(&other, "6", &["--shard", "2/4"]);
    let o = gcl(&[
        "fuzz",
        "merge",
        shards[0].to_str().unwrap(),
        other.to_str().unwrap(),
        "--out",
        tmp.path().join("x").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("not shards of one campaign"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn device_shards_are_disjoint_and_merge_by_signature_and_content_hash() {
    let tmp = tempfile::tempdir().unwrap();
    let campaign = |dir: &Path, shard: &str| {
        let (report, out, corpus) = (dir.join("report"), dir.join("findings"), dir.join("corpus"));
        let o = gcl(&[
            "fuzz",
            "device",
            "--target",
            "sim:seed",
            "--fault",
            "fget-reversed",
            "--seed",
            "1",
            "--runs",
            "60",
            "--shard",
            shard,
            "--quiet",
            "--report",
            report.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--corpus",
            corpus.to_str().unwrap(),
        ]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{}", String::from_utf8_lossy(&o.stderr));
        json(&report.join("fuzz-device.json"))
    };
    let files = |d: &Path| -> std::collections::BTreeSet<String> {
        std::fs::read_dir(d).map_or_else(
            |_| Default::default(),
            |r| r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect(),
        )
    };
    let (a, b, a2) = (tmp.path().join("a"), tmp.path().join("b"), tmp.path().join("a-again"));
    let (ra, rb, ra2) = (campaign(&a, "1/2"), campaign(&b, "2/2"), campaign(&a2, "1/2"));
    assert_eq!(ra["runs"].as_u64().unwrap() + rb["runs"].as_u64().unwrap(), 60, "the shards share --runs");
    // Deterministic: the same shard twice draws the same cases; the other shard draws others.
    assert_eq!(files(&a.join("corpus")), files(&a2.join("corpus")));
    let signatures = |r: &Value| -> Vec<Value> {
        r["findings"].as_array().unwrap().iter().map(|f| f["signature"].clone()).collect()
    };
    assert_eq!(signatures(&ra), signatures(&ra2));
    assert_ne!(files(&a.join("corpus")), files(&b.join("corpus")));
    let merged = tmp.path().join("merged");
    let o = gcl(&[
        "fuzz",
        "merge",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        a2.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", String::from_utf8_lossy(&o.stderr));
    let m = json(&merged.join("report/fuzz-device.json"));
    // Corpus: the union by content hash (a-again adds nothing new).
    let union: std::collections::BTreeSet<String> =
        files(&a.join("corpus")).union(&files(&b.join("corpus"))).cloned().collect();
    assert_eq!(files(&merged.join("corpus")), union);
    assert_eq!(m["corpus"].as_u64().unwrap() as usize, union.len());
    // Findings: one per signature over all folders.
    let sigs = |r: &Value| -> std::collections::BTreeSet<String> {
        r["findings"].as_array().unwrap().iter().map(|f| f["signature"].to_string()).collect()
    };
    let all: std::collections::BTreeSet<String> = sigs(&ra).union(&sigs(&rb)).cloned().collect();
    assert_eq!(sigs(&m), all);
    assert_eq!(m["findings"].as_array().unwrap().len(), all.len());
    assert!(!all.is_empty(), "fget-reversed should be found in 60 runs");
    for f in m["findings"].as_array().unwrap() {
        let p = PathBuf::from(f["path"].as_str().unwrap());
        assert!(p.starts_with(&merged), "{}", p.display());
        assert!(p.is_file(), "{}", p.display());
    }
    assert!(merged.join("report/junit.xml").is_file());
}
