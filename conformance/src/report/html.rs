//! The HTML page of a [`RunReport`] (`gcl conform`, `gcl certify`, `gcl fuzz host`, `gcl
//! check-host`), in the one design of [`super::page`]: the verdict first, then the options
//! that changed what ran, then the root causes (or findings), then the details, each failure
//! folded with its diff, its decoded RealTime fields and plot, and its transcript with the
//! preamble collapsed and the failing step marked. No scripts, no external resources.

use std::collections::BTreeMap;
use std::fmt::Write;

use gcl_transcript::{Form, Level, Transcript};

use super::diff::{self, FieldRow};
use super::page::{Page, details, esc, pre};
use super::svg::{Band, Plot, Series};
use super::{CaseResult, ReportKind, RunReport, Verdict};

fn class(v: Verdict) -> &'static str {
    match v {
        Verdict::Pass => "pass",
        Verdict::Skip | Verdict::Xfail => "skip",
        _ => "fail",
    }
}

/// How a verdict reads on a page of this kind: a host clause that did not apply is "not
/// exercised", not SKIP.
fn verdict_word(kind: ReportKind, v: Verdict) -> &'static str {
    match (kind.is_host(), v) {
        (true, Verdict::Skip) => "not exercised",
        _ => v.as_str(),
    }
}

/// The anchor of a case's failure section.
fn fail_anchor(id: &str) -> String {
    format!("fail-{id}")
}

fn failing(c: &CaseResult) -> bool {
    c.verdict.fails_run() || c.verdict == Verdict::Xfail
}

/// The verdict of a hand's run as its page shows it: the word, the tone and the line under
/// the title, all from [`RunReport::outcome`], the one verdict every output shows.
fn hand_verdict(r: &RunReport) -> (&'static str, &'static str, String) {
    let o = r.outcome();
    let rest = o.verdict.strip_prefix(o.word).unwrap_or_default().trim_start_matches(':').trim();
    let rest = rest.strip_prefix('(').and_then(|x| x.strip_suffix(')')).unwrap_or(rest);
    let headline = match (o.word, rest.is_empty()) {
        (_, true) => o.detail.clone(),
        ("PARTIAL", false) => format!("{rest}; {}", o.detail),
        (_, false) => format!("{}; {rest}", o.detail),
    };
    let mut tone = match o.word {
        "PASS" => "pass",
        "PARTIAL" => "partial",
        _ => "fail",
    };
    // An unsigned certificate says so first: nothing shows who made it.
    let unsigned = r.kind == ReportKind::Certify && r.certificate.as_ref().is_some_and(|c| c.signed_by.is_none());
    let headline = if unsigned {
        if tone == "pass" {
            tone = "partial";
        }
        format!("UNSIGNED certificate: nothing shows who made it (sign it with --key); {headline}")
    } else {
        headline
    };
    (o.word, tone, headline)
}

/// The one line under the title of a host report.
fn headline(r: &RunReport) -> String {
    let bad: Vec<&CaseResult> = r.cases.iter().filter(|c| c.verdict.fails_run()).collect();
    let what = if r.kind == ReportKind::CheckHost { "clauses" } else { "cases" };
    let cannot_test =
        r.stopped.as_ref().filter(|st| st.cause == crate::report::StopCause::CannotTest).map(|st| st.message.as_str());
    // A host session that judged nothing says why, first.
    let session = r.cases.iter().find(|c| c.id == super::SESSION_CASE && c.verdict == Verdict::Error);
    let mut s = match (r.kind, bad.len()) {
        (ReportKind::CheckHost, _) if session.is_some() => {
            session.and_then(|c| c.message.clone()).unwrap_or_else(|| "nothing judged".into())
        }
        // A campaign that could not test says why, and only that.
        (ReportKind::FuzzHost, _) if cannot_test.is_some() => cannot_test.unwrap_or_default().to_string(),
        (ReportKind::FuzzHost, _) => {
            let runs = r.host.as_ref().map_or(0, |h| h.runs);
            let n = r.host.as_ref().map_or(bad.len(), |h| h.findings.len());
            let judged = r.judged().unwrap_or_default();
            let mut s = if n == 0 {
                format!("no finding in {runs} runs against a misbehaving hand ({judged})")
            } else {
                format!("{n} distinct finding(s) in {runs} runs ({judged})")
            };
            if let Some(m) = r.host.as_ref().and_then(|h| h.merged.as_ref()) {
                s.push_str(&format!("; merged from {}", m.describe()));
            }
            s
        }
        (_, 0) if r.ran() == 0 => "nothing ran".to_string(),
        (_, 0) => format!("every one of the {} {what} that ran passed", r.ran()),
        (_, n) => {
            let mut by_level: BTreeMap<Level, usize> = BTreeMap::new();
            for c in &bad {
                *by_level.entry(c.level.parse().unwrap_or(Level::Info)).or_default() += 1;
            }
            let levels: Vec<String> = by_level.iter().map(|(l, n)| format!("{l} {n}")).collect();
            let mut s = match super::verdict_counts(&bad) {
                Some(words) => format!("{n} of {} {what} did not pass ({words})", r.cases.len()),
                None => format!("{n} of {} {what} fail", r.cases.len()),
            };
            if !r.kind.is_host() {
                s.push_str(&format!(" ({})", levels.join(", ")));
            }
            if !r.groups.is_empty() {
                s.push_str(&format!("; {} likely root cause(s)", r.groups.len()));
            }
            s
        }
    };
    if r.kind == ReportKind::CheckHost
        && let Some(j) = r.judged()
    {
        s.push_str(&format!("; {j}"));
    }
    if let Some(st) = r.stopped.as_ref().filter(|_| cannot_test.is_none()) {
        s.push_str(&format!("; ended early: {}", st.message));
    }
    if !r.kind.is_host() && (!r.liveness.before || !r.liveness.after) {
        s.push_str("; the hand did not answer the liveness probe");
    }
    s
}

/// The title: the command and what it judged.
fn title(r: &RunReport) -> String {
    match (r.kind, &r.host) {
        (k, Some(h)) if k.is_host() => {
            format!("{}: {}", k.command(), diff::clip(&super::shell_command(&h.command), 80))
        }
        (k, _) if k.is_host() => format!("{}: {}", k.command(), r.target.trim_start_matches("host: ")),
        (ReportKind::Certify, _) => format!("gcl certify: the certificate of {} on {}", profile_name(r), r.target),
        (k, _) => format!("{} {} on {}", k.command(), profile_name(r), r.target),
    }
}

/// The profile as a hand's page names it: a built-in's id, or the file it came from.
fn profile_name(r: &RunReport) -> String {
    r.profile_spec.as_ref().map_or_else(|| r.profile.clone(), |p| p.name.clone())
}

fn facts(r: &RunReport) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = Vec::new();
    if r.kind.is_host() {
        if let Some(h) = &r.host {
            v.push(("host command".into(), format!("<code>{}</code>", esc(&super::shell_command(&h.command)))));
        } else {
            v.push(("host command".into(), format!("<code>{}</code>", esc(r.target.trim_start_matches("host: ")))));
        }
        v.push(("simulated hand".into(), format!("profile {}", esc(&r.profile))));
        if let Some(h) = &r.host {
            if r.kind == ReportKind::FuzzHost {
                v.push(("runs".into(), format!("{} (+{} to minimize)", h.runs, h.minimize_runs)));
            }
            if let Some(j) = r.judged() {
                v.push(("judged".into(), esc(&j)));
            }
            for (k, val) in &h.facts {
                v.push((k.clone(), esc(val)));
            }
        }
    } else {
        if let Some(c) = &r.certificate {
            v.push((
                "certificate".into(),
                format!(
                    "this page is the report of a certificate bundle (<code>certificate.json</code>, the transcripts, \
<code>MANIFEST.sha256</code>); the certificate's verdict: <strong>{}</strong>",
                    esc(&r.outcome().verdict)
                ),
            ));
            v.push(("firmware (VERS)".into(), format!("<code>{}</code>", esc(&c.firmware_version.join(" / ")))));
            v.push((
                "signed by".into(),
                match &c.signed_by {
                    Some(k) => format!("the key with fingerprint <code>{}</code> (<code>MANIFEST.sig</code>)", esc(k)),
                    None => "nobody: the bundle is unsigned, so nothing says who made it".into(),
                },
            ));
        }
        v.push(("target".into(), format!("<code>{}</code>", esc(&r.target))));
        v.push((
            "profile".into(),
            match &r.profile_spec {
                Some(p) => format!(
                    "{} <span class=\"muted\">(spec sha256 <code>{}</code>)</span>",
                    esc(&p.label()),
                    esc(&p.sha256)
                ),
                None => esc(&r.profile),
            },
        ));
        v.push(("levels run".into(), esc(&r.level)));
        if let Some(p) = &r.preflight {
            v.push(("pre-flight".into(), esc(p.trim_start_matches("pre-flight: "))));
        }
        v.push((
            "liveness probe".into(),
            format!(
                "{} before, {} after",
                if r.liveness.before { "answered" } else { "no answer" },
                if r.liveness.after { "answered" } else { "no answer" }
            ),
        ));
        v.push(("suite".into(), format!("<code>{}</code>", esc(&r.suite_hash))));
    }
    v.push(("started".into(), esc(&r.started)));
    v.push(("duration".into(), duration(r.duration_ms)));
    v.push(("tool".into(), esc(&r.tool)));
    v
}

/// A wall time for people: milliseconds under a second, else seconds.
pub(crate) fn duration(ms: f64) -> String {
    if ms < 1000.0 { format!("{ms:.0} ms") } else { format!("{:.1} s", ms / 1000.0) }
}

fn options(r: &RunReport) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = r.options.pairs().into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    if let Some(h) = r.host.as_ref().filter(|_| r.kind.is_host()) {
        v.push(("seed".into(), h.seed.to_string()));
        if r.kind == ReportKind::FuzzHost {
            v.push(("ops".into(), if h.ops.is_empty() { "every operator".into() } else { h.ops.join(", ") }));
        }
    } else if let Some(seed) = r.options.seed.filter(|s| *s != 0) {
        v.push(("seed".into(), seed.to_string()));
    }
    v
}

/// The MUST/SHOULD/MAY/INFO × verdict table.
fn level_table(r: &RunReport) -> String {
    let mut by_level: BTreeMap<Level, BTreeMap<Verdict, usize>> = BTreeMap::new();
    for c in &r.cases {
        *by_level.entry(c.level.parse().unwrap_or(Level::Info)).or_default().entry(c.verdict).or_default() += 1;
    }
    let mut h = String::from("<table id=\"levels\"><tr><th>level</th><th>cases</th>");
    for v in Verdict::ALL {
        let _ = write!(h, "<th>{v}</th>");
    }
    h.push_str("</tr>\n");
    for l in [Level::Must, Level::Should, Level::May, Level::Info] {
        let counts = by_level.get(&l).cloned().unwrap_or_default();
        let total: usize = counts.values().sum();
        let bad = counts.iter().any(|(v, n)| v.fails_run() && *n > 0);
        let _ = write!(
            h,
            "<tr class=\"{}\"><th>{l}</th><td class=\"n\">{total}</td>",
            if total == 0 {
                "skip"
            } else if bad {
                "fail"
            } else {
                "pass"
            }
        );
        for v in Verdict::ALL {
            let n = counts.get(&v).copied().unwrap_or(0);
            let _ = write!(h, "<td class=\"n\">{}</td>", if n == 0 { String::new() } else { n.to_string() });
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    h
}

/// The highest level among the cases that check a clause.
fn clause_level<'a>(r: &'a RunReport, cases: &[String]) -> Option<Level> {
    let by_id: BTreeMap<&'a str, &'a CaseResult> = r.cases.iter().map(|c| (c.id.as_str(), c)).collect();
    cases.iter().filter_map(|id| by_id.get(id.as_str())).filter_map(|c| c.level.parse().ok()).min()
}

fn case_link(r: &RunReport, id: &str) -> String {
    let bad = r.cases.iter().any(|c| c.id == id && failing(c));
    let target = if bad { fail_anchor(id) } else { id.to_string() };
    format!("<a href=\"#{}\">{}</a>", esc(&target), esc(id))
}

/// Renders the run as one HTML page.
pub fn to_html(r: &RunReport) -> String {
    let ok = r.passed();
    let mut p = if r.kind.is_host() {
        // A merge that lacks shards judged only part of the campaign: never NO FINDING.
        Page::new(&title(r), ok, &r.verdict_line(), &headline(r))
    } else {
        let (word, tone, headline) = hand_verdict(r);
        Page::toned(&title(r), tone, word, &headline)
    };
    p.facts(&facts(r));
    p.options(&options(r));

    if r.kind == ReportKind::FuzzHost {
        fuzz_host_sections(&mut p, r);
    } else if !r.kind.is_host() {
        p.heading("levels", "Cases by level");
        p.push(&level_table(r));
    }

    root_causes(&mut p, r);

    if let Some(w) = r.wire.as_ref().filter(|w| w.refuted()) {
        p.heading("wire", "Wire time");
        p.push(&format!("<p>{}.</p>\n", esc(&w.refuted_text())));
    } else if let Some(w) = &r.wire {
        p.heading("wire", "Wire time");
        p.push(&format!(
            "<p>Lower bound {:.0} ms over the {} PASS/FAIL cases (a passing case: its pauses plus the \
larger of its bytes sent and, step by step, the larger of the bytes received and the model's motion, at {} baud; a \
failing case: its bytes one way; {} bytes sent, {} received, motion \
{:.0} ms) and, by the same rule, the {:.0} ms of the pre-flight and the motion-time probe before them; the whole \
run, probes included, took {:.0} ms, ratio {:.2}.</p>\n",
            w.lower_bound_ms,
            w.counted_cases,
            w.baud,
            w.bytes_sent,
            w.bytes_received,
            w.motion_ms,
            w.probes_ms,
            w.actual_ms,
            w.ratio
        ));
    }

    let goldens = goldens_for(r);
    failures(&mut p, r, &goldens);

    let realtime: Vec<&CaseResult> = r.cases.iter().filter(|c| goldens.contains_key(c.id.as_str())).collect();
    if !realtime.is_empty() {
        p.heading("realtime", "RealTime cases, block by block");
        p.push("<p>Each RealTime case's feedback per block: every motor's position, velocity, strain and the other fields its layout sends, with the golden's accepted range shaded behind the values the hand sent. A failing case's plots are with its failure, marked where it fails.</p>\n");
        let (bad, good): (Vec<&CaseResult>, Vec<&CaseResult>) = realtime.iter().partition(|c| failing(c));
        if !bad.is_empty() {
            // Those that fail on their own by name; the blocked ones are with their root cause.
            let blocked = r.blocked();
            let (held, own): (Vec<&&CaseResult>, Vec<&&CaseResult>) =
                bad.iter().partition(|c| blocked.contains(c.id.as_str()));
            let links: Vec<String> = own.iter().map(|c| case_link(r, &c.id)).collect();
            let mut line = format!("<p>Failing, plotted with their failures: {}", links.join(" "));
            if !held.is_empty() {
                let _ = write!(
                    line,
                    "{}{} blocked by a root cause (plotted under <a href=\"#failures\">Failures</a>, folded by root cause)",
                    if own.is_empty() { "" } else { "; " },
                    held.len()
                );
            }
            p.push(&format!("{line}</p>\n"));
        }
        for c in good {
            let (Some(g), Some(t)) = (goldens.get(c.id.as_str()), c.transcript.as_deref()) else { continue };
            let (plots, blocks, fields) = realtime_plots(r, c, g, t, 0);
            if plots.is_empty() {
                continue;
            }
            p.push(&details(
                &format!(
                    "<strong>{}</strong> <code>{}</code> {} block(s): {} <span class=\"muted\">{}</span>",
                    verdict_word(r.kind, c.verdict),
                    esc(&c.id),
                    blocks,
                    esc(&fields.join(", ")),
                    esc(&c.title)
                ),
                &plots,
                false,
                "",
                Some(&format!("rt-case-{}", c.id)),
            ));
        }
    }

    if r.kind == ReportKind::CheckHost {
        p.heading("clauses", "Clauses");
        p.push(&cases_table(r));
    } else if r.kind == ReportKind::FuzzHost {
        // The findings index and their details say it all; a case table would repeat them.
    } else {
        p.heading("clauses", "Clause coverage");
        p.push(&details(
            &format!("{} clauses, each with the highest level among its cases and its worst verdict", r.clauses.len()),
            &clause_table(r),
            !ok && r.clauses.len() <= 40,
            "",
            None,
        ));
        p.heading("cases", "Every case");
        p.push(&details(&format!("{} cases", r.cases.len()), &cases_table(r), false, "", None));
    }
    p.finish()
}

/// The root-cause groups, largest first: each with its diff, its clause, and the cases it
/// blocks (listed when they are a few, else a link to where they are folded under Failures).
fn root_causes(p: &mut Page, r: &RunReport) {
    if r.groups.is_empty() {
        return;
    }
    p.heading("root-causes", "Root causes first");
    p.push("<p>Failures grouped by where they part from their goldens (the command answered, the kind of difference), largest first; each names the clause of its smallest failing case.</p>\n");
    for (i, g) in r.groups.iter().enumerate() {
        let mut body = format!(
            "<p>command <code>{}</code>, difference: {}, likely clause: <strong>{}</strong>, representative: {}</p>\n",
            esc(&g.command),
            esc(&g.kind),
            esc(&g.clause),
            case_link(r, &g.representative)
        );
        if let Some(d) = &g.diff {
            body.push_str(&pre(&diff::aligned(d)));
        }
        if !g.blocked.is_empty() {
            let folded = format!("folded under <a href=\"#{}\">Failures</a>", blocked_anchor(i));
            let listed = if g.blocked.len() <= FEW {
                let blocked: Vec<String> = g.blocked.iter().map(|id| case_link(r, id)).collect();
                format!(": {} ({folded})", blocked.join(" "))
            } else {
                format!(", {folded}")
            };
            body.push_str(&format!(
                "<p class=\"blocked\">{} blocked by this group (they fail on its clause's bug, not their own){listed}.</p>\n",
                g.blocked.len(),
            ));
        }
        let members: Vec<String> = g.cases.iter().map(|id| case_link(r, id)).collect();
        body.push_str(&details(
            &format!("the {} case(s) of this group", g.cases.len()),
            &format!("<p>{}</p>\n", members.join(" ")),
            g.cases.len() <= FEW,
            "members",
            None,
        ));
        let line = g.diff.as_ref().map(diff::one_line).unwrap_or_default();
        p.push(&details(
            &format!("<strong>{}</strong> <span class=\"muted\">{}</span>", esc(&g.summary), esc(&line)),
            &body,
            i < 3,
            "",
            Some(&format!("group-{}", i + 1)),
        ));
    }
}

/// How many cases a list shows open; more are folded.
const FEW: usize = 12;

/// The anchor of the folded list of the cases group `i` (from 0) blocks.
fn blocked_anchor(i: usize) -> String {
    format!("blocked-{}", i + 1)
}

/// Every failing case folded with its diff, transcript and plots: first those that fail on
/// their own, one line each; then, folded under one line per root cause, the cases it
/// blocks (a bug in the prompt blocks every case of the suite: 353 identical lines would
/// bury the one that matters).
fn failures(p: &mut Page, r: &RunReport, goldens: &BTreeMap<&str, Transcript>) {
    let failures: Vec<&CaseResult> = r.cases.iter().filter(|c| failing(c)).collect();
    if failures.is_empty() {
        return;
    }
    let label = if r.kind == ReportKind::FuzzHost { "Findings in detail" } else { "Failures" };
    p.heading("failures", label);
    let mut preambles = Vec::new();
    // A window plot for each group's representative and each failure of a small group
    // (or none): the members of a large group part the same way as their representative.
    let big: std::collections::BTreeSet<&str> = r
        .groups
        .iter()
        .filter(|g| g.cases.len() > 10)
        .flat_map(|g| g.cases.iter().filter(|id| **id != g.representative).map(String::as_str))
        .collect();
    let blocked = r.blocked();
    let own: Vec<&&CaseResult> = failures.iter().filter(|c| !blocked.contains(c.id.as_str())).collect();
    if !blocked.is_empty() {
        p.push(&format!(
            "<p>{} case(s) fail on their own; {} more are blocked by a root cause (they fail on its clause's bug, not their own), folded under it below.</p>\n",
            own.len(),
            failures.len() - own.len()
        ));
    }
    for c in own {
        let plot = !big.contains(c.id.as_str());
        p.push(&failure_view(r, c, goldens.get(c.id.as_str()), &mut preambles, plot));
    }
    for (i, g) in r.groups.iter().enumerate().filter(|(_, g)| !g.blocked.is_empty()) {
        let mut body = String::new();
        for c in failures.iter().filter(|c| g.blocked.contains(&c.id)) {
            let plot = !big.contains(c.id.as_str());
            body.push_str(&failure_view(r, c, goldens.get(c.id.as_str()), &mut preambles, plot));
        }
        let line = g.diff.as_ref().map(diff::one_line).unwrap_or_else(|| g.summary.clone());
        p.push(&details(
            &format!(
                "<strong>{} blocked</strong> by root cause <a href=\"#group-{}\">{}</a>, clause <code>{}</code> <span class=\"muted\">{}</span>",
                g.blocked.len(),
                i + 1,
                i + 1,
                esc(&g.clause),
                esc(&line)
            ),
            &body,
            false,
            "blocked",
            Some(&blocked_anchor(i)),
        ));
    }
    if !preambles.is_empty() {
        p.heading("preambles", "Preambles");
        p.push("<p>The steps that bring the hand to a known state before a case's check, as the failing cases above ran them (shown once each).</p>\n");
        for (i, text) in preambles.iter().enumerate() {
            p.push(&details(
                &format!("preamble {}", i + 1),
                &format!("<pre class=\"step\">{}</pre>\n", esc(text)),
                false,
                "",
                Some(&format!("preamble-{}", i + 1)),
            ));
        }
    }
}

fn clause_table(r: &RunReport) -> String {
    let mut h = String::from("<table><tr><th>clause</th><th>level</th><th>verdict</th>");
    for v in Verdict::ALL {
        let _ = write!(h, "<th>{v}</th>");
    }
    h.push_str("<th>cases</th></tr>\n");
    for c in &r.clauses {
        let level = clause_level(r, &c.cases).map(|l| l.as_str()).unwrap_or("");
        let _ = write!(
            h,
            "<tr class=\"{}\"><td>{}</td><td>{level}</td><td>{}</td>",
            class(c.verdict),
            esc(&c.clause),
            if c.blocked { format!("{} (blocked)", c.verdict) } else { c.verdict.to_string() }
        );
        for v in Verdict::ALL {
            let n = r.cases.iter().filter(|k| k.verdict == v && k.clauses.contains(&c.clause)).count();
            let _ = write!(h, "<td class=\"n\">{}</td>", if n == 0 { String::new() } else { n.to_string() });
        }
        let links: Vec<String> = c.cases.iter().map(|id| case_link(r, id)).collect();
        let _ = writeln!(h, "<td>{}</td></tr>", links.join(" "));
    }
    h.push_str("</table>\n");
    h
}

fn cases_table(r: &RunReport) -> String {
    if r.kind.is_host() {
        // A host clause has no level to filter by and no time of its own.
        let mut h = String::from("<table><tr><th>clause</th><th>what it asks</th><th>verdict</th><th>why</th></tr>\n");
        for c in &r.cases {
            let id = if failing(c) { case_link(r, &c.id) } else { esc(&c.id) };
            let _ = writeln!(
                h,
                "<tr class=\"{}\" id=\"{}\"><td>{id}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                class(c.verdict),
                esc(&c.id),
                esc(&c.title),
                verdict_word(r.kind, c.verdict),
                esc(c.message.as_deref().unwrap_or(""))
            );
        }
        h.push_str("</table>\n");
        return h;
    }
    // A certificate bundle keeps every case's exchange beside the page, in `transcripts/`.
    let bundle = r.kind == ReportKind::Certify;
    let mut h = format!(
        "<table><tr><th>id</th><th>title</th><th>level</th><th>verdict</th><th>ms</th><th>why</th>{}</tr>\n",
        if bundle { "<th>transcript</th>" } else { "" }
    );
    for c in &r.cases {
        let id = if failing(c) { case_link(r, &c.id) } else { esc(&c.id) };
        let transcript = match (bundle, c.verdict) {
            (false, _) => String::new(),
            (true, Verdict::Skip) => "<td class=\"muted\">not run</td>".to_string(),
            (true, _) => {
                let file = format!("transcripts/{}.gcl", super::safe_name(&c.id));
                format!("<td><a href=\"{}\">{}</a></td>", esc(&file), esc(&file))
            }
        };
        let _ = writeln!(
            h,
            "<tr class=\"{}\" id=\"{}\"><td>{id}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"n\">{:.1}</td><td>{}</td>{transcript}</tr>",
            class(c.verdict),
            esc(&c.id),
            esc(&c.title),
            esc(&c.level),
            verdict_word(r.kind, c.verdict),
            c.duration_ms,
            esc(c.message.as_deref().unwrap_or(""))
        );
    }
    h.push_str("</table>\n");
    h
}

/// The goldens of the cases that answer RealTime blocks and kept their exchange (every
/// RealTime case, passing or failing), from the suite the model generates for the report's
/// profile: the plots need every block's golden, and the report keeps only the failing step's.
fn goldens_for(r: &RunReport) -> BTreeMap<&str, Transcript> {
    if r.kind.is_host() || !r.cases.iter().any(|c| c.transcript.is_some()) {
        return BTreeMap::new();
    }
    let Ok(profile) = gcl_model::Profile::builtin(&r.profile) else { return BTreeMap::new() };
    let Ok(cases) = crate::suite::generate(&profile) else { return BTreeMap::new() };
    let mut by_id: BTreeMap<String, Transcript> = cases
        .into_iter()
        .filter(|c| c.transcript.steps.iter().any(|s| s.expect.segments.first().is_some_and(|g| g.form == Form::Hex)))
        .map(|c| (c.id().to_string(), c.transcript))
        .collect();
    r.cases
        .iter()
        .filter(|c| c.transcript.is_some())
        .filter_map(|c| by_id.remove(&c.id).map(|t| (c.id.as_str(), t)))
        .collect()
}

fn failure_view(
    r: &RunReport,
    c: &CaseResult,
    golden: Option<&Transcript>,
    preambles: &mut Vec<String>,
    plot_windows: bool,
) -> String {
    let one = c.diff.as_ref().map(diff::one_line).or_else(|| c.message.clone()).unwrap_or_default();
    let mut body = String::new();
    let level = if r.kind.is_host() { String::new() } else { format!("; level {}", esc(&c.level)) };
    let _ = writeln!(
        body,
        "<p>{} <span class=\"muted\">— {}; clauses: {}{level}</span></p>",
        esc(c.message.as_deref().unwrap_or("")),
        esc(&c.title),
        esc(&c.clauses.join(", ")),
    );
    if let Some(d) = &c.diff {
        // The transcript below marks the failing step with the diff; without one, it goes here.
        if c.transcript.as_deref().is_none_or(|t| gcl_transcript::parse(t).is_err()) {
            body.push_str(&pre(&diff::aligned(d)));
        }
        let rows = diff::realtime_rows(&r.profile, d, c.transcript.as_deref());
        if !rows.is_empty() {
            body.push_str(&field_table(&rows));
        }
        if let (Some(g), Some(t)) = (golden, c.transcript.as_deref()) {
            body.push_str(&realtime_plots(r, c, g, t, d.step).0);
        }
        if plot_windows {
            body.push_str(&window_plot(c, d));
        }
    }
    if let Some(t) = &c.transcript {
        body.push_str(&transcript_view(t, c.diff.as_ref(), "hand said", Some(preambles)));
        if r.kind.is_host() {
            body.push_str(&session_blocks_view(&r.profile, t));
        }
    }
    details(
        &format!(
            "<strong>{}</strong> <code>{}</code> <span class=\"muted\">{}</span>",
            c.verdict,
            esc(&c.id),
            esc(&one)
        ),
        &body,
        false,
        "case",
        Some(&fail_anchor(&c.id)),
    )
}

fn field_table(rows: &[FieldRow]) -> String {
    let mut h = String::from(
        "<table><tr><th>block in this answer</th><th>motor</th><th>field</th><th>type</th><th>golden range</th><th>bytes</th>\
<th>value (high byte first)</th><th>read low byte first</th></tr>\n",
    );
    for f in rows {
        let _ = writeln!(
            h,
            "<tr class=\"{}\"><td class=\"n\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}..{}</td><td><code>{}</code></td>\
<td class=\"n\">{}</td><td class=\"n\">{}</td></tr>",
            if f.in_range() { "pass" } else { "fail" },
            f.block,
            f.motor.map_or("hand".to_string(), |m| m.to_string()),
            esc(&f.name),
            f.ty.name(),
            f.range.0,
            f.range.1,
            esc(&f.bytes),
            f.value.map_or("missing".to_string(), |v| v.to_string()),
            match (f.swapped, f.swapped_fits()) {
                (Some(v), true) => format!("<strong>{v}: in range, the bytes are swapped</strong>"),
                (Some(v), false) => v.to_string(),
                (None, _) => String::new(),
            }
        );
    }
    h.push_str("</table>\n");
    h
}

/// A host's session's RealTime blocks decoded field by field ([`diff::session_blocks`]): a
/// table for the host's control blocks and one for the hand's feedback blocks, one row per
/// block, one column per field of the layout (a new header row where the layout changes).
fn session_blocks_view(profile: &str, transcript: &str) -> String {
    let Ok(t) = gcl_transcript::parse(transcript) else { return String::new() };
    let blocks = diff::session_blocks(profile, &t);
    let mut h = String::new();
    for (from_host, what) in [(true, "the host's control blocks"), (false, "the hand's feedback blocks")] {
        let mine: Vec<&diff::SessionBlock> = blocks.iter().filter(|b| b.from_host == from_host).collect();
        if mine.is_empty() {
            continue;
        }
        let _ = writeln!(h, "<p>RealTime: {what}, decoded field by field (values as sent, high byte first):</p>");
        let mut table = String::from("<table>\n");
        let mut columns: Option<Vec<(Option<u8>, &str)>> = None;
        for b in mine {
            let cols: Vec<(Option<u8>, &str)> = b.fields.iter().map(|(m, n, _)| (*m, *n)).collect();
            if columns.as_ref() != Some(&cols) {
                table.push_str("<tr><th>step</th><th>header</th>");
                for (m, n) in &cols {
                    let motor = m.map_or("hand".to_string(), |m| format!("motor {m}"));
                    let _ = write!(table, "<th>{} {}</th>", esc(&motor), esc(n));
                }
                table.push_str("</tr>\n");
                columns = Some(cols);
            }
            let _ = write!(
                table,
                "<tr><td class=\"n\">{}</td><td><code>{}</code></td>",
                b.step,
                esc(&gcl_transcript::escape_text(&[b.header]))
            );
            for (_, _, v) in &b.fields {
                let _ = write!(table, "<td class=\"n\">{v}</td>");
            }
            table.push_str("</tr>\n");
        }
        table.push_str("</table>\n");
        h.push_str(&table);
    }
    h
}

/// One plot per RealTime field name over the case's blocks: each motor's actual values with
/// the golden's range behind them, and a mark at the failing block. Also the number of blocks
/// and the fields plotted, for a line that sums the plots up.
fn realtime_plots(
    r: &RunReport,
    c: &CaseResult,
    golden: &Transcript,
    actual_text: &str,
    fail_step: usize,
) -> (String, usize, Vec<String>) {
    let Ok(actual) = gcl_transcript::parse(actual_text) else { return (String::new(), 0, Vec::new()) };
    // The golden's sends are the actual transcript's, and go on past the failing step.
    let layouts = diff::layouts(&r.profile, golden).unwrap_or_default();
    // (field, motor) → series of (block, value) and band (block, lo, hi).
    type Key = (String, Option<u8>);
    let mut values: BTreeMap<Key, Vec<(f64, f64)>> = BTreeMap::new();
    let mut bands: BTreeMap<Key, Vec<(f64, f64, f64)>> = BTreeMap::new();
    let mut block = 0usize;
    let mut mark = None;
    for (i, g) in golden.steps.iter().enumerate() {
        if g.expect.segments.first().map(|s| s.form) != Some(Form::Hex) {
            continue;
        }
        let got = actual.steps.get(i).and_then(|s| s.expect.exact_bytes()).unwrap_or_default();
        let rows = diff::decode_blocks(&g.expect, &got, layouts.get(i).and_then(|l| l.as_ref()));
        let first = block;
        for f in rows {
            let x = (first + f.block) as f64;
            block = block.max(first + f.block);
            let key = (f.name.clone(), f.motor);
            bands.entry(key.clone()).or_default().push((x, f.range.0 as f64, f.range.1 as f64));
            if let Some(v) = f.value {
                values.entry(key).or_default().push((x, v as f64));
            }
        }
        if i + 1 == fail_step {
            mark = Some((first + 1) as f64);
        }
    }
    if block == 0 {
        return (String::new(), 0, Vec::new());
    }
    let mut names: Vec<String> = bands.keys().map(|k| k.0.clone()).collect();
    names.dedup();
    let mut h = if fail_step > 0 {
        String::from(
            "<p>Each RealTime field over the case's blocks: the actual values, the golden's range behind them, and where the case fails.</p>\n",
        )
    } else {
        String::new()
    };
    for name in names.iter().take(8) {
        let keys: Vec<&Key> = bands.keys().filter(|k| &k.0 == name).collect();
        let plot = Plot {
            title: format!("{name} per block: {}", field_meaning(name)),
            x_label: "feedback block".into(),
            y_label: name.clone(),
            series: keys
                .iter()
                .map(|k| Series {
                    name: k.1.map_or("hand".to_string(), |m| format!("motor {m}")),
                    points: values.get(*k).cloned().unwrap_or_default(),
                    ..Default::default()
                })
                .collect(),
            bands: keys.iter().map(|k| Band { points: bands[*k].clone() }).collect(),
            marks: mark.map(|x| vec![(x, "fails here".to_string())]).unwrap_or_default(),
            // A handful of blocks: each numbered under the axis.
            x_ticks: if block <= 12 { (1..=block).map(|b| (b as f64, b.to_string())).collect() } else { Vec::new() },
            ..Default::default()
        };
        h.push_str(&plot.to_svg(&format!("rt-{}-{}", c.id, name)));
    }
    (h, block, names)
}

/// What a RealTime feedback field is, for a plot's title (facts §4.4, §4.5).
fn field_meaning(name: &str) -> &'static str {
    match name {
        "LFAP" => "absolute position, counts",
        "LFDP" => "delta position, counts since the last block",
        "LFV" => "velocity",
        "LFS" => "strain",
        "LFBP" => "breakaway position, counts",
        "LFAIN" => "analog input",
        "LFT" => "temperature",
        _ => "value by type (layout unknown)",
    }
}

/// For a failing answer of decimal values with windows (positions after a motion or a ^C
/// mid-motion, values in ranges): each value's window against where it was, one bar per value
/// in the answer's order (one per motor for a per-motor get), the parting one marked.
fn window_plot(c: &CaseResult, d: &super::Diff) -> String {
    if diff::is_hex(d) {
        return String::new();
    }
    let Some(golden) = diff::golden_expect(d) else { return String::new() };
    let Some(actual) = c
        .transcript
        .as_deref()
        .and_then(|t| gcl_transcript::parse(t).ok())
        .and_then(|t| t.steps.get(d.step.wrapping_sub(1)).and_then(|s| s.expect.exact_bytes()))
    else {
        return String::new();
    };
    let windows = diff::int_windows(&golden, &actual);
    if windows.len() < 2 {
        return String::new();
    }
    let parting = windows.iter().position(|w| w.value.is_none_or(|v| v < w.lo || v > w.hi));
    // A per-motor get (`12FGET P`) answers one value per motor named in front of it, in order.
    let cmd = diff::command(d);
    let motors: Vec<char> = cmd.chars().take_while(char::is_ascii_digit).collect();
    let label = |i: usize| match motors.get(i) {
        Some(m) if motors.len() == windows.len() => format!("motor {m}"),
        _ => format!("value {}", i + 1),
    };
    // A window a relation gives says so under its bar: `motor 2: motor 1 × 153/25 ± 6%`.
    let tick = |i: usize| match &windows[i].relative_to {
        Some((from, rule)) => format!("{}: {} {rule}", label(i), label(*from)),
        None => label(i),
    };
    let plot = Plot {
        title: format!("{cmd}: each value's golden window and where it was"),
        x_label: if motors.len() == windows.len() { "motor".into() } else { "value in the answer".into() },
        y_label: "value".into(),
        series: vec![Series {
            name: "actual".into(),
            points: windows
                .iter()
                .enumerate()
                .filter_map(|(i, w)| w.value.map(|v| ((i + 1) as f64, v as f64)))
                .collect(),
            dots: true,
            steps: false,
        }],
        windows: windows.iter().enumerate().map(|(i, w)| ((i + 1) as f64, w.lo as f64, w.hi as f64)).collect(),
        marks: parting.map(|i| vec![((i + 1) as f64, format!("{} misses", label(i)))]).unwrap_or_default(),
        x_ticks: (0..windows.len()).map(|i| ((i + 1) as f64, tick(i))).collect(),
        ..Default::default()
    };
    plot.to_svg(&format!("windows-{}", c.id))
}

/// A transcript as it happened, step by step: the preamble folded, the failing step marked
/// with the golden and the actual answer aligned under a caret, the answers labelled as what
/// the hand said (not what a golden expects).
pub fn transcript_view(text: &str, d: Option<&super::Diff>, answer: &str, shared: Option<&mut Vec<String>>) -> String {
    let Ok(t) = gcl_transcript::parse(text) else {
        return format!(
            "<p>The exchange as it happened (the hand's answers written as a transcript):</p>\n{}",
            pre(text)
        );
    };
    let fail = d.map(|d| d.step);
    let step_text = |i: usize| -> String {
        let s = &t.steps[i];
        let mut out = String::new();
        for c in &s.comments {
            let _ = writeln!(out, "# {c}");
        }
        if let Some(p) = s.pause {
            let _ = writeln!(out, "pause {}", gcl_transcript::format_duration(p));
        }
        if let Some(b) = &s.send {
            let shown = match b.form {
                Form::Text => format!("\"{}\"", gcl_transcript::escape_text(&b.bytes)),
                Form::Hex => format!("hex {}", gcl_transcript::hex_bytes(&b.bytes)),
            };
            let _ = writeln!(out, "{:>3} send {shown}", i + 1);
        }
        let _ = write!(out, "    {answer} {}", s.expect.to_text());
        out
    };
    // The preamble: the steps from a "preamble" comment up to the "the check" comment.
    let check = t
        .steps
        .iter()
        .position(|s| s.comments.iter().any(|c| c.contains(crate::suite::build::CHECK_COMMENT)))
        .unwrap_or(0);
    let check = match fail {
        Some(f) if f >= 1 && f - 1 < check => f - 1,
        _ => check,
    };
    let mut h = if answer == "expect" {
        String::new()
    } else {
        format!("<p>The exchange as it happened, step by step (\"{answer}\": the bytes the hand sent):</p>\n")
    };
    if check > 0 {
        let text = (0..check).map(step_text).collect::<Vec<_>>().join("\n\n");
        match shared {
            // The same preamble in many failures is shown once on the page, and linked.
            Some(list) => {
                let n = match list.iter().position(|p| *p == text) {
                    Some(i) => i + 1,
                    None => {
                        list.push(text);
                        list.len()
                    }
                };
                let _ = writeln!(
                    h,
                    "<p class=\"muted\">steps 1–{check}: <a href=\"#preamble-{n}\">preamble {n}</a>, the hand's answers as the golden has them</p>"
                );
            }
            None => h.push_str(&details(
                &format!("steps 1–{check}: the preamble"),
                &format!("<pre class=\"step\">{}</pre>\n", esc(&text)),
                false,
                "",
                None,
            )),
        }
    }
    for i in check..t.steps.len() {
        if Some(i + 1) == fail {
            let mut s = step_text(i);
            if let Some(d) = d {
                // The golden and the answer aligned take the place of the answer alone, unless
                // they show only part of it.
                if !diff::clipped(d)
                    && let Some(cut) = s.rfind(&format!("\n    {answer} "))
                {
                    s.truncate(cut);
                }
                s.push_str("\n    the answer parts from the golden:\n");
                for line in diff::aligned(d).lines() {
                    let _ = writeln!(s, "    {line}");
                }
            }
            let _ = writeln!(h, "<pre class=\"step bad\" id=\"step-{}\">{}</pre>", i + 1, esc(s.trim_end()));
        } else {
            let _ = writeln!(h, "<pre class=\"step\">{}</pre>", esc(&step_text(i)));
        }
    }
    h
}

/// The host's code coverage (when it was read): edges reached over time beside runs over time,
/// and the runs that added edges with their schedules.
fn host_coverage_section(p: &mut Page, h: &crate::report::HostDetails) {
    if h.edges_over_time.is_empty() {
        return;
    }
    p.heading("coverage", "The host's code coverage");
    let plot = |title: &str, y: &str, name: &str, pick: fn(&(u64, u64, u64)) -> u64| Plot {
        title: title.into(),
        x_label: "seconds".into(),
        y_label: y.into(),
        series: vec![Series {
            name: name.into(),
            points: h.edges_over_time.iter().map(|t| (t.0 as f64 / 1000.0, pick(t) as f64)).collect(),
            steps: true,
            dots: true,
        }],
        ..Default::default()
    };
    p.push(
        &plot("Edges of the host's code reached over time", "edges", "edges reached", |t| t.2)
            .to_svg("fuzz-host-edges"),
    );
    p.push(&plot("Runs over time", "runs", "runs made", |t| t.1).to_svg("fuzz-host-runs"));
    let mut t = String::from("<table><tr><th>run</th><th>new edges</th><th>schedule</th></tr>\n");
    for (run, new, schedule) in &h.added_coverage {
        let _ = writeln!(
            t,
            "<tr><td class=\"n\">{run}</td><td class=\"n\">{new}</td><td><code>{}</code></td></tr>",
            esc(schedule)
        );
    }
    t.push_str("</table>\n");
    p.push("<p>The runs that reached edges no run before them had (kept for guidance when coverage guided):</p>\n");
    p.push(&t);
}

/// The fuzz host campaign: findings with their bundles and replay commands, findings over
/// runs, the host's code coverage, the misbehaviour × protocol-state table.
fn fuzz_host_sections(p: &mut Page, r: &RunReport) {
    let Some(h) = &r.host else { return };
    p.heading("findings", "Findings");
    if h.findings.is_empty() {
        p.push(&format!("<p>No finding in {} runs.</p>\n", h.runs));
    } else {
        let mut t = String::from(
            "<table><tr><th>kind</th><th>signature</th><th>first run</th><th>bundle</th><th>run it again</th></tr>\n",
        );
        for f in &h.findings {
            let _ = writeln!(
                t,
                "<tr class=\"fail\"><td>{}</td><td><a href=\"#{}\">{}</a></td><td class=\"n\">{}</td><td><code>{}</code></td><td><code class=\"cmd\">{}</code></td></tr>",
                esc(&f.kind),
                esc(&fail_anchor(&f.case)),
                esc(&f.signature),
                f.run,
                esc(f.bundle.as_deref().unwrap_or("not written")),
                esc(f.replay.as_deref().unwrap_or(""))
            );
        }
        t.push_str("</table>\n");
        p.push(&t);
        let mut pts = vec![(0.0, 0.0)];
        let mut runs: Vec<u64> = h.findings.iter().map(|f| f.run).collect();
        runs.sort_unstable();
        for (i, run) in runs.iter().enumerate() {
            pts.push((*run as f64, (i + 1) as f64));
        }
        pts.push((h.runs.max(1) as f64, runs.len() as f64));
        let plot = Plot {
            title: "Distinct findings over runs".into(),
            x_label: "run".into(),
            y_label: "findings".into(),
            series: vec![Series { name: "distinct findings".into(), points: pts, steps: true, dots: false }],
            ..Default::default()
        };
        p.push(&plot.to_svg("fuzz-host-findings"));
    }
    host_coverage_section(p, h);
    p.heading("fired", "Misbehaviours fired, by protocol state");
    if h.fired_at.is_empty() {
        p.push("<p class=\"muted\">None fired.</p>\n");
    } else {
        let states: std::collections::BTreeSet<&String> = h.fired_at.values().flat_map(|m| m.keys()).collect();
        let mut t = String::from("<table><tr><th>misbehaviour</th>");
        for s in &states {
            let _ = write!(t, "<th>{}</th>", esc(s));
        }
        t.push_str("</tr>\n");
        for (op, m) in &h.fired_at {
            let _ = write!(t, "<tr><th>{}</th>", esc(op));
            for s in &states {
                let n = m.get(*s).copied().unwrap_or(0);
                let _ = write!(t, "<td class=\"n\">{}</td>", if n == 0 { String::new() } else { n.to_string() });
            }
            t.push_str("</tr>\n");
        }
        t.push_str("</table>\n");
        p.push(&t);
    }
    for f in h.findings.iter().filter(|f| !f.stderr.is_empty()) {
        p.push(&details(
            &format!("the host's whole stderr in the run that found <code>{}</code>", esc(&f.signature)),
            &pre(&f.stderr),
            false,
            "",
            None,
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_and_shows_failures_with_their_diff() {
        let r = crate::report::tests::sample();
        let page = to_html(&r);
        assert!(page.contains("Echo &lt;all&gt; bytes &amp; keeps case"));
        assert!(!page.contains("<all>"));
        assert!(page.contains("golden: &quot;FGET DP\\n\\r1000&quot;"), "{page}");
        assert!(page.contains("actual: &quot;FGET DP\\r\\n1000&quot;"), "{page}");
        assert!(page.contains("\n                ^ byte 7 of step 2"), "the caret sits under the parting byte: {page}");
        assert!(page.contains("<th>pre-flight</th><td>framing as the profile says"), "{page}");
        assert!(page.contains("<h1>gcl conform seed on sim</h1>"), "{page}");
        assert!(page.contains("<strong>FAIL</strong>: 1 of the 2 cases that ran fail (MUST 1)"), "{page}");
        assert!(page.contains("decision:framing-echo"));
        assert!(!page.contains("<script"), "self-contained and inert");
    }

    /// A host page shows a finding's RealTime blocks decoded field by field (they were escaped
    /// text: `"*\x14\x00..."`), the host's control blocks and the hand's feedback apart.
    #[test]
    fn a_host_page_decodes_the_sessions_realtime_blocks() {
        let mut r = crate::report::tests::sample();
        r.kind = ReportKind::FuzzHost;
        r.host = Some(crate::report::HostDetails { command: vec!["host".into()], runs: 1, ..Default::default() });
        r.cases[1].diff = None;
        r.cases[1].transcript = Some(diff::tests::SESSION.into());
        let page = to_html(&r);
        assert!(page.contains("RealTime: the host's control blocks, decoded field by field"), "{page}");
        assert!(page.contains("RealTime: the hand's feedback blocks, decoded field by field"), "{page}");
        assert!(page.contains("<th>motor 2 LFAP</th>"), "{page}");
        assert!(page.contains("<td class=\"n\">1028</td>"), "{page}");
        assert!(page.contains("<th>motor 1 LCV</th>"), "{page}");
    }

    #[test]
    fn the_level_table_counts_each_level_and_the_clause_table_has_a_level_column() {
        let page = to_html(&crate::report::tests::sample());
        assert!(
            page.contains(
                "<tr class=\"fail\"><th>MUST</th><td class=\"n\">2</td><td class=\"n\">1</td><td class=\"n\">1</td>"
            ),
            "{page}"
        );
        assert!(page.contains("<td>decision:framing-echo</td><td>MUST</td><td>FAIL</td>"), "{page}");
    }

    #[test]
    fn the_failing_step_is_marked_in_its_transcript_and_the_preamble_folds() {
        let t = "gcl-transcript 1\nid: x\ntitle: x\nclause: c\nlevel: MUST\nprofile: seed\n\n# preamble: a known state\nsend \"\\x03\"\nexpect \"\\n\\r=> \"\n\n# the check\nsend \"FGET DP\\r\"\nexpect \"FGET DP\\r\\n1000\"\n";
        let d = crate::report::Diff {
            step: 2,
            offset: 7,
            expected: "\\n\\r1000".into(),
            actual: "\\r\\n1000".into(),
            before: "FGET DP".into(),
            golden: "FGET DP\\n\\r1000".into(),
            form: Some(crate::report::AnswerForm::Text),
        };
        let mut shared = Vec::new();
        let h = transcript_view(t, Some(&d), "hand said", Some(&mut shared));
        assert!(h.contains("steps 1–1: <a href=\"#preamble-1\">preamble 1</a>"), "{h}");
        assert_eq!(shared.len(), 1, "the preamble is kept once for the page");
        let again = transcript_view(t, Some(&d), "hand said", Some(&mut shared));
        assert!(again.contains("#preamble-1"), "the same preamble links to the same place: {again}");
        assert_eq!(shared.len(), 1);
        let bad = h.split("<pre class=\"step bad\" id=\"step-2\">").nth(1).expect("the failing step is marked");
        assert!(bad.contains("golden: &quot;FGET DP\\n\\r1000"), "{bad}");
        assert!(bad.contains("actual: &quot;FGET DP\\r\\n1000"), "{bad}");
        assert!(!bad.contains("hand said"), "the aligned answer replaces the bare one: {bad}");
    }
}
