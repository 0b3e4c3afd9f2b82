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
use crate::report::page::esc;
use crate::report::page::{Page, details, pre};
use crate::report::svg::{Plot, Series};

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
    /// Coverage features reached as the run went (a point whenever they grew), for the
    /// report's plot; the caller that watches progress fills it.
    #[serde(default)]
    pub coverage_over_time: Vec<CoveragePoint>,
    /// What makes it (a shard of) a campaign: its `--shard`, seed and every option that
    /// changed what ran (`--baseline` and `--skip-decision` among them), and for a merged
    /// folder the shards it holds. Set by the CLI, which knows the options as given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<crate::fuzz::shard::Provenance>,
    /// Why the campaign ended before its budget: a signal (`stopped by SIGTERM after 40 of
    /// 1000 runs`; the caller that heard it fills it), a hand that stopped answering, or
    /// drawn cases all dropped. A campaign that ended so without a new finding has no verdict.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// Who the hand said it was, when it named another firmware than the profile models.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identity: Option<String>,
    /// What the campaign left on a hand outside this process as it found it, checked at the end.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hand_after: Vec<String>,
    /// Failures whose minimized transcript did not fail again the same way on every replay on a
    /// fresh connection: notes, not findings.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_reproduced: Vec<super::NotReproduced>,
}

/// Coverage reached by a time in the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CoveragePoint {
    /// Wall time since the start.
    pub elapsed_ms: u64,
    /// Cases run by then.
    pub runs: u64,
    /// Distinct features reached by then.
    pub features: u64,
}

impl FuzzReport {
    /// The exact command that replays a finding's transcript against the hand it was found on:
    /// the target as given, or for a simulated hand with faults, the simulator with the same
    /// profile and faults behind `exec:` (the `sim` target takes no faults).
    pub fn replay_command(&self, path: &Path) -> String {
        let target = if self.target.starts_with("sim") && !self.faults.is_empty() {
            let faults: String = self.faults.iter().map(|f| format!(" --fault {f}")).collect();
            format!("exec:gcl sim --stdio --profile {}{faults}", self.profile)
        } else {
            self.target.clone()
        };
        crate::report::shell_command(&["gcl", "replay", "--target", &target, &path.display().to_string()])
    }

    /// Whether the run found nothing new (what the baseline or the known failures explain was
    /// known before; the CLI's exit status says the same), ran to the end of its budget, and,
    /// for a merged report, holds every shard of its campaign.
    pub fn passed(&self) -> bool {
        self.findings.iter().all(|f| !f.is_new())
            && self.stopped.is_none()
            && self.merged().is_none_or(|m| m.complete())
    }

    /// The campaign's verdict, in the words of the reference's table (`docs/src/reference.md`,
    /// Verdicts), as the page's banner and the console's `result:` line say it: `FINDINGS`
    /// (new ones), `NO FINDING`, `NO NEW FINDING` (a baseline or known failures explain every
    /// one), `STOPPED` (a signal ended it first), `ERROR` (the hand stopped answering, or no
    /// case could be drawn, first), `INCOMPLETE` (a merge that lacks shards).
    pub fn verdict(&self) -> &'static str {
        let new = self.new_findings();
        let known = self.findings.len() - new;
        match (new, known, &self.stopped) {
            // A merge that lacks shards judged only part of the campaign.
            _ if self.merged().is_some_and(|m| !m.complete()) => "INCOMPLETE",
            (0, _, Some(st)) if st.starts_with("stopped by") => "STOPPED",
            (0, _, Some(_)) => "ERROR",
            (0, 0, None) => "NO FINDING",
            (0, _, None) => "NO NEW FINDING",
            _ => "FINDINGS",
        }
    }

    /// The shards a merged report holds (`None`: not a merge).
    pub fn merged(&self) -> Option<&crate::report::merged::Merged> {
        self.provenance.as_ref().and_then(|p| p.merged.as_ref())
    }

    /// How much the campaign judged, for people: `1200 cases run, 31 drawn cases dropped`.
    pub fn judged(&self) -> String {
        format!(
            "{} cases run, {} drawn cases dropped (the model made no case of them, a skipped decision, or the EEPROM \
             write budget)",
            self.runs, self.dropped
        )
    }

    /// How many findings are new.
    pub fn new_findings(&self) -> usize {
        self.findings.iter().filter(|f| f.is_new()).count()
    }
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
            coverage_over_time: Vec::new(),
            provenance: None,
            stopped: s.dead_hand.clone().or_else(|| s.no_cases.clone()).or_else(|| {
                (s.runs == 0 && !s.interrupted).then(|| "the budget ran out before the first case ran".to_string())
            }),
            identity: s.identity.clone(),
            hand_after: s.hand_after.clone(),
            not_reproduced: s.not_reproduced.clone(),
        }
    }
}

/// JUnit XML: one testcase per distinct finding (each a failure whose message is the finding's
/// one-line summary and whose time is the wall time until it was found), or one passing
/// testcase when nothing was found. Written with quick_xml, as the conformance report's JUnit is.
pub fn to_junit(r: &FuzzReport) -> std::io::Result<String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    w.write_event(Event::Start(BytesStart::new("testsuites")))?;
    let name = format!("gcl fuzz device {}", r.target);
    // A new finding fails; one the baseline or the known failures explain is skipped, saying why.
    let new = r.new_findings();
    // A campaign that ended early without a new finding is an error: it has no verdict.
    let unjudged = new == 0 && r.stopped.is_some();
    let errors = usize::from(r.merged().is_some_and(|m| !m.complete())) + usize::from(unjudged);
    let (tests, failures, skipped) =
        ((r.findings.len().max(1) + errors).to_string(), new.to_string(), (r.findings.len() - new).to_string());
    let errors = errors.to_string();
    let time = format!("{:.3}", r.duration_ms as f64 / 1000.0);
    let mut suite = BytesStart::new("testsuite");
    suite.push_attribute(("name", name.as_str()));
    suite.push_attribute(("tests", tests.as_str()));
    suite.push_attribute(("failures", failures.as_str()));
    suite.push_attribute(("errors", errors.as_str()));
    suite.push_attribute(("skipped", skipped.as_str()));
    suite.push_attribute(("time", time.as_str()));
    w.write_event(Event::Start(suite))?;
    w.write_event(Event::Start(BytesStart::new("properties")))?;
    let mut props = vec![("gcl.verdict", r.verdict().to_string()), ("judged", r.judged())];
    if let Some(st) = &r.stopped {
        props.push(("stopped", st.clone()));
    }
    for (k, v) in &props {
        let mut e = BytesStart::new("property");
        e.push_attribute(("name", *k));
        e.push_attribute(("value", v.as_str()));
        w.write_event(Event::Empty(e))?;
    }
    w.write_event(Event::End(BytesEnd::new("properties")))?;
    // A merge that lacks shards: an error CI shows, whatever was found in the rest.
    if let Some(m) = r.merged().filter(|m| !m.complete()) {
        let mut tc = BytesStart::new("testcase");
        tc.push_attribute(("classname", "gcl.fuzz-device.merge"));
        tc.push_attribute(("name", "fuzz-merge-incomplete"));
        tc.push_attribute(("time", "0.000"));
        w.write_event(Event::Start(tc))?;
        let message = format!("merged from {}", m.describe());
        let mut e = BytesStart::new("error");
        e.push_attribute(("message", message.as_str()));
        e.push_attribute(("type", "incomplete"));
        w.write_event(Event::Empty(e))?;
        w.write_event(Event::End(BytesEnd::new("testcase")))?;
    }
    if unjudged {
        let name = format!("no verdict after {} runs ({} dropped)", r.runs, r.dropped);
        let mut tc = BytesStart::new("testcase");
        tc.push_attribute(("classname", "gcl.fuzz-device"));
        tc.push_attribute(("name", name.as_str()));
        tc.push_attribute(("time", time.as_str()));
        w.write_event(Event::Start(tc))?;
        let message = r.stopped.clone().unwrap_or_default();
        let mut e = BytesStart::new("error");
        e.push_attribute(("message", message.as_str()));
        e.push_attribute(("type", "stopped"));
        w.write_event(Event::Start(e))?;
        w.write_event(Event::Text(BytesText::new(&format!("{message}\n{}\n", r.judged()))))?;
        w.write_event(Event::End(BytesEnd::new("error")))?;
        w.write_event(Event::End(BytesEnd::new("testcase")))?;
    } else if r.findings.is_empty() {
        let passed = format!("no finding in {} runs ({} drawn cases dropped)", r.runs, r.dropped);
        let mut tc = BytesStart::new("testcase");
        tc.push_attribute(("classname", "gcl.fuzz-device"));
        tc.push_attribute(("name", passed.as_str()));
        tc.push_attribute(("time", time.as_str()));
        w.write_event(Event::Empty(tc))?;
    }
    for f in &r.findings {
        let signature = f.signature.to_string();
        let classname = format!("gcl.fuzz-device.{}.{}", if f.is_new() { "new" } else { "known" }, f.signature.kind);
        let t = format!("{:.3}", f.found_after.as_secs_f64());
        let mut tc = BytesStart::new("testcase");
        tc.push_attribute(("classname", classname.as_str()));
        tc.push_attribute(("name", signature.as_str()));
        tc.push_attribute(("time", t.as_str()));
        w.write_event(Event::Start(tc))?;
        let (element, message) = match &f.known {
            None => ("failure", summary_line(f)),
            Some(why) => ("skipped", format!("known ({why}): {}", summary_line(f))),
        };
        let mut failure = BytesStart::new(element);
        failure.push_attribute(("message", message.as_str()));
        failure.push_attribute(("type", f.signature.kind.as_str()));
        w.write_event(Event::Start(failure))?;
        let replay =
            f.path.as_deref().map(|p| format!("run it again: {}\n\n", r.replay_command(p))).unwrap_or_default();
        let body = format!("{replay}{}\n\n{}", f.diff, f.transcript_text);
        w.write_event(Event::Text(BytesText::new(&body)))?;
        w.write_event(Event::End(BytesEnd::new(element)))?;
        w.write_event(Event::End(BytesEnd::new("testcase")))?;
    }
    w.write_event(Event::End(BytesEnd::new("testsuite")))?;
    w.write_event(Event::End(BytesEnd::new("testsuites")))?;
    let mut out = crate::report::junit::xml_chars(String::from_utf8_lossy(&w.into_inner()).into_owned());
    out.push('\n');
    Ok(out)
}

/// ` [INFO: rests on seed-motion-model]` for a finding that binds below MUST: the hand
/// may have decided that open point otherwise. Empty at MUST.
pub fn binding_note(f: &Finding) -> String {
    if f.level == gcl_model::Level::Must {
        return String::new();
    }
    match f.rests_on.as_slice() {
        [] => format!(" [{}]", f.level.as_str()),
        ids => format!(" [{}: rests on {}]", f.level.as_str(), ids.join(", ")),
    }
}

/// `INFO (seed-motion-model)`: the level and what it rests on, for the findings index.
fn level_cell(f: &Finding) -> String {
    if f.rests_on.is_empty() {
        f.level.as_str().to_string()
    } else {
        format!("{} ({})", f.level.as_str(), f.rests_on.join(", "))
    }
}

/// A finding's one-line summary: the command, then expected against actual as its diff shows
/// them (`FGET DP: expected "…", got "…"`), or the diff's first line when it has no such pair.
pub fn summary_line(f: &Finding) -> String {
    let field = |name: &str| {
        f.diff
            .lines()
            .map(str::trim)
            .find_map(|l| l.strip_prefix(name))
            .map(|v| crate::report::diff::clip(v.trim(), 70))
    };
    let whole = |name: &str| f.diff.lines().map(str::trim).find_map(|l| l.strip_prefix(name)).map(str::trim);
    // The replayer's lines show the golden and the answer from the same byte: rebuilt as a
    // report's diff, the summary is the one conform's JUnit and console give.
    if let (Some(e), Some(a)) = (whole("expected:"), whole("actual:"))
        && !e.starts_with('(')
    {
        let hex = !e.starts_with('"');
        let unq = |s: &str| s.trim_matches('"').trim_start_matches('…').to_string();
        let (e, a) = (unq(e), unq(a));
        let common = e
            .char_indices()
            .zip(a.chars())
            .take_while(|((_, x), y)| x == y)
            .last()
            .map_or(0, |((i, c), _)| i + c.len_utf8());
        let step = f
            .diff
            .split("step ")
            .nth(1)
            .and_then(|t| t.split(|c: char| !c.is_ascii_digit()).next())
            .and_then(|n| n.parse().ok())
            .unwrap_or(0);
        let d = crate::report::Diff {
            step,
            offset: common,
            expected: e[common..].trim_start().to_string(),
            actual: a[common..].trim_start().to_string(),
            before: e[..common].trim_end().to_string(),
            golden: e.clone(),
            form: Some(if hex { crate::report::AnswerForm::Hex } else { crate::report::AnswerForm::Text }),
        };
        return crate::report::diff::one_line(&d);
    }
    match (field("expected:"), field("actual:")) {
        (Some(e), Some(a)) => format!("{}: expected {e}, got {a}", f.signature.command),
        _ => first_line(&f.diff).unwrap_or_default().to_string(),
    }
}

fn first_line(diff: &str) -> Option<&str> {
    diff.lines().map(str::trim).find(|l| !l.is_empty())
}

/// The banner's colour, by the highest level of what is new: red for a new finding at MUST or
/// SHOULD, or a campaign that judged nothing or part of the campaign (no verdict); amber when
/// the new findings are all at MAY or INFO (open points a hand may decide otherwise, not a
/// broken rule); green when nothing is new.
fn tone(r: &FuzzReport) -> &'static str {
    let highest = r.findings.iter().filter(|f| f.is_new()).map(|f| f.level).min();
    match highest {
        _ if !r.passed() && r.new_findings() == 0 => "fail",
        None => "pass",
        Some(gcl_model::Level::Must | gcl_model::Level::Should) => "fail",
        Some(gcl_model::Level::May | gcl_model::Level::Info) => "partial",
    }
}

/// The page: the verdict, the options, an index of findings (kind, signature, transcript
/// path, the exact `gcl replay` command), coverage over time and by category, then each
/// finding's diff and transcript, folded.
pub fn to_html(r: &FuzzReport) -> String {
    let new = r.new_findings();
    let known = r.findings.len() - new;
    let secs = r.duration_ms as f64 / 1000.0;
    let mut headline = match (new, known) {
        (0, 0) => format!("no finding in {} runs ({secs:.1} s)", r.runs),
        (0, k) => format!(
            "no new finding in {} runs ({secs:.1} s); {k} known (the baseline or known failures explain them)",
            r.runs
        ),
        (n, 0) => format!("{n} distinct finding(s) in {} runs ({secs:.1} s)", r.runs),
        (n, k) => format!("{n} new distinct finding(s) in {} runs ({secs:.1} s), and {k} known", r.runs),
    };
    if let Some(st) = &r.stopped {
        headline.push_str(&format!("; ended early: {st}"));
    }
    let verdict = r.verdict();
    let headline = match r.merged() {
        Some(m) => format!("{headline}; merged from {}", m.describe()),
        None => headline,
    };
    let mut p = Page::toned(&format!("gcl fuzz device {} on {}", r.profile, r.target), tone(r), verdict, &headline);
    let mut facts: Vec<(String, String)> = Vec::new();
    // Who the hand said it was comes first: it explains every finding the two firmwares differ by.
    if let Some(who) = &r.identity {
        facts.push(("identity".into(), esc(who)));
    }
    facts.extend([
        ("target".into(), format!("<code>{}</code>", esc(&r.target))),
        ("profile".into(), esc(&r.profile)),
        ("judged".into(), format!("{} ({:.1} cases/s)", esc(&r.judged()), r.cases_per_second)),
        ("corpus".into(), format!("{} entries", r.corpus)),
        ("wire".into(), format!("{} bytes; {} EEPROM writes", r.wire_bytes, r.eeprom_writes)),
        ("tool".into(), esc(&r.tool)),
    ]);
    for said in &r.hand_after {
        facts.push(("hand after".into(), esc(said)));
    }
    for n in &r.not_reproduced {
        facts.push((
            "not reproduced".into(),
            format!(
                "{} (failed {} of {} replays on a fresh connection: not a finding)",
                esc(&n.signature),
                n.reproduced,
                n.replays
            ),
        ));
    }
    p.facts(&facts);
    let mut opts: Vec<(String, String)> = Vec::new();
    if !r.faults.is_empty() {
        opts.push(("fault".into(), r.faults.join(", ")));
    }
    opts.push(("seed".into(), r.seed.to_string()));
    if r.jobs > 1 {
        opts.push(("jobs".into(), r.jobs.to_string()));
    }
    if !r.refused.is_empty() {
        opts.push(("no".into(), r.refused.join(", ")));
    }
    if let Some(p) = &r.provenance {
        if let Some(s) = p.shard {
            opts.push(("shard".into(), format!("{s} (shard {} of {})", s.index, s.count)));
        }
        // What else changed what ran or how it was judged, as the campaign recorded it.
        for k in ["baseline", "known-failures", "skip-decision", "runs", "duration", "write-budget", "max-findings"] {
            if let Some(v) = p.options.get(k).filter(|v| *v != "none") {
                opts.push((k.into(), v.clone()));
            }
        }
    }
    p.options(&opts);
    // The findings index: new ones first (they fail the run), then the known ones with why.
    let index = |known: bool| {
        let rows: Vec<(usize, &Finding)> = r.findings.iter().enumerate().filter(|(_, f)| f.is_new() != known).collect();
        if rows.is_empty() {
            return format!("<p>None{}.</p>\n", if known || r.findings.is_empty() { "" } else { " new" });
        }
        let mut t = format!(
            "<table><tr><th>#</th><th>kind</th><th>signature</th><th>level</th><th>first run</th>{}<th>transcript</th><th>run it again</th></tr>\n",
            if known { "<th>known because</th>" } else { "" }
        );
        for (i, f) in rows {
            let why = match &f.known {
                Some(w) if known => format!("<td>{}</td>", esc(w)),
                _ => String::new(),
            };
            let _ = writeln!(
                t,
                "<tr class=\"{}\"><td><a href=\"#finding-{n}\">{n}</a></td><td>{}</td><td>{}</td><td>{}</td><td class=\"n\">{}</td>{why}<td><code>{}</code></td><td>{}</td></tr>",
                if known { "skip" } else { "fail" },
                esc(&f.signature.kind),
                esc(&f.signature.to_string()),
                esc(&level_cell(f)),
                f.run,
                esc(&f.path.as_ref().map_or("not written (no --out)".into(), |p| p.display().to_string())),
                f.path.as_deref().map_or_else(
                    || "<span class=\"muted\">write the transcript with --out</span>".to_string(),
                    |p| format!("<code class=\"cmd\">{}</code>", esc(&r.replay_command(p)))
                ),
                n = i + 1,
            );
        }
        t.push_str("</table>\n");
        t
    };
    // "New" means something only beside known findings.
    p.heading("findings", if known > 0 { "New findings" } else { "Findings" });
    p.push(&index(false));
    if known > 0 {
        p.heading("known", "Known findings");
        p.push(&index(true));
    }
    p.heading("coverage", "Coverage");
    if r.coverage_over_time.len() >= 2 {
        let plot = Plot {
            title: "Model features reached over the run".into(),
            x_label: "seconds".into(),
            y_label: "features".into(),
            series: vec![Series {
                name: "features".into(),
                points: r
                    .coverage_over_time
                    .iter()
                    .map(|c| (c.elapsed_ms as f64 / 1000.0, c.features as f64))
                    .collect(),
                steps: true,
                dots: false,
            }],
            marks: r
                .findings
                .iter()
                .enumerate()
                .map(|(i, f)| (f.found_after.as_secs_f64(), format!("#{}", i + 1)))
                .collect(),
            ..Default::default()
        };
        p.push(&plot.to_svg("fuzz-device-coverage"));
    }
    let mut t = String::from("<table><tr><th>category</th><th>reached</th><th>of</th><th>not reached</th></tr>");
    for c in &r.coverage {
        let _ = write!(
            t,
            "<tr><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td></tr>",
            esc(&c.category),
            c.reached,
            c.total.map_or("-".into(), |t| t.to_string()),
            esc(&c.missing.join(" "))
        );
    }
    t.push_str("</table>\n");
    p.push(&t);
    if !r.findings.is_empty() {
        p.heading("details", "Each finding");
        for (i, f) in r.findings.iter().enumerate() {
            let body = format!(
                "<p>run {}, after {} ms, minimized from {} to {} actions</p>\n<h4>How it parts</h4>\n{}<h4>The minimized transcript (the model's expectations; the preamble folded)</h4>\n{}",
                f.run,
                f.found_after.as_millis(),
                f.original_actions,
                f.actions.len(),
                pre(&f.diff),
                crate::report::html::transcript_view(&f.transcript_text, None, "expect", None)
            ) + &details("the transcript file as written", &pre(&f.transcript_text), false, "", None);
            p.push(&details(
                &format!(
                    "<strong>#{}</strong> {}{}{} <span class=\"muted\">{}</span>",
                    i + 1,
                    if f.is_new() { "" } else { "(known) " },
                    esc(&f.signature.to_string()),
                    esc(&binding_note(f)),
                    esc(&summary_line(f))
                ),
                &body,
                i == 0 && f.is_new(),
                if f.is_new() { "case" } else { "" },
                Some(&format!("finding-{}", i + 1)),
            ));
        }
    }
    p.finish()
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
