//! Untrusted transcript text to a typed [`Transcript`]. Every error carries the 1-based line
//! (and where useful the column) it was found on; nothing here panics on any input.

use gcl_model::realtime::FieldType;
use std::time::Duration;

use gcl_model::escape::{UnescapeError, unescape_into};

use super::{
    Expect, Form, Header, HostBytes, Level, MAGIC, MAX_DURATION, MAX_FILE_BYTES, Piece, Relation, Requirement, Setup,
    Step, Transcript, Value, ValueKind, is_capture_name, is_slug,
};

/// Why transcript (or script) text does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}{}: {kind}", column.map(|c| format!(", column {c}")).unwrap_or_default())]
pub struct ParseError {
    /// The 1-based line.
    pub line: usize,
    /// The 1-based column (in bytes), when it helps.
    pub column: Option<usize>,
    /// What is wrong.
    pub kind: ParseErrorKind,
}

/// What is wrong with a transcript's text.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParseErrorKind {
    /// The text is larger than [`MAX_FILE_BYTES`].
    #[error("file larger than {MAX_FILE_BYTES} bytes")]
    TooLarge,
    /// The bytes are not UTF-8.
    #[error("not UTF-8 text")]
    NotUtf8,
    /// The first line is not `gcl-transcript 1`.
    #[error("expected `{MAGIC}` as the first line")]
    MissingMagic,
    /// `gcl-transcript N` with an N this tool does not read.
    #[error("unsupported format version `{0}` (this tool reads `{MAGIC}`)")]
    UnsupportedVersion(String),
    /// A `key:` line with a key the format does not define.
    #[error("unknown header key `{0}` (extensions start with `x-`)")]
    UnknownKey(String),
    /// A key that may appear once appears twice.
    #[error("header key `{0}` given twice")]
    DuplicateKey(String),
    /// A required key is missing.
    #[error("header key `{0}` is missing")]
    MissingKey(String),
    /// A header value is malformed.
    #[error("bad `{key}`: {reason}")]
    BadValue {
        /// The key.
        key: String,
        /// Why.
        reason: String,
    },
    /// A header line after the first step.
    #[error("header key `{0}` after the first step")]
    HeaderInBody(String),
    /// A body line that is not `pause`, `send` or `expect` (or, in a script, no directive).
    #[error("unknown directive `{0}`")]
    UnknownDirective(String),
    /// A duration that is not `Nms` or `Ns` up to 24 h.
    #[error("bad duration `{0}` (expected e.g. 200ms or 20s, at most 24 h)")]
    BadDuration(String),
    /// A malformed string.
    #[error("bad string: {0}")]
    BadString(String),
    /// A malformed hex token.
    #[error("bad hex token `{0}` (expected two hex digits, ?? or an elision in braces)")]
    BadHex(String),
    /// A malformed or misplaced elision.
    #[error("bad elision `{0}`")]
    BadElision(String),
    /// An expectation that breaks a rule of the format (see [`Expect::check`]).
    #[error("{0}")]
    BadExpect(String),
    /// Text after the end of a directive.
    #[error("unexpected `{0}`")]
    Unexpected(String),
    /// No step at all.
    #[error("no steps")]
    NoSteps,
    /// A capture or a relation that breaks the rules: a name captured twice, a relation to a
    /// name not captured before it, a timing window whose lower bound is above its upper.
    #[error("{0}")]
    BadCapture(String),
}

impl ParseError {
    pub(crate) fn new(line: usize, kind: ParseErrorKind) -> ParseError {
        ParseError { line, column: None, kind }
    }

    pub(crate) fn at(line: usize, column: usize, kind: ParseErrorKind) -> ParseError {
        ParseError { line, column: Some(column), kind }
    }
}

/// Parses transcript bytes (checking size and UTF-8 first, with the line of the first bad byte).
pub fn parse_bytes(bytes: &[u8]) -> Result<Transcript, ParseError> {
    parse(check_text(bytes)?)
}

/// Checks size and UTF-8 of a file's bytes.
pub(crate) fn check_text(bytes: &[u8]) -> Result<&str, ParseError> {
    if bytes.len() > MAX_FILE_BYTES {
        return Err(ParseError::new(1, ParseErrorKind::TooLarge));
    }
    std::str::from_utf8(bytes).map_err(|e| {
        let good = &bytes[..e.valid_up_to()];
        let line = 1 + good.iter().filter(|b| **b == b'\n').count();
        let col = 1 + good.iter().rev().take_while(|b| **b != b'\n').count();
        ParseError::at(line, col, ParseErrorKind::NotUtf8)
    })
}

/// Where the literal text that starts at `from` ends: at the next `"` or `{` that is not
/// escaped, or at the end. An escape's second byte never ends it, so `\"` stays in the text
/// (and is refused by [`unescape_into`] as an unknown escape).
fn literal_end(b: &[u8], from: usize) -> usize {
    let mut i = from;
    while let Some(&c) = b.get(i) {
        match c {
            b'"' | b'{' => break,
            b'\\' => i += 2,
            _ => i += 1,
        }
    }
    i.min(b.len())
}

/// Splits text into `(line number, line)` with a trailing CR removed (CRLF files read the same).
pub(crate) fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n').enumerate().map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

/// Header values as they are read, before the required keys are checked (a script's header,
/// which `gcl record` completes from its options).
#[derive(Debug, Clone, Default)]
pub struct HeaderFields {
    /// `id:`.
    pub id: Option<String>,
    /// `title:`.
    pub title: Option<String>,
    /// Every `clause:`.
    pub clauses: Vec<String>,
    /// `level:`.
    pub level: Option<Level>,
    /// `profile:`, split.
    pub profiles: Vec<String>,
    /// `requires:`, split.
    pub requires: Vec<Requirement>,
    /// Every `setup:`.
    pub setup: Vec<Setup>,
    /// Every `note:`.
    pub notes: Vec<String>,
    /// `x-...` keys with their values, in file order.
    pub extensions: Vec<(String, String)>,
}

/// Splits `key: value` when the key is a header key (or `x-...`). `None` if the line is not a
/// header line.
pub(crate) fn split_header(line: &str) -> Option<(&str, &str)> {
    let (k, v) = line.split_once(':')?;
    let key_ok = !k.is_empty() && k.bytes().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == b'-');
    key_ok.then_some((k, v.trim()))
}

fn check_value(key: &str, value: &str, line: usize) -> Result<(), ParseError> {
    let bad = |reason: &str| ParseError::new(line, ParseErrorKind::BadValue { key: key.into(), reason: reason.into() });
    if value.is_empty() {
        return Err(bad("empty value"));
    }
    if value.chars().any(char::is_control) {
        return Err(bad("control character"));
    }
    Ok(())
}

fn list(key: &str, value: &str, line: usize) -> Result<Vec<String>, ParseError> {
    value
        .split(',')
        .map(|t| {
            let t = t.trim();
            if t.is_empty() || t.contains(char::is_whitespace) {
                Err(ParseError::new(
                    line,
                    ParseErrorKind::BadValue { key: key.into(), reason: format!("`{t}` is not a list item") },
                ))
            } else {
                Ok(t.to_string())
            }
        })
        .collect()
}

impl HeaderFields {
    /// Takes one header line. Errors for unknown keys, duplicates and malformed values.
    pub fn apply(&mut self, key: &str, value: &str, line: usize) -> Result<(), ParseError> {
        check_value(key, value, line)?;
        let once = |slot: &Option<String>| {
            if slot.is_some() { Err(ParseError::new(line, ParseErrorKind::DuplicateKey(key.into()))) } else { Ok(()) }
        };
        let bad = |reason: String| ParseError::new(line, ParseErrorKind::BadValue { key: key.to_string(), reason });
        match key {
            "id" => {
                once(&self.id)?;
                if !is_slug(value) {
                    return Err(bad("an id is a slug: a-z, 0-9, and - . _ inside, at most 100 bytes".into()));
                }
                self.id = Some(value.to_string());
            }
            "title" => {
                once(&self.title)?;
                self.title = Some(value.to_string());
            }
            "clause" => self.clauses.push(value.to_string()),
            "level" => {
                if self.level.is_some() {
                    return Err(ParseError::new(line, ParseErrorKind::DuplicateKey(key.into())));
                }
                self.level = Some(value.parse().map_err(|e: super::UnknownLevel| bad(e.to_string()))?);
            }
            "profile" => self.profiles.extend(list(key, value, line)?),
            "requires" => {
                for r in list(key, value, line)? {
                    let req = Requirement::from_slug(&r).ok_or_else(|| bad(format!("`{r}` is not a slug")))?;
                    if !self.requires.contains(&req) {
                        self.requires.push(req);
                    }
                }
            }
            "setup" => {
                let x = Setup::parse(value).map_err(bad)?;
                let Setup::Object { motor, .. } = x;
                if self.setup.iter().any(|Setup::Object { motor: m, .. }| *m == motor) {
                    return Err(bad(format!("motor {motor} already has an object")));
                }
                self.setup.push(x);
            }
            "note" => self.notes.push(value.to_string()),
            k if k.starts_with("x-") && k.len() > 2 => self.extensions.push((k.to_string(), value.to_string())),
            k => return Err(ParseError::new(line, ParseErrorKind::UnknownKey(k.to_string()))),
        }
        Ok(())
    }

    /// Checks the required keys; `line` is reported for a missing one.
    pub fn finish(self, line: usize) -> Result<Header, ParseError> {
        let missing = |k: &str| ParseError::new(line, ParseErrorKind::MissingKey(k.into()));
        let header = Header {
            id: self.id.ok_or_else(|| missing("id"))?,
            title: self.title.ok_or_else(|| missing("title"))?,
            level: self.level.ok_or_else(|| missing("level"))?,
            clauses: self.clauses,
            profiles: self.profiles,
            requires: self.requires,
            setup: self.setup,
            notes: self.notes,
            extensions: self.extensions,
        };
        if header.clauses.is_empty() {
            return Err(missing("clause"));
        }
        if header.profiles.is_empty() {
            return Err(missing("profile"));
        }
        if !header.setup.is_empty() && !header.requires(&Requirement::Object) {
            return Err(ParseError::new(
                line,
                ParseErrorKind::BadValue {
                    key: "setup".into(),
                    reason: "a case with a setup requires `object` (add it to `requires:`)".into(),
                },
            ));
        }
        Ok(header)
    }
}

/// Parses a duration: `Nms` or `Ns`, at most [`MAX_DURATION`].
pub(crate) fn parse_duration(s: &str) -> Option<Duration> {
    let (digits, scale) = if let Some(d) = s.strip_suffix("ms") {
        (d, 1)
    } else if let Some(d) = s.strip_suffix('s') {
        (d, 1000)
    } else {
        return None;
    };
    if digits.is_empty() || digits.len() > 12 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let ms: u64 = digits.parse().ok()?;
    let d = Duration::from_millis(ms.checked_mul(scale)?);
    (d <= MAX_DURATION).then_some(d)
}

/// A cursor over one line, for the tokens after a directive.
pub(crate) struct Cursor<'a> {
    pub text: &'a str,
    pub pos: usize,
    pub line: usize,
    /// Column of `text[0]` in the line, 1-based.
    pub base: usize,
}

impl<'a> Cursor<'a> {
    pub fn new(text: &'a str, line: usize, base: usize) -> Cursor<'a> {
        Cursor { text, pos: 0, line, base }
    }

    fn err(&self, at: usize, kind: ParseErrorKind) -> ParseError {
        ParseError::at(self.line, self.base + at, kind)
    }

    pub fn skip_spaces(&mut self) {
        while self.text.as_bytes().get(self.pos).is_some_and(|b| *b == b' ' || *b == b'\t') {
            self.pos += 1;
        }
    }

    pub fn at_end(&mut self) -> bool {
        self.skip_spaces();
        self.pos >= self.text.len()
    }

    /// The next whitespace-delimited word, without consuming it.
    pub fn peek_word(&mut self) -> &'a str {
        self.skip_spaces();
        let rest = &self.text[self.pos..];
        let end = rest.find([' ', '\t']).unwrap_or(rest.len());
        &rest[..end]
    }

    pub fn take_word(&mut self) -> &'a str {
        let w = self.peek_word();
        self.pos += w.len();
        w
    }

    /// Reads a quoted string with escapes. With `elisions`, `{...}` are pieces; without, a `{`
    /// is refused (write `\x7B`).
    pub fn string(&mut self, form: Form, elisions: bool, out: &mut Expect) -> Result<(), ParseError> {
        self.skip_spaces();
        let b = self.text.as_bytes();
        let start = self.pos;
        if b.get(self.pos) != Some(&b'"') {
            return Err(self.err(self.pos, ParseErrorKind::BadString("expected `\"`".into())));
        }
        self.pos += 1;
        let mut lit = Vec::new();
        loop {
            let Some(&c) = b.get(self.pos) else {
                return Err(self.err(start, ParseErrorKind::BadString("no closing `\"`".into())));
            };
            match c {
                b'"' => {
                    self.pos += 1;
                    break;
                }
                b'{' => {
                    if !elisions {
                        return Err(
                            self.err(self.pos, ParseErrorKind::BadString("`{` in a sent string (write \\x7B)".into()))
                        );
                    }
                    let piece = self.braced_elision()?;
                    out.push_bytes(form, &std::mem::take(&mut lit));
                    out.push(form, piece);
                }
                _ => {
                    // Text up to the next `"` or `{`, decoded by the one unescaper.
                    let end = literal_end(b, self.pos);
                    let run = &self.text[self.pos..end];
                    unescape_into(run, &mut lit).map_err(|e| {
                        let (at, why) = match e {
                            UnescapeError::BadEscape(i) if run.as_bytes().get(i + 1) == Some(&b'x') => {
                                (i, "`\\x` needs two hex digits")
                            }
                            UnescapeError::BadEscape(i) => (i, "unknown escape (use \\n \\r \\t \\\\ or \\xHH)"),
                            UnescapeError::Unprintable(i) => (i, "raw control or non-ASCII character (escape it)"),
                        };
                        self.err(self.pos + at, ParseErrorKind::BadString(why.into()))
                    })?;
                    self.pos = end;
                }
            }
        }
        out.push_bytes(form, &lit);
        Ok(())
    }

    /// Reads a `{...}` elision at the cursor (which is on the `{`) and moves past the `}`.
    fn braced_elision(&mut self) -> Result<Piece, ParseError> {
        let rest = &self.text[self.pos..];
        let Some(end) = rest.find('}') else {
            return Err(self.err(self.pos, ParseErrorKind::BadElision(rest.to_string())));
        };
        let inner = &rest[1..end];
        let piece =
            elision(inner).ok_or_else(|| self.err(self.pos, ParseErrorKind::BadElision(format!("{{{inner}}}"))))?;
        self.pos += end + 1;
        Ok(piece)
    }

    /// Reads hex tokens up to the end of the line or the next string. With `elisions`, `??` and
    /// `{...}` are accepted.
    pub fn hex(&mut self, elisions: bool, out: &mut Expect) -> Result<(), ParseError> {
        loop {
            self.skip_spaces();
            let b = self.text.as_bytes();
            match b.get(self.pos) {
                None | Some(b'"') => return Ok(()),
                Some(b'{') if elisions => {
                    let piece = self.braced_elision()?;
                    out.push(Form::Hex, piece);
                }
                Some(_) => {
                    let at = self.pos;
                    let w = self.take_word();
                    if w == "??" && elisions {
                        out.push(Form::Hex, Piece::AnyByte);
                    } else if w.len() == 2 && w.bytes().all(|d| d.is_ascii_hexdigit()) {
                        let v =
                            u8::from_str_radix(w, 16).map_err(|_| self.err(at, ParseErrorKind::BadHex(w.into())))?;
                        out.push_bytes(Form::Hex, &[v]);
                    } else if w == "hex" {
                        continue;
                    } else {
                        return Err(self.err(at, ParseErrorKind::BadHex(w.to_string())));
                    }
                }
            }
        }
    }
}

fn range(s: &str) -> Option<(i64, i64)> {
    let (a, b) = s.split_once("..")?;
    let num = |t: &str| -> Option<i64> {
        let digits = t.strip_prefix('-').unwrap_or(t);
        if digits.is_empty() || digits.len() > 18 || !digits.bytes().all(|d| d.is_ascii_digit()) {
            return None;
        }
        t.parse().ok()
    };
    let (a, b) = (num(a)?, num(b)?);
    (a <= b).then_some((a, b))
}

/// The piece an elision's inside (between the braces) stands for: `KIND [CONSTRAINT] [as
/// NAME]`, where the constraint is a range `A..B` or a relation `NAME[*N][/D] +-P%`.
fn elision(inner: &str) -> Option<Piece> {
    let mut words: Vec<&str> = inner.split(' ').collect();
    let kind = words.first().copied()?;
    let mut capture = None;
    if words.len() >= 3 && words[words.len() - 2] == "as" {
        let name = words.pop()?;
        words.pop();
        if !is_capture_name(name) {
            return None;
        }
        capture = Some(name.to_string());
    }
    let rest = &words[1..];
    match (kind, rest, &capture) {
        ("line", [], None) => return Some(Piece::Line),
        ("any", [], None) => return Some(Piece::Any),
        ("text", [], None) => return Some(Piece::Text),
        ("byte", [], None) => return Some(Piece::AnyByte),
        _ => {}
    }
    let kind = match kind {
        "int" => ValueKind::Int,
        t @ ("u8" | "i8" | "u16" | "i16") => {
            ValueKind::Field(FieldType::new(if t.ends_with('8') { 1 } else { 2 }, t.starts_with('i'))?)
        }
        _ => return None,
    };
    let (range, relation) = match rest {
        [] => (None, None),
        [r] => (Some(range(r)?), None),
        [term, tol] => (None, Some(relation(term, tol)?)),
        _ => return None,
    };
    // A field without a capture or a relation names its range, as it always has.
    if matches!(kind, ValueKind::Field(_)) && range.is_none() && relation.is_none() && capture.is_none() {
        return None;
    }
    let v = Value { kind, range, relation, capture };
    v.check().ok()?;
    Some(v.into_piece())
}

/// `NAME[*N][/D]` and `+-P%`.
fn relation(term: &str, tol: &str) -> Option<Relation> {
    let small = |t: &str| -> Option<i64> {
        if t.is_empty() || t.len() > 7 || !t.bytes().all(|d| d.is_ascii_digit()) || t.starts_with('0') {
            return None;
        }
        t.parse().ok()
    };
    let (head, den) = match term.split_once('/') {
        Some((h, d)) => (h, small(d)?),
        None => (term, 1),
    };
    let (name, num) = match head.split_once('*') {
        Some((n, f)) => (n, small(f)?),
        None => (head, 1),
    };
    let p = tol.strip_prefix("+-")?.strip_suffix('%')?;
    if p.is_empty() || p.len() > 3 || !p.bytes().all(|d| d.is_ascii_digit()) || (p.len() > 1 && p.starts_with('0')) {
        return None;
    }
    let r = Relation { name: name.to_string(), num, den, tolerance: p.parse().ok()? };
    r.check().ok()?;
    Some(r)
}

#[derive(Default)]
struct StepBuilder {
    step: Step,
    started: bool,
}

/// Parses a transcript.
pub fn parse(text: &str) -> Result<Transcript, ParseError> {
    if text.len() > MAX_FILE_BYTES {
        return Err(ParseError::new(1, ParseErrorKind::TooLarge));
    }
    let mut magic = false;
    let mut fields = HeaderFields::default();
    let mut header: Option<Header> = None;
    let mut steps: Vec<Step> = Vec::new();
    let mut cur = StepBuilder::default();
    let mut comments: Vec<String> = Vec::new();
    let mut last_line = 1;
    for (n, raw) in lines(text) {
        last_line = n;
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(c) = line.strip_prefix('#') {
            // Comments attach to the next step; those among header lines are dropped.
            if magic {
                let c = c.strip_prefix(' ').unwrap_or(c);
                if c.chars().any(char::is_control) {
                    return Err(ParseError::new(n, ParseErrorKind::BadString("control character in a comment".into())));
                }
                comments.push(c.to_string());
            }
            continue;
        }
        if !magic {
            if line == MAGIC {
                magic = true;
                continue;
            }
            return Err(ParseError::new(
                n,
                match line.strip_prefix("gcl-transcript ") {
                    Some(v) => ParseErrorKind::UnsupportedVersion(v.trim().to_string()),
                    None => ParseErrorKind::MissingMagic,
                },
            ));
        }
        let indent = raw.len() - raw.trim_start().len();
        let word_end = line.find([' ', '\t']).unwrap_or(line.len());
        let word = &line[..word_end];
        if !matches!(word, "pause" | "send" | "expect") {
            if let Some((k, v)) = split_header(line) {
                if header.is_some() {
                    return Err(ParseError::new(n, ParseErrorKind::HeaderInBody(k.to_string())));
                }
                fields.apply(k, v, n)?;
                comments.clear();
                continue;
            }
            return Err(ParseError::at(n, indent + 1, ParseErrorKind::UnknownDirective(word.to_string())));
        }
        if header.is_none() {
            header = Some(std::mem::take(&mut fields).finish(n)?);
        }
        let mut cur_args = Cursor::new(&line[word_end..], n, indent + word_end + 1);
        match word {
            "pause" => {
                if cur.started {
                    steps.push(std::mem::take(&mut cur).step);
                }
                let w = cur_args.take_word();
                let d = parse_duration(w).ok_or_else(|| ParseError::new(n, ParseErrorKind::BadDuration(w.into())))?;
                start(&mut cur, n, &mut comments);
                cur.step.pause = Some(d);
            }
            "send" => {
                if cur.step.send.is_some() {
                    steps.push(std::mem::take(&mut cur).step);
                }
                start(&mut cur, n, &mut comments);
                let mut e = Expect::default();
                let form = if cur_args.peek_word() == "hex" {
                    cur_args.take_word();
                    cur_args.hex(false, &mut e)?;
                    Form::Hex
                } else {
                    cur_args.string(Form::Text, false, &mut e)?;
                    Form::Text
                };
                let bytes = e.exact_bytes().unwrap_or_default();
                cur.step.send = Some(HostBytes { bytes, form });
            }
            _ => {
                start(&mut cur, n, &mut comments);
                if cur_args.peek_word() == "within" {
                    cur_args.take_word();
                    let w = cur_args.take_word();
                    let dur = |t: &str| {
                        parse_duration(t).ok_or_else(|| ParseError::new(n, ParseErrorKind::BadDuration(t.into())))
                    };
                    // `within B`, or a window `within A..B`: no sooner than A, no later than B.
                    match w.split_once("..") {
                        Some((a, b)) => {
                            let (a, b) = (dur(a)?, dur(b)?);
                            if a > b {
                                return Err(ParseError::new(
                                    n,
                                    ParseErrorKind::BadCapture(format!(
                                        "timing window `{w}`: its lower bound is above its upper"
                                    )),
                                ));
                            }
                            cur.step.earliest = Some(a);
                            cur.step.within = Some(b);
                        }
                        None => cur.step.within = Some(dur(w)?),
                    }
                }
                let mut e = Expect::default();
                while !cur_args.at_end() {
                    if cur_args.peek_word() == "hex" {
                        cur_args.take_word();
                        cur_args.hex(true, &mut e)?;
                    } else if cur_args.text.as_bytes().get(cur_args.pos) == Some(&b'"') {
                        cur_args.string(Form::Text, true, &mut e)?;
                    } else {
                        let at = cur_args.pos;
                        let w = cur_args.take_word().to_string();
                        return Err(cur_args.err(at, ParseErrorKind::Unexpected(w)));
                    }
                }
                e.check().map_err(|m| ParseError::new(n, ParseErrorKind::BadExpect(m)))?;
                cur.step.expect = e;
                steps.push(std::mem::take(&mut cur).step);
            }
        }
        if word != "expect" && !cur_args.at_end() {
            let at = cur_args.pos;
            let w = cur_args.take_word().to_string();
            return Err(cur_args.err(at, ParseErrorKind::Unexpected(w)));
        }
    }
    if !magic {
        return Err(ParseError::new(1, ParseErrorKind::MissingMagic));
    }
    if cur.started {
        steps.push(cur.step);
    }
    let header = match header {
        Some(h) => h,
        None => fields.finish(last_line)?,
    };
    if steps.is_empty() {
        return Err(ParseError::new(last_line, ParseErrorKind::NoSteps));
    }
    let t = Transcript { header, steps };
    if let Err((i, why)) = t.check_captures() {
        let line = t.steps.get(i).map_or(last_line, |s| s.line);
        return Err(ParseError::new(line, ParseErrorKind::BadCapture(why)));
    }
    Ok(t)
}

fn start(cur: &mut StepBuilder, line: usize, comments: &mut Vec<String>) {
    if !cur.started {
        cur.started = true;
        cur.step.line = line;
        cur.step.comments = std::mem::take(comments);
    }
}
