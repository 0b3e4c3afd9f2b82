//! JUnit XML: one `testsuite` per run, one `testcase` per case with `name` (the case id)
//! and `classname` (`gcl.<profile>.<level>`); failures carry the diff.

use quick_xml::Writer;
use quick_xml::events::{BytesCData, BytesDecl, BytesEnd, BytesStart, BytesText, Event};

use super::{RunReport, Verdict};

/// Renders the run as JUnit XML.
pub fn to_junit(r: &RunReport) -> std::io::Result<String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    let count = |v: Verdict| r.summary.get(&v).copied().unwrap_or(0);
    let failures = count(Verdict::Fail) + count(Verdict::Xpass);
    let errors = count(Verdict::Error) + count(Verdict::Timeout);
    let skipped = count(Verdict::Skip) + count(Verdict::Xfail);
    let time = format!("{:.3}", r.duration_ms / 1000.0);
    let (tests, failures, errors, skipped) =
        (r.cases.len().to_string(), failures.to_string(), errors.to_string(), skipped.to_string());
    // A host suite is named for the host command; a hand's for the profile and target.
    let name = match (&r.host, r.kind.is_host()) {
        (Some(h), true) => format!("{} {}", r.kind.command(), super::shell_command(&h.command)),
        (None, true) => format!("{} {}", r.kind.command(), r.target.trim_start_matches("host: ")),
        _ => format!("{} {} ({})", r.kind.command(), r.profile, r.target),
    };
    let mut suites = BytesStart::new("testsuites");
    suites.push_attribute(("name", name.as_str()));
    suites.push_attribute(("tests", tests.as_str()));
    suites.push_attribute(("failures", failures.as_str()));
    suites.push_attribute(("errors", errors.as_str()));
    suites.push_attribute(("time", time.as_str()));
    w.write_event(Event::Start(suites))?;
    let mut suite = BytesStart::new("testsuite");
    suite.push_attribute(("name", name.as_str()));
    suite.push_attribute(("tests", tests.as_str()));
    suite.push_attribute(("failures", failures.as_str()));
    suite.push_attribute(("errors", errors.as_str()));
    suite.push_attribute(("skipped", skipped.as_str()));
    suite.push_attribute(("time", time.as_str()));
    suite.push_attribute(("timestamp", r.started.as_str()));
    w.write_event(Event::Start(suite))?;
    // The pre-flight, an early end and the root-cause groups lead, as properties CI shows.
    let mut props: Vec<(String, String)> = Vec::new();
    // The run's verdict line, as every other output of the run says it (PARTIAL included).
    props.push(("gcl.verdict".into(), r.verdict_line()));
    for (k, v) in r.options.pairs() {
        props.push((format!("gcl.{k}"), v.to_string()));
    }
    if let Some(p) = &r.preflight {
        props.push(("preflight".into(), p.clone()));
    }
    if let Some(st) = &r.stopped {
        props.push(("stopped".into(), st.message.clone()));
    }
    if let Some(j) = r.judged() {
        props.push(("judged".into(), j));
    }
    for (i, g) in r.groups.iter().enumerate() {
        props.push((format!("root-cause-{}", i + 1), g.summary.clone()));
    }
    if !props.is_empty() {
        w.write_event(Event::Start(BytesStart::new("properties")))?;
        for (k, v) in &props {
            let mut e = BytesStart::new("property");
            e.push_attribute(("name", k.as_str()));
            e.push_attribute(("value", v.as_str()));
            w.write_event(Event::Empty(e))?;
        }
        w.write_event(Event::End(BytesEnd::new("properties")))?;
    }
    for c in &r.cases {
        // CI groups test cases by classname: a hand's by profile and level, a host's by
        // what judged it (the clauses of check-host, the findings of fuzz host).
        let classname = match r.kind {
            super::ReportKind::CheckHost => "gcl.check-host.clause".to_string(),
            super::ReportKind::FuzzHost => {
                format!("gcl.fuzz-host.{}", c.clauses.first().map_or("finding", |k| k.trim_start_matches("host: ")))
            }
            _ => format!("gcl.{}.{}", r.profile, c.level),
        };
        let t = format!("{:.3}", c.duration_ms / 1000.0);
        let mut tc = BytesStart::new("testcase");
        tc.push_attribute(("name", c.id.as_str()));
        tc.push_attribute(("classname", classname.as_str()));
        tc.push_attribute(("time", t.as_str()));
        w.write_event(Event::Start(tc))?;
        // CI shows the message on one line: the diff's summary says what differed. A case
        // blocked by a root cause says which first, so a dashboard groups them by it.
        let mut message = match (&c.diff, &c.message) {
            (Some(d), _) => super::diff::one_line(d),
            (None, Some(m)) => m.clone(),
            (None, None) => c.verdict.to_string(),
        };
        if c.verdict.fails_run()
            && let Some((i, g)) = r.groups.iter().enumerate().find(|(_, g)| g.blocked.contains(&c.id))
        {
            message = format!("blocked by root-cause-{} ({}): {message}", i + 1, g.clause);
        }
        let body = {
            let mut b = format!("{}\n{}\nclauses: {}\n", c.verdict, c.title, c.clauses.join(", "));
            if let Some(m) = &c.message {
                b.push_str(m);
                b.push('\n');
            }
            if let Some(d) = &c.diff {
                b.push_str(&super::diff::aligned(d));
                b.push('\n');
            }
            if let Some(t) = &c.transcript {
                b.push_str("\ntranscript:\n");
                b.push_str(t);
            }
            b
        };
        let element = match c.verdict {
            Verdict::Pass => None,
            Verdict::Fail | Verdict::Xpass => Some("failure"),
            Verdict::Error | Verdict::Timeout => Some("error"),
            Verdict::Skip | Verdict::Xfail => Some("skipped"),
        };
        if let Some(el) = element {
            let mut e = BytesStart::new(el);
            e.push_attribute(("message", message.as_str()));
            e.push_attribute(("type", c.verdict.as_str()));
            w.write_event(Event::Start(e))?;
            // CDATA cannot hold "]]>"; split it if a transcript ever contains it.
            for (i, part) in body.split("]]>").enumerate() {
                if i > 0 {
                    w.write_event(Event::Text(BytesText::new("]]>")))?;
                }
                w.write_event(Event::CData(BytesCData::new(part)))?;
            }
            w.write_event(Event::End(BytesEnd::new(el)))?;
        }
        w.write_event(Event::End(BytesEnd::new("testcase")))?;
    }
    w.write_event(Event::End(BytesEnd::new("testsuite")))?;
    w.write_event(Event::End(BytesEnd::new("testsuites")))?;
    // Every piece written is a Rust string, so the bytes are UTF-8.
    String::from_utf8(w.into_inner()).map(xml_chars).map_err(std::io::Error::other)
}

/// A JUnit file as written, with every character XML 1.0 forbids even as a reference (the
/// control bytes a host or a hand put in a command word, a message, a transcript) written out
/// as text by [`gcl_model::escape::printable`] (`\x00`, `\x1B`): whatever the bytes, a strict
/// XML parser reads the file. The markup itself is printable ASCII, so only text changes.
pub fn xml_chars(xml: String) -> String {
    match gcl_model::escape::printable(&xml) {
        std::borrow::Cow::Borrowed(_) => xml,
        std::borrow::Cow::Owned(s) => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_testcase_has_name_and_classname_and_failures_carry_the_diff() {
        let r = crate::report::tests::sample();
        let xml = to_junit(&r).unwrap();
        assert!(xml.contains(r#"<testcase name="framing-echo" classname="gcl.seed.MUST""#), "{xml}");
        assert!(
            xml.contains(r#"<failure message="FGET DP (step 2): expected &quot;FGET DP\n\r1000&quot;, got &quot;FGET DP\r\n1000&quot;" type="FAIL">"#),
            "{xml}"
        );
        assert!(xml.contains("golden: \"FGET DP\\n\\r1000\""), "{xml}");
        // It is well-formed: quick-xml reads it back to the end.
        let mut reader = quick_xml::Reader::from_str(&xml);
        let mut cases = 0;
        loop {
            match reader.read_event().unwrap() {
                Event::Start(e) if e.name().as_ref() == b"testcase" => cases += 1,
                Event::Eof => break,
                _ => {}
            }
        }
        assert_eq!(cases, 2);
    }
}
