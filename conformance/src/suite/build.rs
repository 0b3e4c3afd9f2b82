//! Turning a case plan into a golden transcript: the plan's host side runs against the
//! in-process reference model through the same recorder `gcl record` uses, and each answer is
//! written down exactly, except where the plan's `Shape` says the protocol lets it vary.
//! Every elision is checked to match the model's own answer before the case is accepted.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::Profile;
use gcl_model::realtime::{ControlHeader, Field, RtFlag};
use gcl_model::spec::{CommandKind, ParamSpec, Scope};

use super::depends::prefix_motors;
use super::plan::{Bind, FieldRule, Plan, Range, Shape, Target};
use crate::record::{Captured, RecordOptions, answer_form, banner_expect, capture, suggest_within};
use gcl_host::SimLink;
use gcl_host::link::LinkError;
use gcl_transcript::matcher::Captures;
use gcl_transcript::script::{Action, ScriptStep};
use gcl_transcript::{
    Expect, Form, Header, HostBytes, Level, Piece, Relation, Requirement, Setup, Step, Transcript, Value, ValueKind,
    elision_text,
};

/// The header key listing every decision a case rests on (those it checks and those its
/// framing, preamble, read-backs and teardown touch), space-separated, in the profile's order.
pub const DECISIONS_KEY: &str = "x-decisions";

/// The clause prefix naming a decision a case checks.
pub const DECISION_CLAUSE: &str = "decision:";

/// The comment before a case's first step after its preamble: where what the case checks
/// begins (the fuzzer seeds its corpus from the steps after it).
pub(crate) const CHECK_COMMENT: &str = "the check";

/// Live values whose reading the protocol fixes (initialisation state, breakaway flags); every
/// other live value (position, strain, temperature, odometer, uptime, serial number) varies
/// from hand to hand and is elided to its parameter's range.
const DETERMINED_LIVE: &[&str] = &["S", "BD", "BP"];

/// A relation from the model's pairs (captured, related): the factor is the midpoint of their
/// ratios as a fraction over 100, and the tolerance the least whole percent that holds every
/// pair, plus `margin` points. `None` when no tolerance up to 100 % holds them all (or a
/// captured value is 0).
pub(crate) fn derive_relation(name: &str, pairs: &[(i64, i64)], margin: u32) -> Option<Relation> {
    if pairs.is_empty() || pairs.iter().any(|(a, _)| *a == 0) {
        return None;
    }
    let ratios: Vec<f64> = pairs.iter().map(|(a, b)| *b as f64 / *a as f64).collect();
    let lo = ratios.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = ratios.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut num = ((lo + hi) / 2.0 * 100.0).round() as i64;
    let mut den = 100i64;
    let g = gcd(num.abs(), den);
    if g > 1 {
        num /= g;
        den /= g;
    }
    fit_tolerance(name, num, den, pairs, margin)
}

/// `name * num / den` with the least whole-percent tolerance that holds every pair, plus
/// `margin` points (at most 100 %); `None` when none up to 100 % does.
pub(crate) fn fit_tolerance(name: &str, num: i64, den: i64, pairs: &[(i64, i64)], margin: u32) -> Option<Relation> {
    if num < 1 || den < 1 || pairs.is_empty() {
        return None;
    }
    let holds = |r: &Relation| {
        pairs.iter().all(|(a, b)| {
            let (x, y) = r.band(*a);
            (x..=y).contains(b)
        })
    };
    let tolerance = (0..=gcl_transcript::MAX_TOLERANCE).find(|t| holds(&Relation::new(name, num, den, *t)))?;
    Some(Relation::new(name, num, den, (tolerance + margin).min(gcl_transcript::MAX_TOLERANCE)))
}

/// The feedback velocity (LFV, before truncation) of a motor running at the control velocity
/// of an LCV `datum` with `lcvc`, reported with `lfvc` (0 acts as 1): the model's arithmetic
/// (the datum × LCVC in the profile's fixed point, in counts per ms, read in LFV's units).
pub(crate) fn lfv_exact(p: &Profile, datum: i64, lcvc: i64, lfvc: i64) -> f64 {
    let h = &p.hand;
    gcl_model::realtime::control_velocity(datum, lcvc, h.lcv_fraction_bits) * h.rt_velocity_counts_per_ms
        / h.lfv_counts_per_ms
        / lfvc.max(1) as f64
}

pub(crate) fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// A case before it runs.
#[derive(Debug, Clone)]
pub(crate) struct CaseDef {
    pub id: String,
    pub title: String,
    pub clauses: Vec<String>,
    pub level: Option<Level>,
    pub requires: Vec<Requirement>,
    /// What must be in place before the first step (objects), which the model is given too.
    pub setup: Vec<Setup>,
    pub notes: Vec<String>,
    pub plans: Vec<Plan>,
}

impl CaseDef {
    /// Names a decision of `p` the case rests on, when `p` has it (see [`CaseB::decision`]).
    pub fn decision(&mut self, p: &Profile, id: &str) {
        if p.decisions.iter().any(|d| d.id == id) {
            let c = format!("{DECISION_CLAUSE}{id}");
            if !self.clauses.contains(&c) {
                self.clauses.push(c);
            }
        }
    }
}

/// A case under construction, with the profile it is for.
pub(crate) struct CaseB {
    pub p: Arc<Profile>,
    pub def: CaseDef,
    pending_pause: Option<Duration>,
    pending_comments: Vec<String>,
}

impl CaseB {
    pub fn new(p: &Arc<Profile>, id: impl Into<String>, title: impl Into<String>) -> CaseB {
        CaseB {
            p: p.clone(),
            def: CaseDef {
                id: id.into(),
                title: title.into(),
                clauses: Vec::new(),
                level: None,
                requires: Vec::new(),
                setup: Vec::new(),
                notes: Vec::new(),
                plans: Vec::new(),
            },
            pending_pause: None,
            pending_comments: Vec::new(),
        }
    }

    /// A clause of the profile's source document: `seed: ...` or `manual: ...`.
    pub fn src(mut self, what: &str) -> CaseB {
        let c = format!("{}: {what}", source_label(&self.p));
        if !self.def.clauses.contains(&c) {
            self.def.clauses.push(c);
        }
        self
    }

    /// A decision of the profile the case checks, when the profile has it: `decision:<id>`.
    /// The case's level is the weakest among every decision it rests on (see [`build`]).
    pub fn decision(mut self, id: &str) -> CaseB {
        self.def.decision(&self.p, id);
        self
    }

    /// Sets the strongest level the case may have (its decisions may weaken it).
    pub fn level(mut self, l: Level) -> CaseB {
        self.def.level = Some(l);
        self
    }

    pub fn requires(mut self, r: Requirement) -> CaseB {
        if !self.def.requires.contains(&r) {
            self.def.requires.push(r);
        }
        self
    }

    /// An object that motor `motor` meets at `at` when closing, there before the first step:
    /// the golden says so (`setup:`), requires `object`, and the model runs with it.
    pub fn object(mut self, motor: u8, at: i64) -> CaseB {
        self.def.setup.push(Setup::Object { motor, at });
        self.requires(Requirement::Object)
    }

    pub fn note(mut self, n: impl Into<String>) -> CaseB {
        self.def.notes.push(n.into());
        self
    }

    fn push(mut self, action: Action, shape: Shape) -> CaseB {
        let step = ScriptStep {
            pause: self.pending_pause.take(),
            comments: std::mem::take(&mut self.pending_comments),
            ..ScriptStep::new(action)
        };
        self.def.plans.push(Plan { step, shape, within_floor: None, earliest: None, binds: Vec::new() });
        self
    }

    /// Gives the last step's answer this shape.
    pub fn shape_last(mut self, shape: Shape) -> CaseB {
        if let Some(p) = self.def.plans.last_mut() {
            p.shape = shape;
        }
        self
    }

    /// A comment written before the next step.
    pub fn comment(mut self, c: impl Into<String>) -> CaseB {
        self.pending_comments.push(c.into());
        self
    }

    /// The standard start of every case: ^C (idle prompt), RESET (banner elided), FDEF and
    /// PDEF (factory values in RAM whatever the EEPROM holds), and HI when motors must move.
    pub fn preamble(mut self, motion: bool) -> CaseB {
        self = self.comment("preamble: a known state").abort().line_shaped("RESET", Shape::Banner).line("FDEF");
        if self.p.command_id("PDEF").is_some() {
            self = self.line("PDEF");
        }
        if motion {
            self = self.requires(Requirement::Motion).line("HI");
        }
        self.comment(CHECK_COMMENT)
    }

    /// A step of a case script, its answer written exactly.
    pub fn step(self, action: Action) -> CaseB {
        self.push(action, Shape::Exact)
    }

    pub fn line(self, text: &str) -> CaseB {
        self.line_shaped(text, Shape::Exact)
    }

    pub fn line_shaped(self, text: &str, shape: Shape) -> CaseB {
        self.push(Action::Line(text.as_bytes().to_vec()), shape)
    }

    /// A host line whose answer is not awaited (the echo only).
    pub fn nowait(self, text: &str) -> CaseB {
        self.push(Action::NoWait(text.as_bytes().to_vec()), Shape::Exact)
    }

    /// A RealTime block, written in hex, with its answer shaped.
    pub fn block(self, bytes: &[u8], shape: Shape) -> CaseB {
        self.push(Action::Bytes { bytes: bytes.to_vec(), form: Form::Hex }, shape)
    }

    pub fn abort(self) -> CaseB {
        self.push(Action::abort(), Shape::Exact)
    }

    /// A pause before the next step.
    pub fn pause_ms(mut self, ms: u64) -> CaseB {
        self.pending_pause = Some(Duration::from_millis(ms));
        self
    }

    /// A get line (`FGET`/`PGET` by the first name's getter) with values shaped: positions
    /// (`P`) by `pos` per motor, other live values by their ranges.
    pub fn get(self, prefix: &str, names: &[&str], pos: Option<[Range; 4]>) -> CaseB {
        let p = self.p.clone();
        let Some(first) = names.first().and_then(|n| p.param_id(n)) else {
            return self.line(&format!("{prefix}FGET {}", names.join(" ")));
        };
        let getter = p.getter(first).to_string();
        let shape = values_shape(&p, prefix, &getter, names, pos);
        self.line_shaped(&format!("{prefix}{getter} {}", names.join(" ")), shape)
    }

    /// Shapes the last step's answer as [`CaseB::get`] shapes its line's (positions by
    /// `pos`): the step is a host line `[prefix]GETTER NAME...` whose getter is the first
    /// name's. A line whose first name is no parameter stays exact, as in `get`.
    pub fn values_last(mut self, pos: Option<[Range; 4]>) -> Result<CaseB, String> {
        let Some(Action::Line(bytes)) = self.def.plans.last().map(|plan| &plan.step.action) else {
            return Err("`expect: values` follows a host line".into());
        };
        let text = String::from_utf8_lossy(bytes).into_owned();
        let mut words = text.split_whitespace();
        let cmd = words.next().unwrap_or_default();
        let names: Vec<&str> = words.collect();
        let p = self.p.clone();
        let Some(first) = names.first().and_then(|n| p.param_id(n)) else {
            return Ok(self);
        };
        let getter = p.getter(first);
        let prefix = cmd
            .len()
            .checked_sub(getter.len())
            .and_then(|at| cmd.get(at..).filter(|g| g.eq_ignore_ascii_case(getter)).and_then(|_| cmd.get(..at)))
            .ok_or_else(|| format!("`expect: values`: `{text}` is not a {getter} line"))?;
        let shape = values_shape(&p, prefix, getter, &names, pos);
        if let Some(plan) = self.def.plans.last_mut() {
            plan.shape = shape;
        }
        Ok(self)
    }

    /// Captures a value of the last step's answer under `name`.
    pub fn capture(mut self, target: Target, name: &str) -> CaseB {
        if let Some(p) = self.def.plans.last_mut() {
            p.binds.push(Bind {
                target,
                capture: Some(name.to_string()),
                relation: None,
                evidence: String::new(),
                samples: Vec::new(),
            });
        }
        self
    }

    /// Holds a value of the last step's answer to a relation with a value captured before,
    /// with its evidence and the model's pairs it must hold.
    pub fn relate(mut self, target: Target, relation: Relation, evidence: String, samples: Vec<(i64, i64)>) -> CaseB {
        if let Some(p) = self.def.plans.last_mut() {
            p.binds.push(Bind { target, capture: None, relation: Some(relation), evidence, samples });
        }
        self
    }

    /// The last step's answer may come no sooner than `d` after its bytes went out.
    pub fn no_sooner_than(mut self, d: Duration, evidence: String) -> CaseB {
        if let Some(p) = self.def.plans.last_mut() {
            p.earliest = Some((d, evidence));
        }
        self
    }

    pub fn within(mut self, d: Duration) -> CaseB {
        if let Some(p) = self.def.plans.last_mut() {
            p.within_floor = Some(d);
        }
        self
    }

    /// The case. A case that writes the EEPROM ends by writing the factory values back
    /// (FDEF then FSAVE, PDEF then PSAVE) unless its last save already wrote them.
    pub fn finish(mut self) -> CaseDef {
        if self.def.requires.contains(&Requirement::Eeprom) {
            for (defaults, save) in [
                (CommandKind::MotorDefaults, CommandKind::MotorSave),
                (CommandKind::GlobalDefaults, CommandKind::GlobalSave),
            ] {
                if !self.last_save_is_factory(defaults, save) {
                    let (d, s) = (self.name_of(defaults), self.name_of(save));
                    self = self.comment("restore the factory values in the EEPROM").line(&d).line(&s);
                }
            }
        }
        self.def
    }

    fn name_of(&self, kind: CommandKind) -> String {
        self.p.command_of_kind(kind).map_or(String::new(), |id| self.p.command(id).name.clone())
    }

    /// Whether the last `save` of the plan (if any) follows an unprefixed `defaults` with no
    /// set or load in between.
    fn last_save_is_factory(&self, defaults: CommandKind, save: CommandKind) -> bool {
        let kinds: Vec<Option<(CommandKind, bool)>> = self
            .def
            .plans
            .iter()
            .map(|pl| match &pl.step.action {
                Action::Line(l) => match gcl_model::grammar::parse_line(&self.p, l) {
                    Ok(gcl_model::Line::Command(c)) => Some((c.kind(&self.p), c.prefix.is_some())),
                    _ => None,
                },
                _ => None,
            })
            .collect();
        let Some(last_save) = kinds.iter().rposition(|k| k.is_some_and(|(k, _)| k == save)) else { return true };
        let set = if save == CommandKind::MotorSave { CommandKind::MotorSet } else { CommandKind::GlobalSet };
        let load = if save == CommandKind::MotorSave { CommandKind::MotorLoad } else { CommandKind::GlobalLoad };
        for k in kinds[..last_save].iter().rev().flatten() {
            match k {
                (k, false) if *k == defaults => return true,
                (k, _) if *k == set || *k == load || *k == CommandKind::Reset => return false,
                _ => {}
            }
        }
        false
    }
}

/// The answer of `[prefix]GETTER NAME...`: for each name a line of values (one for a
/// `PGET`, else one per motor of the prefix), each elided as [`value_range`] says.
fn values_shape(p: &Profile, prefix: &str, getter: &str, names: &[&str], pos: Option<[Range; 4]>) -> Shape {
    let motors = prefix_motors(p, prefix);
    let mut lines = Vec::new();
    for n in names {
        let Some(id) = p.param_id(n) else {
            lines.push(Vec::new());
            continue;
        };
        let spec = p.param(id);
        let per_value: Vec<u8> = if getter == "PGET" { vec![1] } else { motors.clone() };
        lines.push(per_value.iter().map(|m| value_range(spec, *m, pos)).collect());
    }
    Shape::Values(lines)
}

/// The range a read of a parameter is elided to, or `None` when it is exact.
pub(crate) fn value_range(spec: &ParamSpec, motor: u8, pos: Option<[Range; 4]>) -> Option<Range> {
    if !spec.live || DETERMINED_LIVE.contains(&spec.name.as_str()) {
        return None;
    }
    if spec.name == "P" {
        return Some(pos.map_or((spec.min, spec.max), |p| p[(motor.clamp(1, 4) - 1) as usize]));
    }
    Some((spec.min, spec.max))
}

/// The label of a profile's source document in clause strings.
pub(crate) fn source_label(p: &Profile) -> &'static str {
    sources().get(p.id.as_str()).map_or("manual", String::as_str)
}

/// `conformance/suite-cases/sources.toml`: which document each profile's clauses cite.
fn sources() -> &'static std::collections::BTreeMap<String, String> {
    static SOURCES: std::sync::OnceLock<std::collections::BTreeMap<String, String>> = std::sync::OnceLock::new();
    SOURCES.get_or_init(|| {
        // Embedded, and checked by the test below: a broken file is a build of this crate
        // that fails its tests, never a run that cites the wrong document.
        toml::from_str(include_str!("../../suite-cases/sources.toml")).unwrap_or_default()
    })
}

/// The line ending then the prompt.
pub(crate) fn eol_prompt(p: &Profile) -> Vec<u8> {
    [p.framing.line_ending.as_bytes(), p.framing.prompt.as_bytes()].concat()
}

/// A feedback field's accepted range at rest, unless a rule overrides it: strain any byte,
/// the temperature its parameter's range in the field's units, everything else exact.
fn field_range(p: &Profile, f: &Field, rules: &[FieldRule]) -> Option<Range> {
    if let Some(r) = rules.iter().find(|r| r.motor == f.motor() && r.name == f.name()) {
        return r.range;
    }
    match f.flag() {
        RtFlag::Lfs => Some((f.min(), f.max())),
        RtFlag::Lft => {
            let t = p.param_id("TEMP").map(|id| p.param(id)).map_or((f.min(), f.max()), |s| (s.min, s.max));
            let (lo, hi) = if f.size() == 1 && p.hand.lft_whole_degrees { (t.0 / 10, t.1 / 10) } else { (t.0, t.1) };
            Some((lo.max(f.min()), hi.min(f.max())))
        }
        _ => None,
    }
}

/// The bind on a target, if any.
fn bind_on<'a>(binds: &'a [Bind], t: &Target) -> Option<&'a Bind> {
    binds.iter().find(|b| &b.target == t)
}

/// A value piece for a bind: the relation, or the capture with the value's range.
fn bound_piece(kind: ValueKind, range: Option<Range>, b: &Bind) -> Piece {
    let range = if b.relation.is_some() { None } else { range };
    Piece::Value(Value { kind, range, relation: b.relation.clone(), capture: b.capture.clone() })
}

fn shape_block(p: &Profile, c: &Captured, rules: &[FieldRule], binds: &[Bind]) -> Expect {
    let mut e = Expect::default();
    let header = c.sent.first().copied().and_then(ControlHeader::from_byte);
    let Some(layout) = &c.layout else { return Expect::hex(&c.output) };
    let fb = layout.feedback();
    if !header.is_some_and(|h| h.wants_feedback()) || c.output.len() != fb.size() {
        return match answer_form(c, &eol_prompt(p)) {
            Form::Hex => Expect::hex(&c.output),
            Form::Text => Expect::text(&c.output),
        };
    }
    e.push_bytes(Form::Hex, &c.output[..1]);
    for f in fb.fields() {
        let bytes = &c.output[f.offset()..f.offset() + f.size()];
        if let Some(b) = bind_on(binds, &Target::Field { motor: f.motor(), name: f.name() }) {
            let range = field_range(p, f, rules).map(|(lo, hi)| (lo.max(f.min()), hi.min(f.max())));
            e.push(Form::Hex, bound_piece(ValueKind::Field(f.ty()), range, b));
            continue;
        }
        match field_range(p, f, rules) {
            None => e.push_bytes(Form::Hex, bytes),
            Some((lo, hi)) if f.size() == 1 && lo <= f.min() && hi >= f.max() => e.push(Form::Hex, Piece::AnyByte),
            // A range of one value is that value's bytes.
            Some((lo, hi)) if lo == hi => e.push_bytes(Form::Hex, bytes),
            Some((lo, hi)) => {
                e.push(Form::Hex, Piece::Field { ty: f.ty(), min: lo.max(f.min()), max: hi.min(f.max()) })
            }
        }
    }
    e
}

/// Splits an answer `<echo>(<eol><line>)*<eol><prompt>` into the echo, the lines, and the
/// closing bytes. `None` if it does not have that shape.
fn split_lines<'a>(out: &'a [u8], eol: &[u8], ep: &[u8]) -> Option<(&'a [u8], Vec<&'a [u8]>)> {
    let body = out.strip_suffix(ep)?;
    let mut parts = Vec::new();
    let mut rest = body;
    let echo_end = find(rest, eol).unwrap_or(rest.len());
    let echo = &rest[..echo_end];
    rest = &rest[echo_end..];
    while !rest.is_empty() {
        rest = rest.strip_prefix(eol)?;
        let end = find(rest, eol).unwrap_or(rest.len());
        parts.push(&rest[..end]);
        rest = &rest[end..];
    }
    Some((echo, parts))
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len().max(1)).position(|w| w == needle)
}

fn push_values(e: &mut Expect, line: &[u8], ranges: &[Option<Range>], i: usize, binds: &[Bind]) {
    for (j, tok) in line.split(|b| *b == b' ').enumerate() {
        if j > 0 {
            e.push_bytes(Form::Text, b" ");
        }
        if let Some(b) = bind_on(binds, &Target::Value { line: i, token: j }) {
            e.push(Form::Text, bound_piece(ValueKind::Int, ranges.get(j).copied().flatten(), b));
            continue;
        }
        match ranges.get(j).copied().flatten() {
            Some(r) => e.push(Form::Text, Piece::Int(Some(r))),
            None => e.push_bytes(Form::Text, tok),
        }
    }
}

/// See [`Shape::BannerLines`]. `None` if the model's own answer does not have that form.
fn banner_lines_expect(output: &[u8], eol: &[u8], ep: &[u8]) -> Option<Expect> {
    const TEXT: &[u8] = b"BarrettHand Firmware";
    let line = [TEXT, eol].concat();
    let at = find(output, &line)?;
    let rest = &output[at + line.len()..];
    if !rest.ends_with(ep) || rest.len() <= ep.len() {
        return None;
    }
    let echo_end = output.iter().position(|b| *b == b'\n' || *b == b'\r').unwrap_or(at).min(at);
    let mut e = Expect::default();
    e.push_bytes(Form::Text, &output[..echo_end]);
    e.push(Form::Text, Piece::Any);
    e.push_bytes(Form::Text, &line);
    e.push(Form::Text, Piece::AnyByte);
    e.push(Form::Text, Piece::Any);
    e.push_bytes(Form::Text, ep);
    Some(e)
}

/// The expectation for a captured answer under a shape.
pub(crate) fn shape_answer(p: &Profile, c: &Captured, shape: &Shape, binds: &[Bind]) -> Result<Expect, String> {
    let eol = p.framing.line_ending.as_bytes();
    let ep = eol_prompt(p);
    let exact = || match answer_form(c, &ep) {
        Form::Hex => Expect::hex(&c.output),
        Form::Text => Expect::text(&c.output),
    };
    Ok(match shape {
        Shape::Exact => exact(),
        Shape::Banner => banner_expect(&c.output, &ep).ok_or("no banner in the answer")?,
        Shape::BannerLines => banner_lines_expect(&c.output, eol, &ep).ok_or("no banner line in the answer")?,
        Shape::Block(rules) => shape_block(p, c, rules, binds),
        Shape::AnyLines => {
            let (echo, _) = split_lines(&c.output, eol, &ep).ok_or("answer is not lines and a prompt")?;
            let mut e = Expect::default();
            e.push_bytes(Form::Text, echo);
            e.push_bytes(Form::Text, eol);
            e.push(Form::Text, Piece::Text);
            e.push_bytes(Form::Text, &ep);
            e
        }
        Shape::Values(ranges) => {
            let (echo, lines) = split_lines(&c.output, eol, &ep).ok_or("answer is not lines and a prompt")?;
            let mut e = Expect::default();
            e.push_bytes(Form::Text, echo);
            for (i, l) in lines.iter().enumerate() {
                e.push_bytes(Form::Text, eol);
                push_values(&mut e, l, ranges.get(i).map(Vec::as_slice).unwrap_or_default(), i, binds);
            }
            e.push_bytes(Form::Text, &ep);
            e
        }
        Shape::ListValues => {
            let (echo, lines) = split_lines(&c.output, eol, &ep).ok_or("answer is not lines and a prompt")?;
            let mut e = Expect::default();
            e.push_bytes(Form::Text, echo);
            for l in lines {
                e.push_bytes(Form::Text, eol);
                let name = l.split(|b| *b == b' ').next().unwrap_or_default();
                let spec = std::str::from_utf8(name).ok().and_then(|n| p.param_id(n)).map(|id| p.param(id));
                let ranges: Vec<Option<Range>> = match spec {
                    Some(s) => std::iter::once(None)
                        .chain((1..=4u8).map(|m| value_range(s, if s.scope == Scope::Global { 1 } else { m }, None)))
                        .collect(),
                    None => Vec::new(),
                };
                push_values(&mut e, l, &ranges, usize::MAX, &[]);
            }
            e.push_bytes(Form::Text, &ep);
            e
        }
    })
}

/// Runs a plan against a fresh simulated hand of `profile` and writes the golden transcript.
pub(crate) fn build(profile: &Arc<Profile>, def: &CaseDef) -> Result<Transcript, String> {
    let caps = capture_plan_with(profile, &def.plans, &def.setup)
        .map_err(|e| format!("case {} ({}): {e}", def.id, profile.id))?;
    build_from(profile, def, &caps)
}

/// What a fresh simulated hand of `profile` answers to the plans' steps (shapes aside).
pub(crate) fn capture_plan(profile: &Arc<Profile>, plans: &[Plan]) -> Result<Vec<Captured>, LinkError> {
    capture_plan_with(profile, plans, &[])
}

/// [`capture_plan`] with `setup` in place around the hand.
pub(crate) fn capture_plan_with(
    profile: &Arc<Profile>,
    plans: &[Plan],
    setup: &[Setup],
) -> Result<Vec<Captured>, LinkError> {
    let header = Header { setup: setup.to_vec(), ..Header::default() };
    capture_plan_on(profile, plans, super::model_config(&header))
}

/// [`capture_plan`] on a hand built from `config` (a hypothesis about another hand: see
/// `fuzz::device::variant`).
pub(crate) fn capture_plan_on(
    profile: &Arc<Profile>,
    plans: &[Plan],
    config: gcl_model::DeviceConfig,
) -> Result<Vec<Captured>, LinkError> {
    let opts = capture_options(profile, &config);
    let mut link = SimLink::new(profile.clone(), config);
    let steps: Vec<ScriptStep> = plans.iter().map(|p| p.step.clone()).collect();
    capture(&mut link, &steps, &opts)
}

/// How [`capture_plan_on`] records on a hand built from `config`.
pub(crate) fn capture_options(profile: &Arc<Profile>, config: &gcl_model::DeviceConfig) -> RecordOptions {
    let mut opts = RecordOptions::new(profile.clone());
    opts.timeout = Duration::from_secs(120);
    // (a hand with a difference in how it frames or sizes its answers: the shadow has it too)
    opts.shadow.faults = config.faults.clone();
    opts.shadow.without_effect = config.without_effect.clone();
    opts
}

/// [`build`] from the answers [`capture_plan`] gave for `def`'s plans.
pub(crate) fn build_from(profile: &Arc<Profile>, def: &CaseDef, caps: &[Captured]) -> Result<Transcript, String> {
    build_after(profile, def, caps, &super::depends::decisions_by_step(profile, &def.plans, caps), None)
}

/// The steps [`build_from`] makes of a case's first plans and the model's answers to them, to
/// go on from in a case that begins with the same plans and answers ([`build_after`]): a
/// case's preamble, kept with its capture (`actions::preamble`).
#[derive(Debug, Clone)]
pub(crate) struct BuiltSteps {
    plans: Vec<Plan>,
    caps: Vec<Captured>,
    steps: Vec<Step>,
    captured: Captures,
}

impl BuiltSteps {
    /// The steps of `plans` answered with `caps`; `None` where they are no steps of a case
    /// (an answer the shapes refuse) or write notes of their own (relations, timing windows),
    /// which a case going on from them would need too.
    pub(crate) fn of(profile: &Arc<Profile>, plans: &[Plan], caps: &[Captured]) -> Option<BuiltSteps> {
        if plans.len() != caps.len()
            || plans.iter().any(|p| p.earliest.is_some() || p.binds.iter().any(|b| b.relation.is_some()))
        {
            return None;
        }
        let def = CaseDef {
            id: String::new(),
            title: String::new(),
            clauses: Vec::new(),
            level: None,
            requires: Vec::new(),
            setup: Vec::new(),
            notes: Vec::new(),
            plans: plans.to_vec(),
        };
        let mut notes = Vec::new();
        let (steps, captured) = build_steps(profile, &def, caps, (Vec::new(), Captures::new()), &mut notes).ok()?;
        notes.is_empty().then(|| BuiltSteps { plans: plans.to_vec(), caps: caps.to_vec(), steps, captured })
    }
}

/// [`build_from`] with the decisions each step rests on already found (`depends::decisions_by_step`
/// of the same plans and answers), going on from `done` where the case begins with its plans and
/// answers.
pub(crate) fn build_after(
    profile: &Arc<Profile>,
    def: &CaseDef,
    caps: &[Captured],
    by_step: &[Vec<String>],
    done: Option<&BuiltSteps>,
) -> Result<Transcript, String> {
    let fail = |m: String| format!("case {} ({}): {m}", def.id, profile.id);
    let from = match done {
        Some(d) if def.plans.starts_with(&d.plans) && caps.starts_with(&d.caps) => {
            (d.steps.clone(), d.captured.clone())
        }
        _ => (Vec::with_capacity(caps.len()), Captures::new()),
    };
    let mut notes = def.notes.clone();
    let (out, _) = build_steps(profile, def, caps, from, &mut notes)?;
    let mut requires = def.requires.clone();
    requires.sort();
    // The decisions the case rests on: those it checks, then those its steps touch.
    let mut decisions: Vec<String> =
        def.clauses.iter().filter_map(|c| c.strip_prefix(DECISION_CLAUSE)).map(str::to_string).collect();
    for d in super::depends::decisions_of(profile, by_step) {
        if !decisions.contains(&d) {
            decisions.push(d);
        }
    }
    let order = |id: &String| profile.decisions.iter().position(|d| &d.id == id).unwrap_or(usize::MAX);
    decisions.sort_by_key(order);
    // The case binds no more strongly than the weakest decision it rests on.
    let mut level = def.level.unwrap_or(Level::Must);
    for d in profile.decisions.iter().filter(|d| decisions.contains(&d.id)) {
        level = level.max(d.level);
    }
    let mut extensions = Vec::new();
    if !decisions.is_empty() {
        extensions.push((DECISIONS_KEY.to_string(), decisions.join(" ")));
    }
    let header = Header {
        id: def.id.clone(),
        title: def.title.clone(),
        clauses: def.clauses.clone(),
        level,
        profiles: vec![profile.id.clone()],
        requires,
        setup: def.setup.clone(),
        notes,
        extensions,
    };
    if header.clauses.is_empty() {
        return Err(fail("no clause".into()));
    }
    Ok(Transcript { header, steps: out })
}

/// The steps of `def`'s plans answered with `caps`, from the first not in `from` (steps made and
/// the captures they made) on; notes the steps write are added to `notes`.
fn build_steps(
    profile: &Arc<Profile>,
    def: &CaseDef,
    caps: &[Captured],
    (mut out, mut captured): (Vec<Step>, Captures),
    notes: &mut Vec<String>,
) -> Result<(Vec<Step>, Captures), String> {
    let fail = |m: String| format!("case {} ({}): {m}", def.id, profile.id);
    let start = out.len();
    for (i, (plan, c)) in def.plans.iter().zip(caps).enumerate().skip(start) {
        if c.timed_out {
            return Err(fail(format!("step {i} got no complete answer: \"{}\"", gcl_model::escape::escape(&c.output))));
        }
        let expect = shape_answer(profile, c, &plan.shape, &plan.binds).map_err(|m| fail(format!("step {i}: {m}")))?;
        expect.check().map_err(|m| fail(format!("step {i}: {m}")))?;
        if plan.binds.len() != expect.pieces().filter(|(_, p)| matches!(p, Piece::Value(_))).count() {
            return Err(fail(format!("step {i}: a capture or relation names no value of the answer")));
        }
        // Every relation comes with its evidence, and holds the model's own pairs.
        for b in &plan.binds {
            let Some(r) = &b.relation else { continue };
            let piece = elision_text(&bound_piece(ValueKind::Int, None, b));
            if b.evidence.is_empty() || b.samples.is_empty() {
                return Err(fail(format!("step {i}: relation {piece} without evidence or model pairs")));
            }
            if let Some((x, y)) = b.samples.iter().find(|(x, y)| {
                let (lo, hi) = r.band(*x);
                !(lo..=hi).contains(y)
            }) {
                return Err(fail(format!("step {i}: relation {piece} does not hold the model's pair {x} -> {y}")));
            }
            // (a relation held on several answers is stated once)
            let note = format!("relation `{}`: {}", r.text(), b.evidence);
            if !notes.contains(&note) {
                notes.push(note);
            }
        }
        if let Some((_, why)) = &plan.earliest {
            notes.push(format!("timing window: {why}"));
        }
        match expect.matches_with(&captured, &c.output) {
            Some(now) => captured = now,
            None => {
                return Err(fail(format!(
                    "step {i}: the shaped answer {} does not match the model's \"{}\"",
                    expect.to_text(),
                    gcl_model::escape::escape(&c.output)
                )));
            }
        }
        let send = match &plan.step.action {
            Action::Wait => None,
            Action::Bytes { form, .. } => Some(HostBytes { bytes: c.sent.clone(), form: *form }),
            _ => Some(HostBytes::text(c.sent.clone())),
        };
        let mut within = suggest_within(profile, &plan.step.action, &c.sent, c.took, c.output.len());
        if let Some(f) = plan.within_floor {
            within = Some(within.map_or(f, |w| w.max(f)));
        }
        let earliest = plan.earliest.as_ref().map(|(d, _)| *d);
        if let Some(a) = earliest {
            if c.took < a {
                return Err(fail(format!("step {i}: the model answers sooner than the window's {a:?}")));
            }
            within = Some(within.map_or(a, |w| w.max(a)));
        }
        out.push(Step {
            line: 0,
            comments: plan.step.comments.clone(),
            pause: plan.step.pause,
            send,
            within,
            earliest,
            expect,
        });
    }
    Ok((out, captured))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derived_relations_hold_every_pair_and_no_more_than_they_need() {
        let pairs = [(100, 520), (120, 700), (150, 800), (200, 1100)];
        let r = derive_relation("p1", &pairs, 0).unwrap();
        // The factor is the midpoint of the ratios (5.2..5.83), over 100, reduced: 552/100.
        assert_eq!((r.num, r.den), (138, 25));
        let holds = |r: &Relation| {
            pairs.iter().all(|(a, b)| {
                let (lo, hi) = r.band(*a);
                (lo..=hi).contains(b)
            })
        };
        assert!(holds(&r));
        // The least tolerance: one point less breaks a pair.
        assert!(!holds(&Relation::new("p1", r.num, r.den, r.tolerance - 1)));
        assert_eq!(derive_relation("p1", &pairs, 3).unwrap().tolerance, r.tolerance + 3);
        // A fixed factor: the tolerance alone is fitted.
        let half = fit_tolerance("d1", 1, 2, &[(95, 51), (102, 47)], 0).unwrap();
        assert_eq!((half.num, half.den, half.tolerance), (1, 2, 6));
        // Nothing to anchor on, or no tolerance up to 100 % holds: no relation.
        assert!(derive_relation("p1", &[(0, 5)], 0).is_none());
        assert!(fit_tolerance("d1", 1, 2, &[(10, 100)], 0).is_none());
    }

    #[test]
    fn sources_file_parses_and_names_only_builtin_profiles() {
        let text = include_str!("../../suite-cases/sources.toml");
        let parsed: std::collections::BTreeMap<String, String> = toml::from_str(text).unwrap();
        assert_eq!(&parsed, sources(), "the embedded file did not parse");
        for (id, label) in &parsed {
            assert!(Profile::builtin(id).is_ok(), "sources.toml names `{id}`, which is no built-in profile");
            assert!(["seed", "manual"].contains(&label.as_str()), "`{id}`: unknown source `{label}`");
        }
        assert_eq!(source_label(&Profile::builtin("seed").unwrap()), "seed");
        assert_eq!(source_label(&Profile::builtin("bh8-262").unwrap()), "manual");
    }
}
