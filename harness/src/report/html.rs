//! A self-contained HTML report: summary, per-case results, a matrix of which spec clauses
//! were covered and how they fared, and the transcript and diff of every failure. No
//! scripts, no external resources.

use std::fmt::Write;

use super::{RunReport, Verdict};

/// Escapes text for HTML element content and attribute values.
/// Text escaped for HTML content and attribute values.
pub(crate) fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

fn class(v: Verdict) -> &'static str {
    match v {
        Verdict::Pass => "pass",
        Verdict::Skip | Verdict::Xfail => "skip",
        _ => "fail",
    }
}

/// A diff for people: the step and byte, expected and actual with the agreed bytes before the
/// parting one as context, a caret under the parting byte, and the step's whole golden.
fn diff_view(d: &super::Diff) -> String {
    let lead = if d.offset > d.before.len() { "…" } else { "" };
    let caret = 1 + lead.chars().count() + d.before.chars().count();
    let mut p = format!(
        "<p>step {}, parts at byte {}</p>\n<pre>expected: \"{lead}{}{}\"\nactual:   \"{lead}{}{}\"\n          {}^ byte {}",
        d.step,
        d.offset,
        esc(&d.before),
        esc(&d.expected),
        esc(&d.before),
        esc(&d.actual),
        " ".repeat(caret),
        d.offset
    );
    if !d.golden.is_empty() {
        let _ = write!(p, "\ngolden:   {}", esc(&d.golden));
    }
    p.push_str("</pre>");
    p
}

/// Renders the run as one HTML page.
pub fn to_html(r: &RunReport) -> String {
    let mut h = String::new();
    let verdict = if r.passed() { "PASSED" } else { "FAILED" };
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<title>gcl conform {profile}: {verdict}</title>\n<style>\
body{{font-family:system-ui,sans-serif;margin:2em;color:#222}}table{{border-collapse:collapse;margin:1em 0}}\
td,th{{border:1px solid #ccc;padding:.25em .6em;text-align:left;vertical-align:top}}\
.pass{{background:#e6f4e6}}.fail{{background:#fbe3e3}}.skip{{background:#f3f3f3}}\
pre{{background:#f7f7f7;padding:.6em;overflow-x:auto;white-space:pre-wrap}}code{{font-size:90%}}\
</style></head><body>\n<h1>gcl conform: {verdict}</h1>\n",
        profile = esc(&r.profile)
    );
    let _ = write!(
        h,
        "<table><tr><th>target</th><td>{}</td></tr><tr><th>profile</th><td>{}</td></tr>\
<tr><th>level</th><td>{}</td></tr><tr><th>started</th><td>{}</td></tr><tr><th>duration</th><td>{:.1} ms</td></tr>\
<tr><th>suite</th><td><code>{}</code></td></tr><tr><th>tool</th><td>{}</td></tr>\
<tr><th>liveness</th><td>before: {}, after: {}</td></tr></table>",
        esc(&r.target),
        esc(&r.profile),
        esc(&r.level),
        esc(&r.started),
        r.duration_ms,
        esc(&r.suite_hash),
        esc(&r.tool),
        r.liveness.before,
        r.liveness.after
    );
    h.push('\n');
    let given = r.options.pairs();
    if !given.is_empty() {
        h.push_str("<p>Options that changed what ran:</p><table>");
        for (k, v) in &given {
            let _ = write!(h, "<tr><th>--{}</th><td>{}</td></tr>", esc(k), esc(v));
        }
        h.push_str("</table>\n");
    }
    if let Some(p) = &r.preflight {
        let _ = writeln!(h, "<p><strong>{}</strong></p>", esc(p));
    }
    if let Some(st) = &r.stopped {
        let _ = writeln!(h, "<p class=\"fail\"><strong>Ended early:</strong> {}</p>", esc(&st.message));
    }
    if !r.groups.is_empty() {
        h.push_str("<h2>Root causes first</h2>\n<p>Failures grouped by where they part from their goldens (the command answered, the kind of difference), largest first; each names the clause of its smallest failing case.</p>\n<table><tr><th>cases</th><th>command</th><th>kind</th><th>likely clause</th><th>representative</th></tr>\n");
        for g in &r.groups {
            let _ = writeln!(
                h,
                "<tr class=\"fail\"><td>{}</td><td><code>{}</code></td><td>{}</td><td>{}</td><td><a href=\"#fail-{}\">{}</a></td></tr>",
                if g.blocked.is_empty() {
                    g.cases.len().to_string()
                } else {
                    format!("{} ({} blocked)", g.cases.len(), g.blocked.len())
                },
                esc(&g.command),
                esc(&g.kind),
                esc(&g.clause),
                esc(&g.representative),
                esc(&g.representative)
            );
            if let Some(d) = &g.diff {
                let _ = writeln!(h, "<tr><td></td><td colspan=\"4\">{}</td></tr>", diff_view(d));
            }
            if !g.blocked.is_empty() {
                let _ = writeln!(
                    h,
                    "<tr class=\"blocked\"><td></td><td colspan=\"4\">blocked by this group (they fail on its clause's bug, not their own): {}</td></tr>",
                    esc(&g.blocked.join(", "))
                );
            }
        }
        h.push_str("</table>\n");
    }
    if let Some(w) = &r.wire {
        let _ = write!(
            h,
            "<p>Wire time: lower bound {:.0} ms over the {} PASS/FAIL cases (per case, the larger of its bytes one \
way at {} baud, as the line is full duplex, and the model's motion time for it; {} bytes sent, {} received, motion \
{:.0} ms); took {:.0} ms, ratio {:.2}.</p>",
            w.lower_bound_ms,
            w.counted_cases,
            w.baud,
            w.bytes_sent,
            w.bytes_received,
            w.motion_ms,
            w.actual_ms,
            w.ratio
        );
        h.push('\n');
    }
    h.push_str("<h2>Summary</h2>\n<table><tr>");
    for v in Verdict::ALL {
        let _ = write!(h, "<th>{v}</th>");
    }
    h.push_str("</tr><tr>");
    for v in Verdict::ALL {
        let _ = write!(h, "<td>{}</td>", r.summary.get(&v).copied().unwrap_or(0));
    }
    h.push_str("</tr></table>\n");

    // The clause matrix: one row per spec clause, one column per verdict, counting the
    // cases that check it.
    h.push_str("<h2>Clause coverage</h2>\n<table><tr><th>clause</th><th>verdict</th>");
    for v in Verdict::ALL {
        let _ = write!(h, "<th>{v}</th>");
    }
    h.push_str("<th>cases</th></tr>\n");
    for c in &r.clauses {
        let verdict = if c.blocked { format!("{} (blocked)", c.verdict) } else { c.verdict.to_string() };
        let _ = write!(h, "<tr class=\"{}\"><td>{}</td><td>{}</td>", class(c.verdict), esc(&c.clause), verdict);
        for v in Verdict::ALL {
            let n = r.cases.iter().filter(|k| k.verdict == v && k.clauses.contains(&c.clause)).count();
            if n == 0 {
                h.push_str("<td></td>");
            } else {
                let _ = write!(h, "<td>{n}</td>");
            }
        }
        let _ = writeln!(
            h,
            "<td>{}</td></tr>",
            c.cases.iter().map(|id| format!("<a href=\"#{0}\">{0}</a>", esc(id))).collect::<Vec<_>>().join(" ")
        );
    }
    h.push_str("</table>\n");

    h.push_str("<h2>Cases</h2>\n<table><tr><th>id</th><th>title</th><th>level</th><th>verdict</th><th>ms</th></tr>\n");
    for c in &r.cases {
        let _ = writeln!(
            h,
            "<tr class=\"{}\" id=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.2}</td></tr>",
            class(c.verdict),
            esc(&c.id),
            esc(&c.id),
            esc(&c.title),
            esc(&c.level),
            c.verdict,
            c.duration_ms
        );
    }
    h.push_str("</table>\n");

    let failures: Vec<_> = r.cases.iter().filter(|c| c.verdict.fails_run() || c.verdict == Verdict::Xfail).collect();
    if !failures.is_empty() {
        h.push_str("<h2>Failures</h2>\n");
        for c in failures {
            let _ = writeln!(
                h,
                "<h3 id=\"fail-{}\">{} {}</h3>\n<p>{}</p>\n<p>clauses: {}</p>",
                esc(&c.id),
                c.verdict,
                esc(&c.id),
                esc(c.message.as_deref().unwrap_or("")),
                esc(&c.clauses.join(", "))
            );
            if let Some(d) = &c.diff {
                let _ = writeln!(h, "{}", diff_view(d));
            }
            if let Some(t) = &c.transcript {
                let _ = writeln!(
                    h,
                    "<p>The exchange as it happened (the hand's answers written as a transcript):</p>\n<pre>{}</pre>",
                    esc(t)
                );
            }
        }
    }
    h.push_str("</body></html>\n");
    h
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
        assert!(page.contains(r#"expected: "FGET DP\n\r1000""#), "{page}");
        assert!(page.contains(r#"actual:   "FGET DP\r\n1000""#), "{page}");
        assert!(page.contains("step 2, parts at byte 7"), "{page}");
        assert!(page.contains("\n                  ^ byte 7"), "the caret sits under the parting byte: {page}");
        assert!(page.contains("golden:   &quot;FGET DP"), "{page}");
        assert!(page.contains("pre-flight: framing as the profile says"), "{page}");
        assert!(page.contains("<h1>gcl conform: FAILED</h1>"));
        assert!(page.contains("decision:framing-echo"));
        assert!(!page.contains("<script"), "self-contained and inert");
    }
}
