//! Scripts for `gcl record`: what the host does, one directive per line, without the answers.
//!
//! ```text
//! # a comment (kept, attached to the next step)
//! id: abort-during-close          any transcript header key (command-line flags override)
//! timeout: 30s                    capture timeout of the steps that follow
//! HI                              a host line: sent with a CR; the step ends at the prompt
//! line: FGET\tDP                  a host line written with escapes (`line:` alone: a bare CR)
//! nowait: C                       a host line; the step ends once the hand has been quiet
//! pause: 200ms                    wait before the next step's bytes go out
//! abort                           ^C (0x03)
//! block: 43 14 FB                 raw bytes in hex (RealTime blocks), no CR
//! raw: C\x14\xFB                  raw bytes with escapes, no CR
//! partial: FGET D                 bytes with escapes, no CR; the step ends once the hand is quiet
//! wait                            send nothing; capture until the prompt
//! ```
//!
//! Any other line is a host line. A line that would read as a directive (`abort`, `wait`,
//! something with a `:`) is written with `line:`.

use std::time::Duration;

use super::Form;
use super::parse::{HeaderFields, ParseError, ParseErrorKind, check_text, lines, parse_duration, split_header};

/// What one step of a script sends.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Action {
    /// A command line; the CR is added when it is sent. The step ends at the prompt (or at the
    /// `*` of a LOOP).
    Line(Vec<u8>),
    /// A command line whose answer is not awaited: the step ends once the hand has been quiet
    /// for the recorder's quiet time (for ^C during motion).
    NoWait(Vec<u8>),
    /// Bytes as they are with no CR (a partial line); like [`Action::NoWait`], the step ends
    /// once the hand has been quiet.
    Partial(Vec<u8>),
    /// Bytes as they are (RealTime blocks, ^C, several lines at once).
    Bytes {
        /// The bytes.
        bytes: Vec<u8>,
        /// How the transcript writes them.
        form: Form,
    },
    /// Nothing is sent; the step collects the answer to something sent before.
    Wait,
}

impl Action {
    /// The bytes this action puts on the wire.
    pub fn wire_bytes(&self, terminator: u8) -> Vec<u8> {
        match self {
            Action::Line(l) | Action::NoWait(l) => {
                let mut v = l.clone();
                v.push(terminator);
                v
            }
            Action::Bytes { bytes, .. } | Action::Partial(bytes) => bytes.clone(),
            Action::Wait => Vec::new(),
        }
    }

    /// Whether the step ends on silence rather than at a prompt.
    pub fn ends_on_quiet(&self) -> bool {
        matches!(self, Action::NoWait(_) | Action::Partial(_))
    }

    /// The ^C byte as an action.
    pub fn abort() -> Action {
        Action::Bytes { bytes: vec![3], form: Form::Text }
    }
}

/// One step of a script.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScriptStep {
    /// The 1-based source line (0 when built in code).
    pub line: usize,
    /// Comments written before it.
    pub comments: Vec<String>,
    /// Time to let pass before sending.
    pub pause: Option<Duration>,
    /// What to send.
    pub action: Action,
    /// How long to wait for the answer while recording; the recorder's default when `None`.
    pub timeout: Option<Duration>,
}

impl ScriptStep {
    /// A step with no pause, comment or timeout.
    pub fn new(action: Action) -> ScriptStep {
        ScriptStep { line: 0, comments: Vec::new(), pause: None, action, timeout: None }
    }
}

/// A parsed script: header fields (possibly incomplete: the command line may add the rest)
/// and steps.
#[derive(Debug, Clone, Default)]
pub struct Script {
    /// The header keys the script gives.
    pub fields: HeaderFields,
    /// The steps.
    pub steps: Vec<ScriptStep>,
}

impl Script {
    /// The `id:` of the script, if it has one.
    pub fn id(&self) -> Option<&str> {
        self.fields.id.as_deref()
    }
}

/// Parses a script.
pub fn parse_script(text: &str) -> Result<Script, ParseError> {
    let mut script = Script::default();
    let mut comments = Vec::new();
    let mut pause = None;
    let mut timeout = None;
    for (n, raw) in lines(text) {
        let line = raw.trim_end();
        let t = line.trim_start();
        if t.is_empty() {
            continue;
        }
        if let Some(c) = t.strip_prefix('#') {
            comments.push(c.strip_prefix(' ').unwrap_or(c).to_string());
            continue;
        }
        let col = line.len() - t.len() + 1;
        let esc = |s: &str| {
            gcl_model::escape::unescape(s).map_err(|e| ParseError::at(n, col, ParseErrorKind::BadString(e.to_string())))
        };
        let action = match t {
            "abort" => Action::abort(),
            "wait" => Action::Wait,
            _ => match split_header(t) {
                Some(("line", _)) => Action::Line(esc(directive_arg(t, "line:"))?),
                Some(("nowait", _)) => Action::NoWait(esc(directive_arg(t, "nowait:"))?),
                Some(("raw", _)) => Action::Bytes { bytes: esc(directive_arg(t, "raw:"))?, form: Form::Text },
                Some(("partial", _)) => Action::Partial(esc(directive_arg(t, "partial:"))?),
                Some(("block", v)) => {
                    let mut bytes = Vec::new();
                    for w in v.split_whitespace() {
                        if w.len() != 2 || !w.bytes().all(|d| d.is_ascii_hexdigit()) {
                            return Err(ParseError::at(n, col, ParseErrorKind::BadHex(w.to_string())));
                        }
                        bytes.push(u8::from_str_radix(w, 16).unwrap_or_default());
                    }
                    Action::Bytes { bytes, form: Form::Hex }
                }
                Some(("pause", v)) => {
                    pause = Some(
                        parse_duration(v).ok_or_else(|| ParseError::new(n, ParseErrorKind::BadDuration(v.into())))?,
                    );
                    continue;
                }
                Some(("timeout", v)) => {
                    timeout = Some(
                        parse_duration(v).ok_or_else(|| ParseError::new(n, ParseErrorKind::BadDuration(v.into())))?,
                    );
                    continue;
                }
                Some((k, v)) => {
                    if !script.steps.is_empty() {
                        return Err(ParseError::new(n, ParseErrorKind::HeaderInBody(k.to_string())));
                    }
                    script.fields.apply(k, v, n)?;
                    comments.clear();
                    continue;
                }
                None => {
                    if t.bytes().any(|b| !(0x20..=0x7e).contains(&b) && b != b'\t') {
                        return Err(ParseError::at(
                            n,
                            col,
                            ParseErrorKind::BadString("non-ASCII in a host line (use `line:` with escapes)".into()),
                        ));
                    }
                    Action::Line(t.as_bytes().to_vec())
                }
            },
        };
        script.steps.push(ScriptStep {
            line: n,
            comments: std::mem::take(&mut comments),
            pause: pause.take(),
            action,
            timeout,
        });
    }
    if script.steps.is_empty() {
        return Err(ParseError::new(1, ParseErrorKind::NoSteps));
    }
    Ok(script)
}

/// The text after `key:` and at most one space.
fn directive_arg<'a>(t: &'a str, key: &str) -> &'a str {
    let rest = t.strip_prefix(key).unwrap_or_default();
    rest.strip_prefix(' ').unwrap_or(rest)
}

/// Parses script bytes (size and UTF-8 checked first).
pub fn parse_script_bytes(bytes: &[u8]) -> Result<Script, ParseError> {
    parse_script(check_text(bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directives_and_host_lines() {
        let s = parse_script(
            "# hello\nid: x-1\ntitle: T\nHI\ntimeout: 30s\nnowait: C\npause: 200ms\nabort\nblock: 43 14 fb\nraw: a\\x03\nline:\nline: FGET\\tDP\nwait\n",
        )
        .unwrap();
        assert_eq!(s.id(), Some("x-1"));
        let acts: Vec<&Action> = s.steps.iter().map(|s| &s.action).collect();
        assert_eq!(
            acts,
            vec![
                &Action::Line(b"HI".to_vec()),
                &Action::NoWait(b"C".to_vec()),
                &Action::abort(),
                &Action::Bytes { bytes: vec![0x43, 0x14, 0xFB], form: Form::Hex },
                &Action::Bytes { bytes: b"a\x03".to_vec(), form: Form::Text },
                &Action::Line(Vec::new()),
                &Action::Line(b"FGET\tDP".to_vec()),
                &Action::Wait,
            ]
        );
        assert_eq!(s.steps[2].pause, Some(Duration::from_millis(200)));
        assert_eq!(s.steps[0].timeout, None);
        assert_eq!(s.steps[1].timeout, Some(Duration::from_secs(30)));
        assert!(s.steps[0].comments.is_empty(), "header comments are dropped");
    }

    #[test]
    fn errors_have_line_numbers() {
        let e = parse_script("HI\nblock: 4G\n").unwrap_err();
        assert_eq!(e.line, 2);
        let e = parse_script("HI\nid: late\n").unwrap_err();
        assert_eq!((e.line, e.kind), (2, ParseErrorKind::HeaderInBody("id".into())));
        let e = parse_script("pause: soon\n").unwrap_err();
        assert_eq!(e.line, 1);
        let e = parse_script("bogus-key: 1\n").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::UnknownKey(_)));
        assert!(matches!(parse_script("# only\n").unwrap_err().kind, ParseErrorKind::NoSteps));
    }
}
