//! # gcl-transcript: the `gcl-transcript 1` format of a conversation with a GCL hand
//!
//! A transcript is a header (a stable id, a title, the spec clauses it checks, a level, the
//! profiles it applies to, what it requires of the target) and a list of [`Step`]s. Each step
//! may pause, may send bytes to the hand, and then expects an answer: an [`Expect`] made of
//! exact bytes and *elisions* for values that legitimately vary (an integer in a range, any
//! line, lines of text that are not a status, any byte of a RealTime block, a two-byte field in
//! a range). The same file is a golden
//! vector, a fuzz seed and a regression case. `vectors/README.md` is the normative description
//! of the text; this crate owns its typed form, [`parse`] (untrusted text to [`Transcript`],
//! errors with line numbers), printing ([`Transcript::to_text`], canonical, so that
//! `parse(print(t)) == t`), matching device bytes against an [`Expect`] ([`matcher`]), the
//! `gcl record` script format ([`script`]) and the escaping of bytes in strings
//! ([`escape_text`], over the one escaping of [`gcl_model::escape`]).
//!
//! It is the crate `vectors/README.md` offers to other implementers: it does no I/O, reads no
//! clock and depends only on the pure reference model, so a host or a device written in Rust
//! can run the golden transcripts with its own transport. Sending the host side and reading
//! the answers is the caller's job (in this project, `gcl-harness`'s `replay` and `record`).
//!
//! ```
//! use gcl_transcript::matcher::{Feed, Matcher};
//!
//! let text = "gcl-transcript 1\n\
//!             id: vers\n\
//!             title: VERS answers one line\n\
//!             clause: manual: VERS\n\
//!             level: MUST\n\
//!             profile: seed\n\
//!             \n\
//!             send \"VERS\\r\"\n\
//!             expect \"VERS\\n\\r{line}\\n\\r=> \"\n";
//! let t = gcl_transcript::parse(text)?;
//! assert_eq!(t.header.id, "vers");
//! // Printing is canonical: reading the printed text gives the same transcript.
//! assert_eq!(gcl_transcript::parse(&t.to_text())?, t);
//!
//! // Feed a hand's answer byte by byte; the matcher says when it is complete or has parted.
//! let mut m = Matcher::new(&t.steps[0].expect);
//! let mut last = Feed::Alive;
//! for &b in b"VERS\n\rBH8-262 4.4\n\r=> " {
//!     last = m.feed(b);
//! }
//! assert_eq!(last, Feed::Complete);
//! assert!(!t.steps[0].expect.matches(b"VERS\n\rERR 32\n\r"));
//! # Ok::<(), gcl_transcript::ParseError>(())
//! ```
//!
//! In the matcher, values captured by name (`{i8 4..127 as v1}`) carry from step to step as
//! `Captures`; a relation (`{i8 v1/2 +-25%}`) is a range computed from one; and `{text}` is lines
//! none of which begins with `ERR`, tracked in a state's `k` like a line prefix. Strings are
//! unescaped by `gcl_model::escape`, the one unescaper.
//!
//! A header's `Setup` lines (`setup: object M AT`) name what must be in place before the first
//! step that no command can make; a transcript with one requires `object`, and `Header::objects`
//! gives where each motor meets one. The harness reads it in one place each: `suite::model_config`
//! (every fresh model a transcript runs on) and `conform::places_setup` (only the in-process `sim`
//! places objects; elsewhere a case with a setup is SKIP unless the operator declares `--fixture
//! object`; the device fuzzer leaves such cases out of its corpus).

pub mod matcher;
mod parse;
pub mod script;

use std::fmt::{self, Write as _};
use std::time::Duration;

use gcl_model::realtime::FieldType;

pub use matcher::{Captures, Feed, Matcher};
pub use parse::{HeaderFields, ParseError, ParseErrorKind, parse, parse_bytes};

/// The first line of every transcript: the format and its version.
pub const MAGIC: &str = "gcl-transcript 1";

/// How long a step without `within` may wait for its answer.
pub const DEFAULT_STEP_TIMEOUT: Duration = Duration::from_secs(2);

/// The longest duration the format accepts (24 h), so that arithmetic on it cannot overflow.
pub const MAX_DURATION: Duration = Duration::from_secs(86_400);

/// Transcript files larger than this are refused unread.
pub const MAX_FILE_BYTES: usize = 4 << 20;

pub use gcl_model::level::{Level, UnknownLevel};

/// Something a case needs from its target beyond a supervisory conversation. A runner skips
/// cases whose requirements the target (or the operator) does not grant.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Requirement {
    /// Moves motors (HI and motion commands): the hand must be free to move.
    Motion,
    /// Enters RealTime mode (LOOP).
    Realtime,
    /// Writes the EEPROM (FSAVE or PSAVE); the case restores the factory values at its end.
    Eeprom,
    /// Depends on a pause before ^C landing while motors still move.
    AbortTiming,
    /// Needs an object in the fingers' way, as its [`Setup`] lines place it: a runner places it
    /// (a simulator) or the operator declares it in place.
    Object,
    /// Any other requirement, by its slug.
    Other(String),
}

impl Requirement {
    /// The slug as written in files.
    pub fn as_str(&self) -> &str {
        match self {
            Requirement::Motion => "motion",
            Requirement::Realtime => "realtime",
            Requirement::Eeprom => "eeprom",
            Requirement::AbortTiming => "abort-timing",
            Requirement::Object => "object",
            Requirement::Other(s) => s,
        }
    }

    /// Reads a slug; unknown slugs become [`Requirement::Other`]. `None` if it is not a slug.
    pub fn from_slug(s: &str) -> Option<Requirement> {
        Some(match s {
            "motion" => Requirement::Motion,
            "realtime" => Requirement::Realtime,
            "eeprom" => Requirement::Eeprom,
            "abort-timing" => Requirement::AbortTiming,
            "object" => Requirement::Object,
            _ if is_slug(s) => Requirement::Other(s.to_string()),
            _ => return None,
        })
    }
}

impl fmt::Display for Requirement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Whether `s` is a slug: lower-case ASCII letters and digits, with `-`, `.` or `_` inside,
/// 1 to 100 bytes. Ids and requirements are slugs.
pub fn is_slug(s: &str) -> bool {
    let b = s.as_bytes();
    !b.is_empty()
        && b.len() <= 100
        && (b[0].is_ascii_lowercase() || b[0].is_ascii_digit())
        && b.iter().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || matches!(c, b'-' | b'.' | b'_'))
}

/// The header of a transcript.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Header {
    /// A stable slug naming the case (never a position); unique within a profile.
    pub id: String,
    /// One line for people.
    pub title: String,
    /// The spec clauses checked: a profile's decision as `decision:<id>`, or a source section
    /// such as `seed: Command FGET`. At least one.
    pub clauses: Vec<String>,
    /// How strongly the case binds.
    pub level: Level,
    /// The profiles the case applies to. At least one.
    pub profiles: Vec<String>,
    /// What the case needs from its target.
    pub requires: Vec<Requirement>,
    /// The physical set-up the case needs before its first step, one entry per `setup:` line.
    /// A case with a setup requires [`Requirement::Object`].
    pub setup: Vec<Setup>,
    /// Free text for people, one entry per `note:` line.
    pub notes: Vec<String>,
    /// `x-*` keys and their values, kept in order for tools that add their own.
    pub extensions: Vec<(String, String)>,
}

impl Header {
    /// Whether the case needs `r`.
    pub fn requires(&self, r: &Requirement) -> bool {
        self.requires.contains(r)
    }

    /// Where each motor 1..=4 meets an object when closing, as the setup places them.
    pub fn objects(&self) -> [Option<i64>; 4] {
        Setup::objects(&self.setup)
    }
}

/// The farthest position a [`Setup::Object`] may name, in encoder counts.
pub const MAX_OBJECT_POSITION: i64 = 1_000_000;

/// Something in or around the hand that a case needs before its first step and that no
/// command can make: a runner that can (a simulator) makes it, and on a real hand the operator
/// puts it in place and says so. Written `setup: object M AT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Setup {
    /// An object that motor `motor` (1..=4) meets at position `at` (encoder counts, 0 at the
    /// open stop) when closing: from there on it presses into the object.
    Object {
        /// The motor, 1..=4.
        motor: u8,
        /// Where it meets the object, 0..=[`MAX_OBJECT_POSITION`].
        at: i64,
    },
}

impl Setup {
    /// The value of its `setup:` line: `object 1 6000`.
    pub fn text(&self) -> String {
        match self {
            Setup::Object { motor, at } => format!("object {motor} {at}"),
        }
    }

    /// A list of set-ups for people: `object 1 8500 and object 3 0`.
    pub fn list(setup: &[Setup]) -> String {
        setup.iter().map(Setup::text).collect::<Vec<_>>().join(" and ")
    }

    /// Where each motor 1..=4 meets an object when closing, as `setup` places them.
    pub fn objects(setup: &[Setup]) -> [Option<i64>; 4] {
        let mut o = [None; 4];
        for s in setup {
            let Setup::Object { motor, at } = *s;
            if let Some(slot) = o.get_mut(usize::from(motor).wrapping_sub(1)) {
                *slot = Some(at);
            }
        }
        o
    }

    /// Reads the value of a `setup:` line.
    pub fn parse(s: &str) -> Result<Setup, String> {
        let words: Vec<&str> = s.split_whitespace().collect();
        match words.as_slice() {
            ["object", m, at] => {
                let motor = match m.as_bytes() {
                    [d @ b'1'..=b'4'] => d - b'0',
                    _ => return Err(format!("`{m}` is not a motor 1..4")),
                };
                let at = at
                    .parse::<i64>()
                    .ok()
                    .filter(|a| (0..=MAX_OBJECT_POSITION).contains(a) && a.to_string() == *at)
                    .ok_or_else(|| format!("`{at}` is not a position 0..{MAX_OBJECT_POSITION}"))?;
                Ok(Setup::Object { motor, at })
            }
            [kind, ..] if *kind != "object" => Err(format!("unknown setup `{kind}` (known: object)")),
            _ => Err("expected `object MOTOR POSITION`".into()),
        }
    }
}

impl fmt::Display for Setup {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text())
    }
}

/// How a chunk of bytes is written: as an escaped string or as hex bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Form {
    /// `"..."` with `\n \r \t \\ \xHH` escapes.
    #[default]
    Text,
    /// `hex 2A 13 88`.
    Hex,
}

/// Bytes the host sends.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct HostBytes {
    /// The bytes.
    pub bytes: Vec<u8>,
    /// How they are written.
    pub form: Form,
}

impl HostBytes {
    /// Bytes written as a string.
    pub fn text(bytes: impl Into<Vec<u8>>) -> HostBytes {
        HostBytes { bytes: bytes.into(), form: Form::Text }
    }

    /// Bytes written in hex.
    pub fn hex(bytes: impl Into<Vec<u8>>) -> HostBytes {
        HostBytes { bytes: bytes.into(), form: Form::Hex }
    }
}

/// One element of an expected answer.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Piece {
    /// These bytes exactly. Never empty inside an [`Expect`].
    Bytes(Vec<u8>),
    /// `{int}` / `{int A..B}`: a decimal integer as GCL prints them (`0`, or an optional `-`
    /// and digits without a leading zero, at most 18 digits), optionally within `A..=B`.
    Int(Option<(i64, i64)>),
    /// `{line}`: zero or more bytes other than LF and CR.
    Line,
    /// `{any}`: zero or more bytes of any value (as few as the rest of the answer needs).
    Any,
    /// `{text}`: one or more whole lines of text that are not a status answer. Its bytes hold
    /// at least one byte other than LF and CR, and no line among them (a run of bytes between
    /// LF or CR bytes) begins with `ERR`, the way a hand answers a refused line (`ERR 64`). It
    /// sits between line breaks: the byte before it (if any) and the byte after it are LF or
    /// CR ([`Expect::check`]).
    Text,
    /// `{byte}`, or `??` in hex: exactly one byte of any value.
    AnyByte,
    /// `{u8 A..B}`, `{i8 A..B}`, `{u16 A..B}`, `{i16 A..B}`: a binary field of a RealTime
    /// field type (two-byte types big-endian) whose value lies within `min..=max`.
    Field {
        /// The wire type.
        ty: FieldType,
        /// Lowest accepted value.
        min: i64,
        /// Highest accepted value.
        max: i64,
    },
    /// An integer or a binary field that is captured under a name (`{i8 1..127 as v1}`), or
    /// whose accepted values follow from a value captured before (`{i8 v1*2 +-25%}`), or
    /// both. Without a capture or a relation it is written as [`Piece::Int`] or
    /// [`Piece::Field`] ([`Expect::push`] keeps that normal form).
    Value(Value),
}

impl Piece {
    /// Whether the piece can match a varying number of bytes (an expectation must not end
    /// with one: the match would be cut at its shortest).
    pub fn is_variable(&self) -> bool {
        matches!(
            self,
            Piece::Int(_) | Piece::Line | Piece::Any | Piece::Text | Piece::Value(Value { kind: ValueKind::Int, .. })
        )
    }
}

/// What kind of value a [`Value`] piece reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ValueKind {
    /// A decimal integer as `{int}` reads it.
    Int,
    /// A binary field of a RealTime field type, as `{u8 ..}`, `{i16 ..}` read it.
    Field(FieldType),
}

impl fmt::Display for ValueKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ValueKind::Int => f.write_str("int"),
            ValueKind::Field(ty) => write!(f, "{ty}"),
        }
    }
}

/// An integer or a binary field with a name and/or a relation to a value captured before.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Value {
    /// What is read.
    pub kind: ValueKind,
    /// The accepted values, `A..B` inclusive (`None`: any; a field's type bounds it). Never
    /// together with a relation.
    pub range: Option<(i64, i64)>,
    /// The accepted values as a band around a multiple of a captured value.
    pub relation: Option<Relation>,
    /// The name the value read is captured under, for relations later in the transcript.
    pub capture: Option<String>,
}

/// Most bytes a capture name may have.
pub const MAX_NAME: usize = 32;

/// The largest factor or divisor of a [`Relation`].
pub const MAX_FACTOR: i64 = 1_000_000;

/// The largest tolerance of a [`Relation`], in percent.
pub const MAX_TOLERANCE: u32 = 100;

/// Whether `s` can name a captured value: a lower-case letter, then lower-case letters, digits
/// and `_`, at most [`MAX_NAME`] bytes.
pub fn is_capture_name(s: &str) -> bool {
    let b = s.as_bytes();
    !b.is_empty()
        && b.len() <= MAX_NAME
        && b[0].is_ascii_lowercase()
        && b.iter().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == b'_')
}

/// `NAME[*N][/D] +-P%`: a value within P percent of the captured value NAME times N / D.
///
/// The band is rounded outward to whole numbers: with `E` = NAME × N / D (exactly), a value
/// `x` matches when `floor(E - |E| × P / 100) <= x <= ceil(E + |E| × P / 100)`.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Relation {
    /// The captured value it is relative to.
    pub name: String,
    /// The factor's numerator, 1..=[`MAX_FACTOR`].
    pub num: i64,
    /// The factor's denominator, 1..=[`MAX_FACTOR`].
    pub den: i64,
    /// The tolerance in percent, 0..=[`MAX_TOLERANCE`].
    pub tolerance: u32,
}

impl Relation {
    /// `name * num / den` within `tolerance` percent.
    pub fn new(name: impl Into<String>, num: i64, den: i64, tolerance: u32) -> Relation {
        Relation { name: name.into(), num, den, tolerance }
    }

    /// The accepted values, inclusive, when the captured value is `v`.
    pub fn band(&self, v: i64) -> (i64, i64) {
        let (num, den) = (i128::from(self.num.max(1)), i128::from(self.den.max(1)));
        let p = i128::from(self.tolerance.min(MAX_TOLERANCE));
        // E = v * num / den; the band's ends are E * (100 -+ p) / 100, taken over |E|.
        let e = i128::from(v) * num;
        let d = den * 100;
        let (a, b) = (e * (100 - p), e * (100 + p));
        let (lo, hi) = if e >= 0 { (a, b) } else { (b, a) };
        let clamp = |x: i128| x.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64;
        (clamp(lo.div_euclid(d)), clamp(-((-hi).div_euclid(d))))
    }

    /// The relation as written inside an elision: `v1*2 +-25%`.
    pub fn text(&self) -> String {
        let mut s = self.name.clone();
        if self.num != 1 {
            let _ = write!(s, "*{}", self.num);
        }
        if self.den != 1 {
            let _ = write!(s, "/{}", self.den);
        }
        let _ = write!(s, " +-{}%", self.tolerance);
        s
    }

    fn check(&self) -> Result<(), String> {
        if !is_capture_name(&self.name) {
            return Err(format!("`{}` is not a capture name", self.name));
        }
        if !(1..=MAX_FACTOR).contains(&self.num) || !(1..=MAX_FACTOR).contains(&self.den) {
            return Err(format!("`{}`: factors are 1..{MAX_FACTOR}", self.text()));
        }
        if self.tolerance > MAX_TOLERANCE {
            return Err(format!("`{}`: a tolerance is at most {MAX_TOLERANCE}%", self.text()));
        }
        Ok(())
    }
}

impl Value {
    /// The piece this value is: [`Piece::Int`] or [`Piece::Field`] when it has neither a
    /// capture nor a relation, else [`Piece::Value`].
    pub fn into_piece(self) -> Piece {
        match (&self.capture, &self.relation, self.kind) {
            (None, None, ValueKind::Int) => Piece::Int(self.range),
            (None, None, ValueKind::Field(ty)) => {
                let (min, max) = self.range.unwrap_or_else(|| ty.range().into_inner());
                Piece::Field { ty, min, max }
            }
            _ => Piece::Value(self),
        }
    }

    fn check(&self) -> Result<(), String> {
        if let Some((a, b)) = self.range {
            let fits = match self.kind {
                ValueKind::Int => a <= b,
                ValueKind::Field(ty) => a <= b && ty.range().contains(&a) && ty.range().contains(&b),
            };
            if !fits {
                return Err(format!("{}: range outside the field or empty", elision_text(&Piece::Value(self.clone()))));
            }
        }
        if self.range.is_some() && self.relation.is_some() {
            return Err("a value has a range or a relation, not both".into());
        }
        if let Some(r) = &self.relation {
            r.check()?;
        }
        if let Some(n) = &self.capture
            && !is_capture_name(n)
        {
            return Err(format!("`{n}` is not a capture name"));
        }
        Ok(())
    }
}

/// A run of pieces written in one [`Form`].
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Segment {
    /// How the segment is written.
    pub form: Form,
    /// Its pieces: never empty, no empty [`Piece::Bytes`], no two adjacent `Bytes`.
    pub pieces: Vec<Piece>,
}

/// What the hand is expected to answer in one step.
///
/// Built with [`Expect::push`] and friends, which keep it in the normal form the printer and
/// the parser agree on (adjacent segments of one form merged, adjacent bytes merged).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Expect {
    /// The segments, in order. Empty: the step expects nothing.
    pub segments: Vec<Segment>,
}

impl Expect {
    /// Expects nothing.
    pub fn nothing() -> Expect {
        Expect::default()
    }

    /// Expects exactly these bytes, written as a string.
    pub fn text(bytes: &[u8]) -> Expect {
        let mut e = Expect::default();
        e.push_bytes(Form::Text, bytes);
        e
    }

    /// Expects exactly these bytes, written in hex.
    pub fn hex(bytes: &[u8]) -> Expect {
        let mut e = Expect::default();
        e.push_bytes(Form::Hex, bytes);
        e
    }

    /// Appends a piece written in `form`, keeping the normal form.
    pub fn push(&mut self, form: Form, piece: Piece) {
        let piece = match piece {
            Piece::Value(v) => v.into_piece(),
            p => p,
        };
        if let Piece::Bytes(b) = &piece
            && b.is_empty()
        {
            return;
        }
        match self.segments.last_mut() {
            Some(seg) if seg.form == form => match (seg.pieces.last_mut(), piece) {
                (Some(Piece::Bytes(prev)), Piece::Bytes(more)) => prev.extend_from_slice(&more),
                (_, p) => seg.pieces.push(p),
            },
            _ => self.segments.push(Segment { form, pieces: vec![piece] }),
        }
    }

    /// Appends exact bytes.
    pub fn push_bytes(&mut self, form: Form, bytes: &[u8]) {
        self.push(form, Piece::Bytes(bytes.to_vec()));
    }

    /// Whether nothing is expected.
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// Every piece with the form of its segment, in order.
    pub fn pieces(&self) -> impl Iterator<Item = (Form, &Piece)> {
        self.segments.iter().flat_map(|s| s.pieces.iter().map(move |p| (s.form, p)))
    }

    /// The exact bytes expected, if the expectation has no elision.
    pub fn exact_bytes(&self) -> Option<Vec<u8>> {
        let mut out = Vec::new();
        for (_, p) in self.pieces() {
            match p {
                Piece::Bytes(b) => out.extend_from_slice(b),
                _ => return None,
            }
        }
        Some(out)
    }

    /// Checks the rules the parser enforces: ranges ordered and representable, no variable
    /// elision at the end, `{text}` between line breaks.
    pub fn check(&self) -> Result<(), String> {
        let pieces: Vec<&Piece> = self.pieces().map(|(_, p)| p).collect();
        let is_break = |b: Option<&u8>| matches!(b, Some(b'\n' | b'\r'));
        for (i, p) in pieces.iter().enumerate() {
            if !matches!(p, Piece::Text) {
                continue;
            }
            let before = i.checked_sub(1).map(|j| pieces[j]);
            let after = pieces.get(i + 1);
            let ok_before = match before {
                None => true,
                Some(Piece::Bytes(b)) => is_break(b.last()),
                Some(_) => false,
            };
            let ok_after = matches!(after, Some(Piece::Bytes(b)) if is_break(b.first()));
            if !ok_before || !ok_after {
                return Err("{text} must stand between line breaks (LF or CR before it, unless it begins the expectation, and after it)".into());
            }
        }
        for (_, p) in self.pieces() {
            match p {
                Piece::Int(Some((a, b))) if a > b => return Err(format!("{{int {a}..{b}}}: empty range")),
                Piece::Field { ty, min, max } => {
                    let r = ty.range();
                    if min > max || !r.contains(min) || !r.contains(max) {
                        let (lo, hi) = r.into_inner();
                        return Err(format!("{{{ty} {min}..{max}}}: range outside {lo}..{hi}"));
                    }
                }
                Piece::Value(v) => v.check()?,
                _ => {}
            }
        }
        if self.pieces().last().is_some_and(|(_, p)| p.is_variable()) {
            return Err("an expectation must not end with {int}, {line}, {any} or {text}".into());
        }
        Ok(())
    }

    /// Whether `actual` is exactly a complete answer (the whole of it, not a prefix), with no
    /// value captured before (a relation to one never matches).
    pub fn matches(&self, actual: &[u8]) -> bool {
        self.matches_with(&Captures::new(), actual).is_some()
    }

    /// Whether `actual` is exactly a complete answer given the values captured by earlier
    /// steps; if so, those values and the ones this answer captured.
    pub fn matches_with(&self, captured: &Captures, actual: &[u8]) -> Option<Captures> {
        // (no elision: the answer is these bytes and nothing else, and captures nothing)
        if self.pieces().all(|(_, p)| matches!(p, Piece::Bytes(_))) {
            let mut rest = actual;
            for (_, p) in self.pieces() {
                let Piece::Bytes(b) = p else { return None };
                rest = rest.strip_prefix(b.as_slice())?;
            }
            return rest.is_empty().then(|| captured.clone());
        }
        let mut m = Matcher::with_captures(self, captured);
        for &b in actual {
            if m.feed(b) == Feed::Dead {
                return None;
            }
        }
        m.captures()
    }

    /// The names this expectation captures, in order.
    pub fn captures(&self) -> impl Iterator<Item = &str> {
        self.pieces().filter_map(|(_, p)| match p {
            Piece::Value(Value { capture: Some(n), .. }) => Some(n.as_str()),
            _ => None,
        })
    }

    /// The relations this expectation holds values to, in order.
    pub fn relations(&self) -> impl Iterator<Item = &Relation> {
        self.pieces().filter_map(|(_, p)| match p {
            Piece::Value(Value { relation: Some(r), .. }) => Some(r),
            _ => None,
        })
    }

    /// The expectation as written after `expect` (without `within`).
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        if self.segments.is_empty() {
            return "\"\"".to_string();
        }
        for (i, seg) in self.segments.iter().enumerate() {
            if i > 0 {
                s.push(' ');
            }
            write_segment(&mut s, seg.form, &seg.pieces);
        }
        s
    }
}

/// One step: an optional pause, optional bytes to send, and the expected answer.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Step {
    /// The 1-based line of the step's first action in its source file; 0 when the step was
    /// built in code. Compare transcripts with [`Transcript::without_lines`] to ignore it.
    pub line: usize,
    /// `#` comment lines written before the step.
    pub comments: Vec<String>,
    /// Time to let pass before sending.
    pub pause: Option<Duration>,
    /// Bytes to send.
    pub send: Option<HostBytes>,
    /// How long the answer may take; [`DEFAULT_STEP_TIMEOUT`] (or a runner's override) when
    /// `None`.
    pub within: Option<Duration>,
    /// The soonest the answer may be complete (`within A..B` gives A): an answer complete
    /// sooner fails. Only with `within`.
    pub earliest: Option<Duration>,
    /// The answer.
    pub expect: Expect,
}

/// A whole transcript.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Transcript {
    /// Who the case is and what it checks.
    pub header: Header,
    /// What happens, in order.
    pub steps: Vec<Step>,
}

impl Transcript {
    /// The canonical text. [`parse`] of it gives back `self` (line numbers aside).
    pub fn to_text(&self) -> String {
        let mut s = String::with_capacity(256 + self.steps.len() * 64);
        let h = &self.header;
        s.push_str(MAGIC);
        s.push('\n');
        let _ = writeln!(s, "id: {}", h.id);
        let _ = writeln!(s, "title: {}", h.title);
        for c in &h.clauses {
            let _ = writeln!(s, "clause: {c}");
        }
        let _ = writeln!(s, "level: {}", h.level);
        if !h.profiles.is_empty() {
            let _ = writeln!(s, "profile: {}", h.profiles.join(", "));
        }
        if !h.requires.is_empty() {
            let r: Vec<&str> = h.requires.iter().map(Requirement::as_str).collect();
            let _ = writeln!(s, "requires: {}", r.join(", "));
        }
        for x in &h.setup {
            let _ = writeln!(s, "setup: {x}");
        }
        for n in &h.notes {
            let _ = writeln!(s, "note: {n}");
        }
        for (k, v) in &h.extensions {
            let _ = writeln!(s, "{k}: {v}");
        }
        for step in &self.steps {
            s.push('\n');
            write_step(&mut s, step);
        }
        s
    }

    /// Every byte the host sends, in order: the transcript's host side as one fuzz input.
    pub fn host_bytes(&self) -> Vec<u8> {
        self.steps.iter().filter_map(|s| s.send.as_ref()).flat_map(|s| s.bytes.iter().copied()).collect()
    }

    /// Checks the transcript's captures and relations: a name is captured once, and a relation
    /// refers to a name captured before it (earlier in its answer or in an earlier step). On
    /// error, the index of the first step that breaks the rule and why.
    pub fn check_captures(&self) -> Result<(), (usize, String)> {
        let mut known: Vec<&str> = Vec::new();
        for (i, step) in self.steps.iter().enumerate() {
            if step.earliest.is_some_and(|a| step.within.is_none_or(|w| a > w)) {
                return Err((i, "a timing window `within A..B` needs A <= B".into()));
            }
            for (_, p) in step.expect.pieces() {
                let Piece::Value(v) = p else { continue };
                if let Some(r) = &v.relation
                    && !known.contains(&r.name.as_str())
                {
                    return Err((i, format!("`{}` is not captured before it is used", r.name)));
                }
                if let Some(n) = &v.capture {
                    if known.contains(&n.as_str()) {
                        return Err((i, format!("`{n}` is captured twice")));
                    }
                    known.push(n);
                }
            }
        }
        Ok(())
    }

    /// A copy with every [`Step::line`] set to 0, for comparing a parsed transcript with a
    /// built one.
    pub fn without_lines(&self) -> Transcript {
        let mut t = self.clone();
        for s in &mut t.steps {
            s.line = 0;
        }
        t
    }
}

impl fmt::Display for Transcript {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_text())
    }
}

fn write_step(s: &mut String, step: &Step) {
    for c in &step.comments {
        if c.is_empty() {
            s.push_str("#\n");
        } else {
            let _ = writeln!(s, "# {c}");
        }
    }
    if let Some(p) = step.pause {
        let _ = writeln!(s, "pause {}", format_duration(p));
    }
    if let Some(send) = &step.send {
        s.push_str("send ");
        match send.form {
            Form::Text => {
                s.push('"');
                s.push_str(&escape_text(&send.bytes));
                s.push('"');
            }
            Form::Hex => {
                s.push_str("hex");
                for b in &send.bytes {
                    let _ = write!(s, " {b:02X}");
                }
            }
        }
        s.push('\n');
    }
    s.push_str("expect ");
    match (step.earliest, step.within) {
        (Some(a), Some(w)) => {
            let _ = write!(s, "within {}..{} ", format_duration(a), format_duration(w));
        }
        (_, Some(w)) => {
            let _ = write!(s, "within {} ", format_duration(w));
        }
        _ => {}
    }
    s.push_str(&step.expect.to_text());
    s.push('\n');
}

/// Writes a duration as the format does: whole seconds as `Ns`, anything else as `Nms`.
pub fn format_duration(d: Duration) -> String {
    let ms = d.as_millis();
    if ms.is_multiple_of(1000) && ms > 0 { format!("{}s", ms / 1000) } else { format!("{ms}ms") }
}

/// Escapes bytes for a transcript string: [`gcl_model::escape::escape`], plus `"` as `\x22`
/// and `{` as `\x7B` (they delimit strings and elisions).
pub fn escape_text(bytes: &[u8]) -> String {
    gcl_model::escape::escape_also(bytes, b"\"{")
}

/// Writes bytes as space-separated upper-case hex.
pub fn hex_bytes(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 3);
    for (i, b) in bytes.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        let _ = write!(s, "{b:02X}");
    }
    s
}

/// The elision syntax of a piece, `{...}` (the same in strings and hex segments; `??` is the
/// hex shorthand of `{byte}`); empty for [`Piece::Bytes`].
pub fn elision_text(p: &Piece) -> String {
    match p {
        Piece::Bytes(_) => String::new(),
        Piece::Int(None) => "{int}".into(),
        Piece::Int(Some((a, b))) => format!("{{int {a}..{b}}}"),
        Piece::Line => "{line}".into(),
        Piece::Any => "{any}".into(),
        Piece::Text => "{text}".into(),
        Piece::AnyByte => "{byte}".into(),
        Piece::Field { ty, min, max } => format!("{{{ty} {min}..{max}}}"),
        Piece::Value(v) => {
            let mut s = format!("{{{}", v.kind);
            if let Some((a, b)) = v.range {
                let _ = write!(s, " {a}..{b}");
            }
            if let Some(r) = &v.relation {
                let _ = write!(s, " {}", r.text());
            }
            if let Some(n) = &v.capture {
                let _ = write!(s, " as {n}");
            }
            s.push('}');
            s
        }
    }
}

/// Writes pieces in a form: a quoted string, or `hex` and tokens.
pub(crate) fn write_segment(s: &mut String, form: Form, pieces: &[Piece]) {
    match form {
        Form::Text => {
            s.push('"');
            s.push_str(&pieces_text(pieces));
            s.push('"');
        }
        Form::Hex => {
            s.push_str("hex");
            for p in pieces {
                s.push(' ');
                s.push_str(&pieces_hex(std::slice::from_ref(p)));
            }
        }
    }
}

/// Pieces as the inside of a string (no quotes).
pub(crate) fn pieces_text(pieces: &[Piece]) -> String {
    let mut s = String::new();
    for p in pieces {
        match p {
            Piece::Bytes(b) => s.push_str(&escape_text(b)),
            _ => s.push_str(&elision_text(p)),
        }
    }
    s
}

/// Pieces as hex tokens (no `hex` keyword).
pub(crate) fn pieces_hex(pieces: &[Piece]) -> String {
    let mut parts = Vec::new();
    for p in pieces {
        match p {
            Piece::Bytes(b) => parts.push(hex_bytes(b)),
            Piece::AnyByte => parts.push("??".into()),
            _ => parts.push(elision_text(p)),
        }
    }
    parts.join(" ")
}

#[cfg(test)]
mod tests;
