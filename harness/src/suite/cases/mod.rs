//! The catalogue: which cases each profile gets, in order. Most are generated from the
//! profile's tables (every command with its prefix and argument rules, every parameter's
//! default, range and access, every RealTime flag, every status bit); every case written by
//! hand is a script (`harness/suite-cases/<area>/`, read by `scripts.rs`), placed by its area's
//! module. The few cases still built in code besides the table generators need arithmetic
//! the scripts' expressions lack; `harness/suite-cases/generated.toml` lists every family built
//! here and why, and a test fails on a case it does not name. Each case starts from the same
//! preamble, so cases are independent on a real hand, and takes its level from the decisions
//! it checks.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::realtime::lfdp_step;
use gcl_model::spec::{ArgRule, CommandKind, CommandSpec, ParamSpec, PrefixRule, Scope};
use gcl_model::{Profile, StatusBits};

use super::build::{CaseB, CaseDef};
use super::plan::{FieldRule, Range, Shape, Target};
use gcl_transcript::Relation;

mod abort;
mod commands;
mod effects;
mod examples;
mod firmware;
mod framing;
mod motion;
mod params;
mod persistence;
mod realtime;
mod scripts;
mod status;
use gcl_transcript::{Level, Requirement};
pub(crate) use scripts::ScriptError;

/// Every case of a profile, in catalogue order, or the first case script that has no case
/// for it (an expression or condition the profile cannot answer).
pub(crate) fn catalogue(p: &Arc<Profile>) -> Result<Vec<CaseDef>, ScriptError> {
    let mut g = Gen { p: p.clone(), out: Vec::new(), failed: None };
    g.framing();
    g.commands();
    g.params();
    g.status();
    g.persistence();
    g.abort();
    g.motion();
    g.effects();
    g.realtime();
    g.examples();
    g.firmware();
    g.banner();
    match g.failed {
        Some(e) => Err(e),
        None => Ok(g.out),
    }
}

struct Gen {
    p: Arc<Profile>,
    out: Vec<CaseDef>,
    /// The first case script that made no case.
    failed: Option<ScriptError>,
}

/// A command or parameter name as part of an id.
pub(crate) fn slug(name: &str) -> String {
    match name {
        "?" => "help".into(),
        "A?" => "a-help".into(),
        _ => name.to_ascii_lowercase().chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect(),
    }
}

impl Gen {
    fn case(&self, id: impl Into<String>, title: impl Into<String>) -> CaseB {
        CaseB::new(&self.p, id, title)
    }

    fn add(&mut self, c: CaseB) {
        self.out.push(c.finish());
    }

    fn has_cmd(&self, name: &str) -> bool {
        self.p.command_id(name).is_some()
    }

    /// Whether the profile has this decision. Profiles differ in data, not in code: a case
    /// names every decision it may rest on (the seed's and the manuals'), and
    /// [`CaseB::decision`] cites those the profile has.
    fn has_decision(&self, id: &str) -> bool {
        self.p.decisions.iter().any(|d| d.id == id)
    }

    /// Cites those of `ids` the profile has; a case that rests on none of them is MUST.
    fn cite_or_must(&self, k: CaseB, ids: &[&str]) -> CaseB {
        if ids.iter().any(|id| self.has_decision(id)) {
            ids.iter().fold(k, |k, id| k.decision(id))
        } else {
            k.level(Level::Must)
        }
    }

    fn has_param(&self, name: &str) -> bool {
        self.p.param_id(name).is_some()
    }

    fn param(&self, name: &str) -> Option<&ParamSpec> {
        self.p.param_id(name).map(|id| self.p.param(id))
    }

    fn default(&self, name: &str, motor: u8) -> i64 {
        self.p.param_id(name).map_or(0, |id| self.p.default_for(id, motor))
    }

    fn mpe(&self, motor: u8) -> i64 {
        self.default("MPE", motor)
    }

    fn limit(&self, motor: u8) -> i64 {
        if motor == 4 { self.p.hand.spread_limit } else { self.p.hand.finger_limit }
    }

    /// `x` within MPE, for each motor.
    fn near(&self, goals: [i64; 4]) -> [Range; 4] {
        std::array::from_fn(|i| {
            let m = i as u8 + 1;
            ((goals[i] - self.mpe(m)).max(0), goals[i] + self.mpe(m))
        })
    }

    fn close_target(&self, motor: u8) -> i64 {
        if self.has_param("CT") {
            self.default("CT", motor)
        } else {
            // Where C goes without a CT parameter is the role's declared absence (the
            // `[hand]` targets); a profile that has neither does not load.
            gcl_model::Motor::new(motor)
                .and_then(|m| self.p.absent_value(gcl_model::spec::Role::CloseTarget, m))
                .unwrap_or_default()
        }
    }

    /// The status a hand constant names, as the wire number.
    fn code(&self, bits: u32) -> u32 {
        StatusBits::from_bits_truncate(bits).code()
    }
}

/// The band a feedback velocity of about `v` may read in: 25 %, the tolerance the cases' notes
/// state.
fn tol(v: i64) -> (i64, i64) {
    (((v as f64) * 0.75).floor() as i64, ((v as f64) * 1.25).ceil() as i64)
}

/// The least feedback velocity a relation between two motors' velocities is anchored on:
/// from 4 on, the truncation of either value stays inside the 25 % tolerance, and a hand that
/// ignores the parameter (both motors alike) falls outside a ratio of 2 or 1/2.
const LEAST_ANCHOR: i64 = 4;

/// Motors 1 and 2 in the loop, both sent `datum`; after a pause motor 1's feedback velocity
/// (about `v1` in the model's units) is captured as `v1`, and motor 2's is held to `v1` times
/// `num / den` within 25 %: the ratio is the clause, the units are not.
fn two_motor_ratio(k: CaseB, datum: i64, (v1, v2): (i64, i64), (num, den): (i64, i64), why: &str) -> CaseB {
    let motor = |m: u8| Target::Field { motor: Some(m), name: "LFV" };
    let evidence = format!(
        "{why}, so motor 2 reads motor 1's velocity times {num}/{den}, whatever the hand's velocity units \
         (the model reads {v1} and {v2}); velocities during motion are compared with 25 % tolerance, and \
         motor 1 must read {LEAST_ANCHOR}..127, the sign of the datum, large enough for the ratio to show"
    );
    k.line("12LOOP")
        .block(&[b'C', datum as u8, datum as u8], Shape::Block(Vec::new()))
        .pause_ms(50)
        .block(b"A", Shape::Block(vec![FieldRule { motor: Some(1), name: "LFV", range: Some((LEAST_ANCHOR, 127)) }]))
        .capture(motor(1), "v1")
        .relate(motor(2), Relation::new("v1", num, den, 25), evidence, vec![(v1, v2)])
        .abort()
}

/// A value other than `default` within the parameter's values: its maximum, else its minimum.
fn other_value(x: &ParamSpec, default: i64) -> i64 {
    match &x.values {
        Some(vs) => vs.iter().copied().find(|v| *v != default).unwrap_or(default),
        None if x.max != default => x.max,
        None => x.min,
    }
}

/// The longest line a case sends (outside the line-length case itself): the profile's limit,
/// but no more than [`super::depends::SAFE_LINE`], the longest line a host library is known to
/// send, so that a hand with a shorter buffer than the model's fails only framing-max-line.
fn safe_line(p: &Profile) -> usize {
    p.framing.max_line.min(super::depends::SAFE_LINE)
}

/// `head` then as many `item`s as fit in `max` bytes.
fn fill_line(head: &str, item: &str, max: usize) -> String {
    let mut s = head.to_string();
    while s.len() + item.len() <= max {
        s.push_str(item);
    }
    while s.len() < max {
        s.push(' ');
    }
    s
}

/// Lines of `head` followed by items, each line at most `max` bytes.
fn chunk_lines(head: &str, items: &[String], max: usize) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = head.to_string();
    for it in items {
        if cur.len() + 1 + it.len() > max && cur.len() > head.len() {
            out.push(std::mem::replace(&mut cur, head.to_string()));
        }
        cur.push(' ');
        cur.push_str(it);
    }
    if cur.len() > head.len() {
        out.push(cur);
    }
    out
}

impl CaseB {
    /// Replaces the title.
    pub(crate) fn title_set(mut self, t: String) -> CaseB {
        self.def.title = t;
        self
    }

    /// A clause given literally.
    pub(crate) fn clause(mut self, c: &str) -> CaseB {
        if !self.def.clauses.iter().any(|x| x == c) {
            self.def.clauses.push(c.to_string());
        }
        self
    }
}
