//! Certificate bundles: what `gcl certify` leaves a firmware team to keep, and the tamper
//! check behind `gcl certify --verify`.
//!
//! A bundle is a folder: `certificate.json` (firmware VERS text, profile, suite hash,
//! harness version, date, a verdict per clause), the reports, one actual transcript per
//! case under `transcripts/`, and `MANIFEST.sha256`, which lists the SHA-256 of every other
//! file in the `sha256sum` format, so `sha256sum -c MANIFEST.sha256` checks it too.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::report::{RunReport, Verdict, write_all, write_atomic};

/// The manifest's file name.
pub const MANIFEST: &str = "MANIFEST.sha256";

/// The certificate proper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Certificate {
    /// What the device answered to `VERS` (its lines).
    pub firmware_version: Vec<String>,
    /// The profile certified against.
    pub profile: String,
    /// The target as given.
    pub target: String,
    /// The suite version: SHA-256 over every golden transcript.
    pub suite_hash: String,
    /// `gcl` and its version.
    pub harness_version: String,
    /// When the run started, RFC 3339 UTC.
    pub date: String,
    /// The levels run (MUST and SHOULD).
    pub levels: Vec<String>,
    /// PASS when every case passed (or was a known failure), else FAIL.
    pub verdict: Verdict,
    /// The verdict per spec clause.
    pub clauses: Vec<ClauseVerdict>,
}

/// One clause's verdict in a certificate.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ClauseVerdict {
    /// The clause.
    pub clause: String,
    /// The worst verdict among its cases.
    pub verdict: Verdict,
    /// How many cases check it.
    pub cases: usize,
}

/// SHA-256 of bytes, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

fn safe_name(id: &str) -> String {
    id.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '.' { c } else { '_' }).collect()
}

/// Writes a whole bundle into `dir` (created if needed; it should be empty).
pub fn write_bundle(
    dir: &Path,
    cert: &Certificate,
    report: &RunReport,
    transcripts: &[(String, String)],
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir.join("transcripts"))?;
    write_all(dir, report)?;
    for (id, text) in transcripts {
        write_atomic(&dir.join("transcripts").join(format!("{}.gcl", safe_name(id))), text.as_bytes())?;
    }
    write_atomic(&dir.join("certificate.json"), &serde_json::to_vec_pretty(cert)?)?;
    let mut lines = String::new();
    for rel in files_under(dir)? {
        if rel == MANIFEST {
            continue;
        }
        let bytes = std::fs::read(dir.join(&rel))?;
        lines.push_str(&format!("{}  {}\n", sha256_hex(&bytes), rel));
    }
    write_atomic(&dir.join(MANIFEST), lines.as_bytes())?;
    Ok(())
}

/// Every regular file under `dir`, as `/`-separated relative paths, sorted.
fn files_under(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for e in std::fs::read_dir(dir.join(&rel))? {
            let e = e?;
            let r = rel.join(e.file_name());
            let ty = e.file_type()?;
            if ty.is_dir() {
                stack.push(r);
            } else {
                out.push(
                    r.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect::<Vec<_>>().join("/"),
                );
            }
        }
    }
    out.sort();
    Ok(out)
}

/// One problem `--verify` found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Tamper {
    /// A listed file's content changed.
    Modified(String),
    /// A listed file is gone.
    Missing(String),
    /// A file is in the bundle but not in the manifest.
    Unlisted(String),
    /// The manifest or the certificate does not parse.
    Malformed(String),
}

impl std::fmt::Display for Tamper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Tamper::Modified(p) => write!(f, "modified: {p}"),
            Tamper::Missing(p) => write!(f, "missing: {p}"),
            Tamper::Unlisted(p) => write!(f, "not in the manifest: {p}"),
            Tamper::Malformed(m) => write!(f, "malformed: {m}"),
        }
    }
}

/// Checks a bundle against its manifest. `Ok(cert)` when intact; the problems otherwise.
pub fn verify(dir: &Path) -> anyhow::Result<Result<Certificate, Vec<Tamper>>> {
    let manifest = match std::fs::read_to_string(dir.join(MANIFEST)) {
        Ok(m) => m,
        Err(e) => return Ok(Err(vec![Tamper::Malformed(format!("{MANIFEST}: {e}"))])),
    };
    let mut problems = Vec::new();
    let mut listed = BTreeSet::new();
    for (n, line) in manifest.lines().enumerate() {
        let Some((hash, path)) = line.split_once("  ") else {
            problems.push(Tamper::Malformed(format!("{MANIFEST} line {}: expected `<sha256>  <path>`", n + 1)));
            continue;
        };
        if hash.len() != 64
            || !hash.bytes().all(|b| b.is_ascii_hexdigit())
            || path.contains("..")
            || path.starts_with('/')
        {
            problems.push(Tamper::Malformed(format!("{MANIFEST} line {}", n + 1)));
            continue;
        }
        listed.insert(path.to_string());
        match std::fs::read(dir.join(path)) {
            Ok(bytes) if sha256_hex(&bytes) == hash.to_ascii_lowercase() => {}
            Ok(_) => problems.push(Tamper::Modified(path.to_string())),
            Err(_) => problems.push(Tamper::Missing(path.to_string())),
        }
    }
    for f in files_under(dir)? {
        if f != MANIFEST && !listed.contains(&f) {
            problems.push(Tamper::Unlisted(f));
        }
    }
    if !listed.contains("certificate.json") && !problems.iter().any(|p| matches!(p, Tamper::Missing(_))) {
        problems.push(Tamper::Missing("certificate.json".into()));
    }
    if !problems.is_empty() {
        return Ok(Err(problems));
    }
    let text = std::fs::read_to_string(dir.join("certificate.json"))?;
    match serde_json::from_str::<Certificate>(&text) {
        Ok(c) => Ok(Ok(c)),
        Err(e) => Ok(Err(vec![Tamper::Malformed(format!("certificate.json: {e}"))])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bundle() -> (tempfile::TempDir, Certificate) {
        let dir = tempfile::tempdir().unwrap();
        let report = crate::report::tests::sample();
        let cert = Certificate {
            firmware_version: vec!["BarrettHand Firmware test".into()],
            profile: "seed".into(),
            target: "sim".into(),
            suite_hash: "ab".repeat(32),
            harness_version: "gcl 0.1.0".into(),
            date: "2026-11-22T00:00:00Z".into(),
            levels: vec!["MUST".into(), "SHOULD".into()],
            verdict: Verdict::Fail,
            clauses: report
                .clauses
                .iter()
                .map(|c| ClauseVerdict { clause: c.clause.clone(), verdict: c.verdict, cases: c.cases.len() })
                .collect(),
        };
        write_bundle(dir.path(), &cert, &report, &[("framing-echo".into(), "> HI\\r\n< HI\\n\\r=> \n".into())])
            .unwrap();
        (dir, cert)
    }

    #[test]
    fn an_untouched_bundle_verifies() {
        let (dir, cert) = bundle();
        assert_eq!(verify(dir.path()).unwrap(), Ok(cert));
        let manifest = std::fs::read_to_string(dir.path().join(MANIFEST)).unwrap();
        assert!(manifest.contains("  transcripts/framing-echo.gcl\n"));
        assert!(manifest.contains("  certificate.json\n"));
    }

    #[test]
    fn tampering_is_found() {
        let (dir, _) = bundle();
        let p = dir.path().join("certificate.json");
        let text = std::fs::read_to_string(&p).unwrap().replace("\"FAIL\"", "\"PASS\"");
        std::fs::write(&p, text).unwrap();
        std::fs::remove_file(dir.path().join("junit.xml")).unwrap();
        std::fs::write(dir.path().join("transcripts/extra.gcl"), "x").unwrap();
        let problems = verify(dir.path()).unwrap().unwrap_err();
        assert!(problems.contains(&Tamper::Modified("certificate.json".into())), "{problems:?}");
        assert!(problems.contains(&Tamper::Missing("junit.xml".into())), "{problems:?}");
        assert!(problems.contains(&Tamper::Unlisted("transcripts/extra.gcl".into())), "{problems:?}");
    }
}
