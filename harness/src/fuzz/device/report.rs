//! The reports of a fuzzing run: `fuzz-device.json` (schema in
//! `reports/fuzz-device.schema.json`), `junit.xml` (one testcase per distinct finding) and
//! `fuzz-device.html` (each finding's minimized transcript and how the hand parted from it).
//! Written atomically; nothing is printed here.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::coverage::{CoverageRow, table};
use super::{Finding, FuzzError, FuzzOptions, FuzzSummary};

/// The JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct FuzzReport {
    /// Format version.
    pub format: u32,
    /// `gcl` and its version.
    pub tool: String,
    /// The target as given.
    pub target: String,
    /// The profile.
    pub profile: String,
    /// Deliberate faults of a sim target.
    pub faults: Vec<String>,
    /// The generator's seed.
    pub seed: u64,
    /// Workers.
    pub jobs: usize,
    /// Wall time.
    pub duration_ms: u64,
    /// Cases run against the target.
    pub runs: u64,
    /// Drawn cases dropped (the model made no case of them, or the write budget was spent).
    pub dropped: u64,
    /// Cases per second, minimization excluded.
    pub cases_per_second: f64,
    /// EEPROM writes made.
    pub eeprom_writes: u64,
    /// Bytes on the wire (both directions) during the cases.
    pub wire_bytes: u64,
    /// Corpus entries at the end.
    pub corpus: usize,
    /// What was refused (`motion`, `realtime`, `eeprom`, `abort-timing`).
    pub refused: Vec<String>,
    /// The coverage table.
    pub coverage: Vec<CoverageRow>,
    /// Distinct findings.
    pub findings: Vec<Finding>,
}

impl FuzzReport {
    /// The report of a run.
    pub fn new(opts: &FuzzOptions, s: &FuzzSummary) -> FuzzReport {
        let a = opts.allowed;
        let refused =
            [("motion", a.motion), ("realtime", a.realtime), ("eeprom", a.eeprom), ("abort-timing", a.abort_timing)]
                .iter()
                .filter(|(_, ok)| !ok)
                .map(|(n, _)| n.to_string())
                .collect();
        FuzzReport {
            format: 1,
            tool: format!("gcl {}", env!("CARGO_PKG_VERSION")),
            target: opts.target.to_string(),
            profile: opts.profile.id.clone(),
            faults: opts.open.faults.iter().map(|f| f.name().to_string()).collect(),
            seed: opts.seed,
            jobs: opts.jobs,
            duration_ms: s.elapsed.as_millis() as u64,
            runs: s.runs,
            dropped: s.dropped,
            cases_per_second: s.cases_per_second(),
            eeprom_writes: s.eeprom_writes,
            wire_bytes: s.wire_bytes,
            corpus: s.corpus,
            refused,
            coverage: table(&opts.profile, &s.features),
            findings: s.findings.clone(),
        }
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
}

/// JUnit XML: one testcase per distinct finding (each a failure), or one passing testcase
/// when nothing was found.
pub fn to_junit(r: &FuzzReport) -> String {
    let mut s = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let n = r.findings.len().max(1);
    let _ = writeln!(
        s,
        "<testsuites><testsuite name=\"gcl fuzz device {}\" tests=\"{n}\" failures=\"{}\" time=\"{:.3}\">",
        esc(&r.target),
        r.findings.len(),
        r.duration_ms as f64 / 1000.0
    );
    if r.findings.is_empty() {
        let _ = writeln!(s, "<testcase classname=\"fuzz.device\" name=\"no finding in {} runs\"/>", r.runs);
    }
    for f in &r.findings {
        let _ = writeln!(
            s,
            "<testcase classname=\"fuzz.device\" name=\"{}\"><failure message=\"{}\">{}</failure></testcase>",
            esc(&f.signature.to_string()),
            esc(&f.signature.to_string()),
            esc(&format!("{}\n\n{}", f.diff, f.transcript_text))
        );
    }
    s.push_str("</testsuite></testsuites>\n");
    s
}

/// A self-contained HTML page: summary, coverage table, each finding's transcript and diff.
pub fn to_html(r: &FuzzReport) -> String {
    let mut s = String::from("<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>gcl fuzz device</title>");
    s.push_str("<style>body{font-family:sans-serif;margin:2em}pre{background:#f4f4f4;padding:1em;overflow:auto}td,th{padding:2px 8px;text-align:left}</style></head><body>");
    let _ = write!(
        s,
        "<h1>gcl fuzz device</h1><p>target <code>{}</code>, profile {}, seed {}, {} runs in {:.1} s ({:.1} cases/s), {} distinct findings</p>",
        esc(&r.target),
        esc(&r.profile),
        r.seed,
        r.runs,
        r.duration_ms as f64 / 1000.0,
        r.cases_per_second,
        r.findings.len()
    );
    s.push_str("<h2>Coverage</h2><table><tr><th>category</th><th>reached</th><th>of</th><th>not reached</th></tr>");
    for c in &r.coverage {
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&c.category),
            c.reached,
            c.total.map_or("-".into(), |t| t.to_string()),
            esc(&c.missing.join(" "))
        );
    }
    s.push_str("</table><h2>Findings</h2>");
    for f in &r.findings {
        let _ = write!(
            s,
            "<h3>{}</h3><p>run {}, after {} ms, minimized from {} to {} actions</p><h4>How it parts</h4><pre>{}</pre><h4>Transcript</h4><pre>{}</pre>",
            esc(&f.signature.to_string()),
            f.run,
            f.found_after.as_millis(),
            f.original_actions,
            f.actions.len(),
            esc(&f.diff),
            esc(&f.transcript_text)
        );
    }
    s.push_str("</body></html>\n");
    s
}

/// Writes `fuzz-device.json`, `junit.xml` and `fuzz-device.html` into `dir`.
pub fn write_all(dir: &Path, r: &FuzzReport) -> Result<Vec<PathBuf>, FuzzError> {
    let files = [
        ("fuzz-device.json", serde_json::to_string_pretty(r).unwrap_or_default() + "\n"),
        ("junit.xml", to_junit(r)),
        ("fuzz-device.html", to_html(r)),
    ];
    let mut out = Vec::new();
    for (name, text) in files {
        let path = dir.join(name);
        crate::report::write_atomic(&path, text.as_bytes())
            .map_err(|source| FuzzError::Out { path: path.clone(), source })?;
        out.push(path);
    }
    Ok(out)
}

/// The JSON schema of `fuzz-device.json`.
pub const SCHEMA: &str = include_str!("../../../../reports/fuzz-device.schema.json");
