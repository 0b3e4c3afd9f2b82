//! Matching a device's bytes against an [`Expect`], one byte at a time.
//!
//! The expectation is run as a small nondeterministic automaton: every way the bytes so far can
//! line up with the pieces is kept as a state. A byte that no state can take is where the
//! answer parts from the expectation; the match is complete as soon as one state has consumed
//! every piece, so an expectation is satisfied by the *shortest* prefix of the output that
//! matches it (the rest belongs to the next step). Integers are checked digit by digit against
//! their range, and two-byte fields against theirs after the high byte, so a wrong value is
//! reported at its first impossible byte rather than at the end of the line.

use std::collections::BTreeMap;

use gcl_model::realtime::FieldType;

use super::{Expect, Form, Piece, Value, ValueKind, hex_bytes, pieces_hex, pieces_text};

/// Values captured so far (`{int as p1}`), by name: what a relation later in the transcript
/// is measured against. A runner carries them from step to step.
pub type Captures = BTreeMap<String, i64>;

/// Most digits an integer may have (as `gcl_model::grammar::parse_integer`).
const MAX_DIGITS: u32 = 18;

#[derive(Debug, Clone, Eq)]
struct State {
    /// Index of the piece being matched; `pieces.len()` when every piece has matched.
    piece: usize,
    /// Progress inside the piece: bytes of a literal or field, characters of an integer.
    k: u32,
    /// Integer or field value so far (an integer's absolute value).
    acc: i64,
    /// An integer's minus sign.
    neg: bool,
    /// The values captured along this way through the pieces, in piece order.
    caps: Vec<i64>,
}

// (by hand: captures are compared only when there are some. `Vec`'s own comparison calls
// `memcmp` even for two empty vectors, whose pointers are dangling, and glibc's AVX-512
// `memcmp` then makes a masked load there that the CPU serves slowly: compared at every byte of
// an elision, that made a fuzzing campaign 15 % slower)
impl PartialEq for State {
    fn eq(&self, other: &State) -> bool {
        self.piece == other.piece
            && self.k == other.k
            && self.acc == other.acc
            && self.neg == other.neg
            && same_caps(&self.caps, &other.caps)
    }
}

/// Whether two lists of captured values are the same (without a `memcmp` of empty lists).
fn same_caps(a: &[i64], b: &[i64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y)
}

impl State {
    fn at(piece: usize) -> State {
        State { piece, k: 0, acc: 0, neg: false, caps: Vec::new() }
    }

    /// The start of the next piece, keeping the captures (and adding `captured`).
    fn next(&self, captured: Option<i64>) -> State {
        let mut caps = self.caps.clone();
        caps.extend(captured);
        State { piece: self.piece + 1, k: 0, acc: 0, neg: false, caps }
    }
}

/// What a relation is measured against, resolved when the matcher is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Base {
    /// A value an earlier step captured.
    Known(i64),
    /// The n-th value this expectation captures.
    Local(usize),
    /// A name nobody captured: no value matches.
    Unknown,
}

/// A value piece's capture and relation, resolved for the matcher.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct Slot {
    /// Its ordinal among this expectation's captures, if it captures.
    capture: Option<usize>,
    /// What its relation is measured against, if it has one.
    base: Option<Base>,
}

/// What a numeric piece accepts for one state.
#[derive(Debug, Clone, Copy)]
enum Reads {
    /// A GCL integer, within a range if any.
    Int(Option<(i64, i64)>),
    /// A binary field within `min..=max`.
    Field(FieldType, i64, i64),
}

/// What one more byte did to a match.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feed {
    /// The bytes so far can still become a complete answer.
    Alive,
    /// The bytes so far are a complete answer.
    Complete,
    /// No answer starts with the bytes so far: this byte is where they part.
    Dead,
}

/// An incremental matcher for one [`Expect`].
#[derive(Debug, Clone)]
pub struct Matcher {
    pieces: Vec<(Form, Piece)>,
    /// For each piece, its capture and relation (value pieces only).
    slots: Vec<Slot>,
    /// The values captured before this expectation.
    known: Captures,
    states: Vec<State>,
    /// Where the states alive before the last byte are, whose furthest reports what was
    /// expected ([`Matcher::best`]); found only when asked for.
    before: Before,
    consumed: usize,
    /// The states before the last byte when [`Before::Spare`], and room for the next byte's
    /// states (kept from byte to byte: no allocation per byte).
    spare: Vec<State>,
}

/// Where the states alive before the last byte fed are kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Before {
    /// They are the states now: no byte fed yet, or the last left every way as it was.
    Now,
    /// The one state now, a byte back in its literal.
    Back,
    /// In `spare`.
    Spare,
}

impl Matcher {
    /// A matcher at the start of `expect`, with no value captured before (a relation to one
    /// never matches).
    pub fn new(expect: &Expect) -> Matcher {
        Matcher::with_captures(expect, &Captures::new())
    }

    /// A matcher at the start of `expect`, given the values earlier steps captured.
    pub fn with_captures(expect: &Expect, known: &Captures) -> Matcher {
        let mut pieces: Vec<(Form, Piece)> = Vec::new();
        for (form, p) in expect.pieces() {
            match (pieces.last_mut(), p) {
                (Some((_, Piece::Bytes(prev))), Piece::Bytes(more)) => prev.extend_from_slice(more),
                _ => pieces.push((form, p.clone())),
            }
        }
        let mut local: Vec<&str> = Vec::new();
        let mut slots = Vec::with_capacity(pieces.len());
        for (_, p) in &pieces {
            let Piece::Value(v) = p else {
                slots.push(Slot::default());
                continue;
            };
            let base = v.relation.as_ref().map(|r| match local.iter().position(|n| *n == r.name) {
                Some(i) => Base::Local(i),
                None => known.get(&r.name).map_or(Base::Unknown, |v| Base::Known(*v)),
            });
            let capture = v.capture.as_deref().map(|n| {
                local.push(n);
                local.len() - 1
            });
            slots.push(Slot { capture, base });
        }
        let mut m = Matcher {
            pieces,
            slots,
            known: known.clone(),
            states: Vec::new(),
            before: Before::Now,
            consumed: 0,
            spare: Vec::new(),
        };
        let mut start = Vec::new();
        m.close(State::at(0), &mut start);
        m.states = start;
        m
    }

    /// Bytes fed so far.
    pub fn consumed(&self) -> usize {
        self.consumed
    }

    /// Whether the bytes fed so far are a complete answer.
    pub fn is_complete(&self) -> bool {
        self.states.iter().any(|s| s.piece == self.pieces.len())
    }

    /// Whether some answer still starts with the bytes fed so far.
    pub fn is_alive(&self) -> bool {
        !self.states.is_empty()
    }

    /// When the bytes fed so far are a complete answer: the values captured before it and
    /// the ones it captured (along the first complete way through the pieces).
    pub fn captures(&self) -> Option<Captures> {
        let done = self.states.iter().find(|s| s.piece == self.pieces.len())?;
        let mut out = self.known.clone();
        let names = self.pieces.iter().filter_map(|(_, p)| match p {
            Piece::Value(Value { capture: Some(n), .. }) => Some(n),
            _ => None,
        });
        for (n, v) in names.zip(&done.caps) {
            out.insert(n.clone(), *v);
        }
        Some(out)
    }

    /// Feeds one byte. Feeding a dead matcher keeps it dead.
    pub fn feed(&mut self, b: u8) -> Feed {
        if self.states.is_empty() {
            return Feed::Dead;
        }
        // One way through, inside a literal that this byte goes on with and does not end: the
        // way moves a byte on (what the general path below gives, without its bookkeeping).
        if let [s] = self.states.as_mut_slice()
            && let Some((_, Piece::Bytes(lit))) = self.pieces.get(s.piece)
            && (s.k as usize) + 1 < lit.len()
            && lit[s.k as usize] == b
        {
            s.k += 1;
            self.before = Before::Back;
            self.consumed += 1;
            return Feed::Alive;
        }
        self.feed_slowly(b)
    }

    /// [`Matcher::feed`] past its first shortcut (kept out of line, so that the shortcut, taken
    /// for most bytes, costs a small call).
    #[inline(never)]
    fn feed_slowly(&mut self, b: u8) -> Feed {
        // Inside elisions (`{any}`, `{line}`) waiting for the literal after each: every way is an
        // elision that takes this byte, followed by the way out of it at the literal's first byte,
        // which this byte does not begin. The general path would give the same ways again.
        if self.elisions_take(b) {
            self.before = Before::Now;
            self.consumed += 1;
            return Feed::Alive;
        }
        self.feed_every_way(b)
    }

    /// Whether the ways are pairs (an elision, the way out of it at the start of the literal
    /// after it) in which the elision takes `b` and the literal does not begin with it: then
    /// `b` leaves every way as it was (the elision goes on; its way out starts again).
    fn elisions_take(&self, b: u8) -> bool {
        self.states.len() >= 2
            && self.states.len().is_multiple_of(2)
            && self.states.chunks_exact(2).all(|pair| {
                let [e, out] = pair else { return false };
                let takes = match self.pieces.get(e.piece) {
                    Some((_, Piece::Any)) => true,
                    Some((_, Piece::Line)) => b != b'\n' && b != b'\r',
                    _ => false,
                };
                takes
                    && e.k == 0
                    && e.acc == 0
                    && !e.neg
                    && out.piece == e.piece + 1
                    && out.k == 0
                    && out.acc == 0
                    && !out.neg
                    && same_caps(&out.caps, &e.caps)
                    && matches!(self.pieces.get(out.piece), Some((_, Piece::Bytes(lit))) if lit.first().is_some_and(|&c| c != b))
            })
    }

    /// [`Matcher::feed`] by its general path: every state takes the byte, then the states
    /// reachable without a byte are added.
    fn feed_every_way(&mut self, b: u8) -> Feed {
        if self.states.is_empty() {
            return Feed::Dead;
        }
        let mut next = std::mem::take(&mut self.spare);
        next.clear();
        for s in &self.states {
            if let Some(t) = self.step(s.clone(), b) {
                self.close(t, &mut next);
            }
        }
        // (the states before this byte stay in `spare` until the next)
        self.spare = std::mem::replace(&mut self.states, next);
        self.before = Before::Spare;
        self.consumed += 1;
        if self.states.is_empty() {
            Feed::Dead
        } else if self.is_complete() {
            Feed::Complete
        } else {
            Feed::Alive
        }
    }

    /// The state that has matched the most pieces (the most progress inside its piece). A
    /// state inside a `{text}` ranks above every state of the piece after it: where a text
    /// parts, what was wanted is the text (the way out of it parts at the same byte).
    fn furthest(&self) -> Option<State> {
        self.furthest_of(&self.states)
    }

    /// [`Matcher::furthest`] of some states.
    fn furthest_of(&self, states: &[State]) -> Option<State> {
        let rank = |s: &State| match self.pieces.get(s.piece) {
            Some((_, Piece::Text)) => (s.piece + 1, u32::MAX),
            _ => (s.piece, s.k),
        };
        states.iter().max_by_key(|s| rank(s)).cloned()
    }

    /// The furthest state alive before the last byte fed (before any, the furthest at the
    /// start): where a match that the last byte killed parted.
    fn best(&self) -> State {
        match self.before {
            Before::Now => self.furthest(),
            Before::Back => self.states.first().map(|s| State { k: s.k.saturating_sub(1), ..s.clone() }),
            Before::Spare => self.furthest_of(&self.spare),
        }
        .unwrap_or(State::at(0))
    }

    /// What numeric piece `i` reads for state `s`; `None` for a piece that is not numeric or
    /// that nothing can match (a relation to a name nobody captured, a band outside a field).
    fn reads(&self, i: usize, s: &State) -> Option<Reads> {
        let (_, p) = self.pieces.get(i)?;
        Some(match p {
            Piece::Int(r) => Reads::Int(*r),
            Piece::Field { ty, min, max } => Reads::Field(*ty, *min, *max),
            Piece::Value(v) => {
                let band = match self.slots.get(i).and_then(|sl| sl.base) {
                    None => v.range,
                    Some(base) => {
                        let x = match base {
                            Base::Known(x) => x,
                            Base::Local(j) => *s.caps.get(j)?,
                            Base::Unknown => return None,
                        };
                        Some(v.relation.as_ref()?.band(x))
                    }
                };
                match v.kind {
                    ValueKind::Int => Reads::Int(band),
                    ValueKind::Field(ty) => {
                        let (lo, hi) = ty.range().into_inner();
                        let (a, b) = band.unwrap_or((lo, hi));
                        let (a, b) = (a.max(lo), b.min(hi));
                        if a > b {
                            return None;
                        }
                        Reads::Field(ty, a, b)
                    }
                }
            }
            _ => return None,
        })
    }

    /// Adds `s` and every state reachable from it without a byte.
    fn close(&self, s: State, out: &mut Vec<State>) {
        if out.contains(&s) {
            return;
        }
        let next = match self.pieces.get(s.piece).map(|(_, p)| p) {
            None | Some(Piece::AnyByte) => None,
            Some(Piece::Bytes(b)) => (s.k as usize >= b.len()).then(|| s.next(None)),
            Some(Piece::Line | Piece::Any) => Some(s.next(None)),
            Some(Piece::Text) => (s.k & TEXT_SEEN != 0).then(|| s.next(None)),
            Some(_) => {
                let capturing = self.slots.get(s.piece).is_some_and(|sl| sl.capture.is_some());
                match self.reads(s.piece, &s) {
                    Some(Reads::Int(r)) => {
                        let digits = s.k - u32::from(s.neg);
                        let v = if s.neg { -s.acc } else { s.acc };
                        (digits >= 1 && !(s.neg && s.acc == 0) && in_range(r, v))
                            .then(|| s.next(capturing.then_some(v)))
                    }
                    Some(Reads::Field(ty, min, max)) => {
                        let v = signed_value(ty, s.acc);
                        (s.k as usize == ty.size() && (min..=max).contains(&v)).then(|| s.next(capturing.then_some(v)))
                    }
                    None => None,
                }
            }
        };
        out.push(s);
        if let Some(next) = next {
            self.close(next, out);
        }
    }

    /// The state after `s` takes byte `b`, if it can.
    fn step(&self, s: State, b: u8) -> Option<State> {
        let (_, p) = self.pieces.get(s.piece)?;
        match p {
            Piece::Bytes(lit) => (lit.get(s.k as usize) == Some(&b)).then_some(State { k: s.k + 1, ..s }),
            Piece::Line => (b != b'\n' && b != b'\r').then_some(s),
            Piece::Any => Some(s),
            Piece::Text => step_text(s, b),
            Piece::AnyByte => Some(s.next(None)),
            _ => match self.reads(s.piece, &s)? {
                Reads::Int(r) => step_int(s, b, r),
                Reads::Field(ty, min, max) => step_field(s, b, ty, min, max),
            },
        }
    }

    /// How the expectation continues from where the furthest match stands, as written
    /// (escaped text, or hex when the piece there is in a hex segment).
    pub fn expected_rest(&self) -> String {
        let s = self.furthest().unwrap_or_else(|| self.best());
        self.render_from(&s)
    }

    /// As [`Matcher::expected_rest`], from the furthest state before the last byte fed (what was
    /// expected at the byte that killed the match).
    pub fn expected_at_parting(&self) -> String {
        self.render_from(&self.best())
    }

    /// The form of the piece where the furthest match stands.
    pub fn form_at_parting(&self) -> Form {
        self.pieces.get(self.best().piece).or(self.pieces.last()).map_or(Form::Text, |(f, _)| *f)
    }

    fn render_from(&self, s: &State) -> String {
        let mut parts: Vec<(Form, Piece)> = Vec::new();
        for (i, (form, p)) in self.pieces.iter().enumerate().skip(s.piece) {
            match p {
                Piece::Bytes(b) if i == s.piece => {
                    let rest = b.get(s.k as usize..).unwrap_or_default();
                    if !rest.is_empty() {
                        parts.push((*form, Piece::Bytes(rest.to_vec())));
                    }
                }
                // A relation whose value is known by now shows the band it stands for: what
                // the answer had to be, in numbers (the whole expectation shows the relation).
                Piece::Value(Value { relation: Some(_), capture: None, .. }) => match self.reads(i, s) {
                    Some(Reads::Int(r)) => parts.push((*form, Piece::Int(r))),
                    Some(Reads::Field(ty, min, max)) => parts.push((*form, Piece::Field { ty, min, max })),
                    None => parts.push((*form, p.clone())),
                },
                _ => parts.push((*form, p.clone())),
            }
        }
        render(&parts)
    }
}

/// Renders pieces for people: consecutive pieces of one form together, text escaped, hex as
/// tokens, segments separated by a space.
fn render(parts: &[(Form, Piece)]) -> String {
    let mut out = String::new();
    let mut i = 0;
    while i < parts.len() {
        let form = parts[i].0;
        let mut j = i;
        while j < parts.len() && parts[j].0 == form {
            j += 1;
        }
        let ps: Vec<Piece> = parts[i..j].iter().map(|(_, p)| p.clone()).collect();
        if !out.is_empty() {
            out.push(' ');
        }
        match form {
            Form::Text => out.push_str(&pieces_text(&ps)),
            Form::Hex => out.push_str(&pieces_hex(&ps)),
        }
        i = j;
    }
    out
}

/// Shows device bytes in a form: escaped text or hex.
pub fn show(bytes: &[u8], form: Form) -> String {
    match form {
        Form::Text => super::escape_text(bytes),
        Form::Hex => hex_bytes(bytes),
    }
}

/// In a `{text}` state's `k`: a byte other than LF and CR has been taken.
const TEXT_SEEN: u32 = 8;
/// In a `{text}` state's `k` (low bits): how far the present line is known to be from a
/// status. 0 to 2: it is so far the first 0 to 2 bytes of `ERR`; [`TEXT_FREE`]: it is not.
const TEXT_FREE: u32 = 3;
const TEXT_LINE: u32 = 7;

/// A `{text}`'s next byte: a line break starts a new line; a line that begins with `ERR` (a
/// status answer) is where the text parts.
fn step_text(s: State, b: u8) -> Option<State> {
    if b == b'\n' || b == b'\r' {
        return Some(State { k: s.k & TEXT_SEEN, ..s });
    }
    let line = match (s.k & TEXT_LINE, b) {
        (0, b'E') => 1,
        (1, b'R') => 2,
        (2, b'R') => return None,
        _ => TEXT_FREE,
    };
    Some(State { k: TEXT_SEEN | line, ..s })
}

/// An integer's next character.
fn step_int(s: State, b: u8, r: Option<(i64, i64)>) -> Option<State> {
    let digits = s.k - u32::from(s.neg);
    if b == b'-' && s.k == 0 {
        let ok = r.is_none_or(|(lo, _)| lo <= -1);
        return ok.then_some(State { k: 1, neg: true, ..s });
    }
    if !b.is_ascii_digit() || digits >= MAX_DIGITS || (digits >= 1 && s.acc == 0) {
        return None;
    }
    let acc = s.acc * 10 + i64::from(b - b'0');
    let t = State { k: s.k + 1, acc, ..s };
    extendable(r, t.neg, acc, digits + 1).then_some(t)
}

/// A binary field's next byte.
fn step_field(s: State, b: u8, ty: FieldType, min: i64, max: i64) -> Option<State> {
    let acc = (s.acc << 8) | i64::from(b);
    let k = s.k + 1;
    if k as usize == ty.size() {
        // The range check happens in `close`; a value out of range leaves a state that
        // cannot advance, so check it here to die on this byte.
        (min..=max).contains(&signed_value(ty, acc)).then_some(State { k, acc, ..s })
    } else {
        // High byte of a two-byte field: some low byte must land in range.
        let (lo, hi) = if ty.signed() {
            let h = i64::from(b as i8);
            (h * 256, h * 256 + 255)
        } else {
            (acc * 256, acc * 256 + 255)
        };
        (lo <= max && hi >= min).then_some(State { k, acc, ..s })
    }
}

/// The value of a whole field from its bytes accumulated big-endian into `acc`.
fn signed_value(ty: FieldType, acc: i64) -> i64 {
    match ty {
        FieldType::I8 => i64::from(acc as u8 as i8),
        FieldType::I16 => i64::from(acc as u16 as i16),
        FieldType::U8 | FieldType::U16 => acc,
    }
}

fn in_range(r: Option<(i64, i64)>, v: i64) -> bool {
    r.is_none_or(|(lo, hi)| (lo..=hi).contains(&v))
}

/// Whether an integer whose first `digits` digits give `acc` (absolute value) can still end in
/// range by appending digits (never after a leading zero, at most [`MAX_DIGITS`]).
fn extendable(r: Option<(i64, i64)>, neg: bool, acc: i64, digits: u32) -> bool {
    let Some((lo, hi)) = r else { return true };
    let max_extra = if acc == 0 { 0 } else { MAX_DIGITS - digits };
    let (lo, hi) = (i128::from(lo), i128::from(hi));
    let mut scale: i128 = 1;
    for _ in 0..=max_extra {
        let a = i128::from(acc) * scale;
        let b = a + scale - 1;
        let (vmin, vmax) = if neg { (-b, -a) } else { (a, b) };
        if vmin <= hi && vmax >= lo {
            return true;
        }
        scale *= 10;
    }
    false
}

/// Where a device's answer stands against an expectation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// The first `n` bytes are a complete answer.
    Complete(usize),
    /// Every byte fits, but the answer is not complete yet.
    Partial,
    /// The answer parts from the expectation at this byte offset.
    Parted(usize),
}

/// Runs `actual` through a fresh matcher: the shortest complete prefix, a partial match, or
/// the offset where the bytes part from the expectation.
pub fn match_prefix(expect: &Expect, actual: &[u8]) -> Outcome {
    let mut m = Matcher::new(expect);
    if m.is_complete() {
        return Outcome::Complete(0);
    }
    for (i, &b) in actual.iter().enumerate() {
        match m.feed(b) {
            Feed::Complete => return Outcome::Complete(i + 1),
            Feed::Dead => return Outcome::Parted(i),
            Feed::Alive => {}
        }
    }
    Outcome::Partial
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Form, Piece};
    use gcl_model::realtime::FieldType;

    fn text(parts: &[Piece]) -> Expect {
        let mut e = Expect::default();
        for p in parts {
            e.push(Form::Text, p.clone());
        }
        e
    }

    fn b(s: &str) -> Piece {
        Piece::Bytes(s.as_bytes().to_vec())
    }

    /// A piece for [`feeding_fast_is_feeding_every_way`], over a small alphabet so that bytes
    /// often go on with a literal.
    fn piece() -> impl proptest::strategy::Strategy<Value = Piece> {
        use proptest::prelude::*;
        prop_oneof![
            4 => proptest::collection::vec(proptest::sample::select(b"AB1-\n\r".to_vec()), 1..6).prop_map(Piece::Bytes),
            1 => (-20i64..20, 0i64..40).prop_map(|(lo, w)| Piece::Int(Some((lo, lo + w)))),
            1 => Just(Piece::Int(None)),
            1 => Just(Piece::Line),
            1 => Just(Piece::Any),
            1 => Just(Piece::Text),
            1 => Just(Piece::AnyByte),
        ]
    }

    proptest::proptest! {
        /// The fast path of [`Matcher::feed`] (one way through, inside a literal) answers every
        /// byte as the general path does: the same outcome, progress, captures and what was
        /// expected where the bytes part; and [`Expect::matches_with`] (bytes compared when
        /// nothing is elided) answers a whole answer as the general path does.
        #[test]
        fn feeding_fast_is_feeding_every_way(
            parts in proptest::collection::vec(piece(), 1..6),
            bytes in proptest::collection::vec(proptest::sample::select(b"AB1-2\n\rx".to_vec()), 0..40),
        ) {
            let e = text(&parts);
            // (whole answers: an expectation without elisions is compared as bytes)
            let known = Captures::from([("p1".to_string(), 5)]);
            let mut whole = Matcher::with_captures(&e, &known);
            let dead = bytes.iter().any(|&b| whole.feed_every_way(b) == Feed::Dead);
            proptest::prop_assert_eq!(e.matches_with(&known, &bytes), if dead { None } else { whole.captures() });
            let mut fast = Matcher::new(&e);
            let mut general = fast.clone();
            for &b in &bytes {
                proptest::prop_assert_eq!(fast.feed(b), general.feed_every_way(b));
                proptest::prop_assert_eq!(fast.consumed(), general.consumed());
                proptest::prop_assert_eq!(fast.is_complete(), general.is_complete());
                proptest::prop_assert_eq!(fast.captures(), general.captures());
                proptest::prop_assert_eq!(fast.expected_at_parting(), general.expected_at_parting());
                proptest::prop_assert_eq!(fast.expected_rest(), general.expected_rest());
                proptest::prop_assert_eq!(fast.form_at_parting(), general.form_at_parting());
                proptest::prop_assert_eq!(&fast.states, &general.states);
                proptest::prop_assert_eq!(fast.best(), general.best());
            }
        }

        /// The same, for answers with elisions between literals (a banner: `RESET{any}BarrettHand
        /// Firmware{any}\n\r=> `), where the bytes inside an elision take the shortcut.
        #[test]
        fn feeding_elisions_fast_is_feeding_every_way(
            parts in proptest::collection::vec(
                (proptest::bool::ANY, proptest::collection::vec(proptest::sample::select(b"AB\n\r".to_vec()), 1..4)),
                1..4,
            ),
            bytes in proptest::collection::vec(proptest::sample::select(b"AB1\n\rx".to_vec()), 0..40),
        ) {
            let mut pieces = vec![b("A")];
            for (any, lit) in parts {
                pieces.push(if any { Piece::Any } else { Piece::Line });
                pieces.push(Piece::Bytes(lit));
            }
            let e = text(&pieces);
            let mut fast = Matcher::new(&e);
            let mut general = fast.clone();
            for &b in &bytes {
                proptest::prop_assert_eq!(fast.feed(b), general.feed_every_way(b));
                proptest::prop_assert_eq!(fast.consumed(), general.consumed());
                proptest::prop_assert_eq!(fast.captures(), general.captures());
                proptest::prop_assert_eq!(fast.expected_rest(), general.expected_rest());
                proptest::prop_assert_eq!(&fast.states, &general.states);
                proptest::prop_assert_eq!(fast.best(), general.best());
            }
        }
    }

    #[test]
    fn a_banner_is_read_through_its_elisions() {
        let e = text(&[b("RESET"), Piece::Any, b("BarrettHand Firmware"), Piece::Any, b("\n\r=> ")]);
        let banner = b"RESET\n\rBarrettHand Firmware\n\rVersion 4.4x\n\r=> ";
        assert_eq!(match_prefix(&e, banner), Outcome::Complete(banner.len()));
        assert_eq!(match_prefix(&e, &banner[..30]), Outcome::Partial);
        assert_eq!(match_prefix(&e, b"RESET\n\rBarrettHand Firmwar\n\r=> "), Outcome::Partial);
    }

    #[test]
    fn exact_bytes_and_parting_offset() {
        let e = Expect::text(b"FGET DP\n\r1000\n\r=> ");
        assert_eq!(match_prefix(&e, b"FGET DP\n\r1000\n\r=> "), Outcome::Complete(18));
        assert_eq!(match_prefix(&e, b"FGET DP\n\r10"), Outcome::Partial);
        assert_eq!(match_prefix(&e, b"FGET DP\r\n1000"), Outcome::Parted(7));
        assert_eq!(match_prefix(&e, b"FGET DP\n\r1000\n\r=> more"), Outcome::Complete(18));
    }

    #[test]
    fn integers_in_range_part_at_the_first_impossible_digit() {
        let e = text(&[b("P "), Piece::Int(Some((4950, 5050))), b("\n")]);
        assert!(e.matches(b"P 5000\n"));
        assert!(e.matches(b"P 4950\n"));
        assert!(!e.matches(b"P 5051\n"));
        assert_eq!(match_prefix(&e, b"P 5123\n"), Outcome::Parted(3));
        assert_eq!(match_prefix(&e, b"P 05000\n"), Outcome::Parted(2));
        assert_eq!(match_prefix(&e, b"P -5\n"), Outcome::Parted(2));
        let neg = text(&[Piece::Int(Some((-550, 1250))), b(";")]);
        assert!(neg.matches(b"-12;"));
        assert!(neg.matches(b"0;"));
        assert!(!neg.matches(b"-0;"));
        assert!(!neg.matches(b"00;"));
        assert_eq!(match_prefix(&neg, b"-551;"), Outcome::Parted(3));
        let any = text(&[Piece::Int(None), b(";")]);
        assert!(any.matches(b"-123456789012345678;"));
        assert!(!any.matches(b"1234567890123456789;"));
    }

    #[test]
    fn line_and_any_are_lazy() {
        let e = text(&[b("RESET"), Piece::Any, b("BarrettHand Firmware"), Piece::Any, b("\n\r=> ")]);
        let out = b"RESET\n\rBarrettHand Firmware 4.4x\n\rmore\n\r=> ";
        assert_eq!(match_prefix(&e, out), Outcome::Complete(out.len()));
        assert_eq!(match_prefix(&e, b"RESET\n\rno banner\n\r=> "), Outcome::Partial);
        let l = text(&[b("V\n\r"), Piece::Line, b("\n\r=> ")]);
        assert!(l.matches(b"V\n\r\n\r=> "));
        assert!(l.matches(b"V\n\rversion 1\n\r=> "));
        assert!(!l.matches(b"V\n\rtwo\n\rlines\n\r=> "));
    }

    #[test]
    fn text_is_lines_that_are_not_a_status() {
        let e = text(&[b("VERS\n\r"), Piece::Text, b("\n\r=> ")]);
        assert!(e.matches(b"VERS\n\rGCL seed hand 0.1\n\r=> "));
        assert!(e.matches(b"VERS\n\rFirmware 4.4x\n\rBarrett Technology\n\r=> "));
        // A line that is `ERR` and a status parts the answer at its second R, first or last.
        assert_eq!(match_prefix(&e, b"VERS\n\rERR 64\n\r=> "), Outcome::Parted(8));
        assert_eq!(match_prefix(&e, b"VERS\n\rv1\n\rERR 64\n\r=> "), Outcome::Parted(12));
        assert!(!e.matches(b"VERS\n\rERR\n\r=> "));
        // ERR elsewhere on a line, and lines that begin like it, are text.
        assert!(e.matches(b"VERS\n\rno ERR here\n\r=> "));
        assert!(e.matches(b"VERS\n\rER\n\rEEROR\n\r=> "));
        // At least one byte that is not a line break: no answer, or empty lines, is not text.
        assert_eq!(match_prefix(&e, b"VERS\n\r=> "), Outcome::Partial);
        assert!(!e.matches(b"VERS\n\r\n\r\n\r=> "));
        assert!(e.matches(b"VERS\n\r\n\rx\n\r=> "));
        // Where it parts, the text is what was wanted.
        let mut m = Matcher::new(&e);
        for &c in b"VERS\n\rERR" {
            m.feed(c);
        }
        assert_eq!(m.expected_at_parting(), "{text}\\n\\r=> ");
    }

    #[test]
    fn binary_fields_and_wildcards() {
        let mut e = Expect::default();
        e.push_bytes(Form::Hex, b"*");
        e.push(Form::Hex, Piece::AnyByte);
        e.push(Form::Hex, Piece::Field { ty: FieldType::U16, min: 4950, max: 5050 });
        e.push(Form::Hex, Piece::Field { ty: FieldType::I8, min: -3, max: 3 });
        assert!(e.matches(&[b'*', 0x80, 0x13, 0x88, 0xFE]));
        // Little-endian 5000 parts at its first byte.
        assert_eq!(match_prefix(&e, &[b'*', 0x80, 0x88, 0x13, 0]), Outcome::Parted(2));
        assert_eq!(match_prefix(&e, &[b'*', 0x80, 0x13, 0x88, 0x04]), Outcome::Parted(4));
        let s16 = Piece::Field { ty: FieldType::I16, min: -550, max: 1250 };
        let mut t = Expect::default();
        t.push(Form::Hex, s16);
        t.push_bytes(Form::Hex, b"!");
        assert!(t.matches(&[0x01, 0x3B, b'!']));
        assert!(t.matches(&[0xFE, 0x00, b'!']));
        assert_eq!(match_prefix(&t, &[0x80, 0x00, b'!']), Outcome::Parted(0));
    }

    #[test]
    fn a_relation_shows_its_band_where_the_answer_parts() {
        let t = crate::parse(
            "gcl-transcript 1\nid: a\ntitle: t\nclause: c\nlevel: MUST\nprofile: seed\n\
             send hex 41\nexpect hex 2A {i8 4..127 as v1} {i8 v1/2 +-25%}\n",
        )
        .unwrap();
        let mut m = Matcher::new(&t.steps[0].expect);
        for b in [b'*', 80, 80] {
            m.feed(b);
        }
        assert!(!m.is_alive());
        assert_eq!(m.expected_at_parting(), "{i8 30..50}");
    }

    #[test]
    fn expected_rest_shows_what_was_wanted() {
        let e = Expect::text(b"FGET DP\n\r1000\n\r=> ");
        let mut m = Matcher::new(&e);
        for &c in b"FGET DP\r" {
            m.feed(c);
        }
        assert!(!m.is_alive());
        assert_eq!(m.expected_at_parting(), "\\n\\r1000\\n\\r=> ");
        let mut h = Expect::hex(b"*");
        h.push(Form::Hex, Piece::Field { ty: FieldType::U16, min: 0, max: 50 });
        let mut m = Matcher::new(&h);
        m.feed(b'*');
        m.feed(0x13);
        assert_eq!(m.expected_at_parting(), "{u16 0..50}");
        assert_eq!(m.form_at_parting(), Form::Hex);
    }
}
