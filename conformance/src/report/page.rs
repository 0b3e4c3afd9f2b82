//! The one page design every HTML report shares (conform, certify, fuzz device, fuzz host,
//! check-host): its own title, the verdict first, then the options that changed what ran,
//! then the findings or groups, then the details, long content folded in `<details>`.
//! Self-contained: one inline style sheet, inline SVG plots, no script, no external resource.

use std::fmt::Write;

/// Text escaped for HTML content and attribute values. A bidirectional control (U+202E, the
/// right-to-left override, in a host's file name or a profile's title) is shown as
/// `\u{202E}`, never obeyed: it would reorder what the page shows around it.
pub fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c if gcl_model::escape::bidi_control(c) => {
                let _ = write!(o, "\\u{{{:04X}}}", c as u32);
            }
            c => o.push(c),
        }
    }
    o
}

/// The style sheet of every page. Long lines wrap (`pre-wrap`, breaking anywhere) rather than
/// hide behind a scroll bar.
const STYLE: &str = "\
body{font-family:system-ui,sans-serif;margin:1.5em 2em;color:#222;max-width:72em}\
h1{font-size:1.5em;margin:.2em 0}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ddd}\
h3{font-size:1.05em}table{border-collapse:collapse;margin:.6em 0}\
td,th{border:1px solid #ccc;padding:.2em .5em;text-align:left;vertical-align:top}\
th{background:#f3f3f3}td.n{text-align:right;font-variant-numeric:tabular-nums}\
.pass{background:#e6f4e6}.fail{background:#fbe3e3}.skip{background:#f3f3f3}\
.verdict{font-size:1.2em;padding:.5em .8em;border-radius:4px;margin:.6em 0}\
.verdict.pass{border:1px solid #7b7}.verdict.fail{border:1px solid #d77}\
.verdict.partial{border:1px solid #cb4;background:#fdf5d8}\
pre{background:#f7f7f7;padding:.5em .7em;white-space:pre-wrap;overflow-wrap:anywhere;margin:.4em 0}\
code,pre{font-family:ui-monospace,monospace;font-size:90%}\
details{margin:.3em 0}details>summary{cursor:pointer}details.case{border-left:3px solid #d77;padding-left:.6em}\
.step{margin:.15em 0}.step.bad{background:#fbe3e3;border-left:3px solid #c33}\
.muted{color:#666}.cmd{background:#eef;padding:.1em .3em}\
svg{display:block;margin:.5em 0;background:#fff;border:1px solid #ddd}\
";

/// A page being written.
pub struct Page {
    html: String,
}

impl Page {
    /// A page titled `title` whose first line says the verdict (`ok`: green, else red) and
    /// `headline`, one sentence of what it means.
    pub fn new(title: &str, ok: bool, verdict: &str, headline: &str) -> Page {
        Page::toned(title, if ok { "pass" } else { "fail" }, verdict, headline)
    }

    /// [`Page::new`] in a tone of its own: `pass` (green), `fail` (red) or `partial` (amber:
    /// nothing failed, but not everything was judged).
    pub fn toned(title: &str, tone: &str, verdict: &str, headline: &str) -> Page {
        let mut html = String::with_capacity(64 * 1024);
        let _ = write!(
            html,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width\"><title>{t}: {v}</title>\n<style>{STYLE}</style></head><body>\n\
<h1>{t}</h1>\n<div class=\"verdict {c}\" id=\"verdict\"><strong>{v}</strong>: {h}</div>\n",
            t = esc(title),
            v = esc(verdict),
            c = esc(tone),
            h = esc(headline),
        );
        Page { html }
    }

    /// A table of facts (name, value; values already HTML).
    pub fn facts(&mut self, rows: &[(String, String)]) {
        if rows.is_empty() {
            return;
        }
        self.html.push_str("<table>");
        for (k, v) in rows {
            let _ = write!(self.html, "<tr><th>{}</th><td>{v}</td></tr>", esc(k));
        }
        self.html.push_str("</table>\n");
    }

    /// The options that changed what ran (name without dashes, value as text), or a line
    /// saying there were none.
    pub fn options(&mut self, pairs: &[(String, String)]) {
        self.heading("options", "Options that changed what ran");
        if pairs.is_empty() {
            self.html.push_str("<p class=\"muted\">None: the defaults ran.</p>\n");
            return;
        }
        self.html.push_str("<table>");
        for (k, v) in pairs {
            let _ = write!(self.html, "<tr><th><code>--{}</code></th><td>{}</td></tr>", esc(k), esc(v));
        }
        self.html.push_str("</table>\n");
    }

    /// A section heading with an anchor.
    pub fn heading(&mut self, id: &str, text: &str) {
        let _ = writeln!(self.html, "<h2 id=\"{}\">{}</h2>", esc(id), esc(text));
    }

    /// Raw HTML.
    pub fn push(&mut self, html: &str) {
        self.html.push_str(html);
    }

    /// The finished page.
    pub fn finish(mut self) -> String {
        self.html.push_str("</body></html>\n");
        self.html
    }
}

/// A folded block: `summary` (HTML) always shown, `body` (HTML) on opening.
pub fn details(summary: &str, body: &str, open: bool, class: &str, id: Option<&str>) -> String {
    let id = id.map(|i| format!(" id=\"{}\"", esc(i))).unwrap_or_default();
    let class = if class.is_empty() { String::new() } else { format!(" class=\"{class}\"") };
    format!("<details{id}{class}{}><summary>{summary}</summary>\n{body}</details>\n", if open { " open" } else { "" })
}

/// A preformatted block of plain text.
pub fn pre(text: &str) -> String {
    format!("<pre>{}</pre>\n", esc(text))
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_bidirectional_control_is_shown_not_obeyed() {
        assert_eq!(super::esc("<a> \u{202E}txt.exe"), "&lt;a&gt; \\u{202E}txt.exe");
    }
}
