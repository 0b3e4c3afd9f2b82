//! The reports of a fuzzing run: `fuzz-device.json` (schema in
//! `reports/fuzz-device.schema.json`), `junit.xml` (one testcase per distinct finding) and
//! `fuzz-device.html` (each finding's minimized transcript and how the hand parted from it).
//! Written atomically; nothing is printed here.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, BytesText, Event};
use serde::{Deserialize, Serialize};

use super::coverage::{CoverageRow, table};
use super::{Finding, FuzzError, FuzzOptions, FuzzSummary};
use crate::report::html::esc;

/// The JSON report.
#[derive(Debug, Clone, Serialize, Deserialize)]
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

/// JUnit XML: one testcase per distinct finding (each a failure), or one passing testcase
/// when nothing was found. Written with quick_xml, as the conformance report's JUnit is.
pub fn to_junit(r: &FuzzReport) -> std::io::Result<String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    w.write_event(Event::Start(BytesStart::new("testsuites")))?;
    let name = format!("gcl fuzz device {}", r.target);
    let (tests, failures) = (r.findings.len().max(1).to_string(), r.findings.len().to_string());
    let time = format!("{:.3}", r.duration_ms as f64 / 1000.0);
    let mut suite = BytesStart::new("testsuite");
    suite.push_attribute(("name", name.as_str()));
    suite.push_attribute(("tests", tests.as_str()));
    suite.push_attribute(("failures", failures.as_str()));
    suite.push_attribute(("time", time.as_str()));
    w.write_event(Event::Start(suite))?;
    if r.findings.is_empty() {
        let passed = format!("no finding in {} runs", r.runs);
        let mut tc = BytesStart::new("testcase");
        tc.push_attribute(("classname", "fuzz.device"));
        tc.push_attribute(("name", passed.as_str()));
        w.write_event(Event::Empty(tc))?;
    }
    for f in &r.findings {
        let signature = f.signature.to_string();
        let mut tc = BytesStart::new("testcase");
        tc.push_attribute(("classname", "fuzz.device"));
        tc.push_attribute(("name", signature.as_str()));
        w.write_event(Event::Start(tc))?;
        let mut failure = BytesStart::new("failure");
        failure.push_attribute(("message", signature.as_str()));
        w.write_event(Event::Start(failure))?;
        let body = format!("{}\n\n{}", f.diff, f.transcript_text);
        w.write_event(Event::Text(BytesText::new(&body)))?;
        w.write_event(Event::End(BytesEnd::new("failure")))?;
        w.write_event(Event::End(BytesEnd::new("testcase")))?;
    }
    w.write_event(Event::End(BytesEnd::new("testsuite")))?;
    w.write_event(Event::End(BytesEnd::new("testsuites")))?;
    let mut out = String::from_utf8_lossy(&w.into_inner()).into_owned();
    out.push('\n');
    Ok(out)
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
    let junit = to_junit(r).map_err(|source| FuzzError::Out { path: dir.join("junit.xml"), source })?;
    let files = [
        ("fuzz-device.json", serde_json::to_string_pretty(r).unwrap_or_default() + "\n"),
        ("junit.xml", junit),
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
