//! Host actions and how they are drawn from a profile.
//!
//! A fuzz case is a short list of [`HostAction`]s after the suite's preamble. The generator
//! knows no command by name: it reads the profile's commands (kind, prefix rule, argument
//! rule and range), parameters (range, values, read-only, effect, RealTime field), prefixes
//! and framing (maximum line, abort byte), so a new profile is fuzzed by its own data.
//! RealTime blocks are drawn as a header and raw values; the case builder encodes them with
//! the layout the shadow model is in when the block goes out.
//!
//! This lives below the fuzzer so that the runner's motion probe can build its case too
//! (`fuzz::device` re-exports `action` and `case`); besides drawing actions it mutates corpus
//! entries. `case` shapes answers wider for hands outside this process after RealTime motion or ^C
//! mid-motion, and drops cases that do not pass on a fresh model; in process a drawn case is
//! checked
//! so only when the hand fails it (`build_case_unchecked`, `BuiltCase::check`). The shadow device
//! gives the coverage features through the public model API only: the model is not
//! instrumented.

pub mod case;
mod preamble;
mod relate;

use gcl_model::Profile;
use gcl_model::spec::{ArgRule, CommandKind, CommandSpec, ParamSpec, PrefixRule, Role};
use rand_core::RngCore;
use serde::{Deserialize, Serialize};

/// One thing the host does after the preamble.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HostAction {
    /// A command line (the terminator is added); the step ends at the prompt.
    Line(String),
    /// Bytes as they are, ending with the terminator (stray control bytes inside a line).
    Raw(Vec<u8>),
    /// A line whose answer is not awaited, then ^C after a pause (^C mid-motion).
    LineThenAbort {
        /// The line.
        line: String,
        /// The pause before ^C, in ms.
        after_ms: u64,
    },
    /// Bytes without the terminator, then ^C (^C mid-line).
    PartialThenAbort(String),
    /// A RealTime block: a header byte and control values, encoded with the loop's layout
    /// (values clamped to their fields), then `extra` bytes more (0x00) or fewer.
    Block {
        /// The header byte (`C`, `c`, `A`, `a`, or anything else: an invalid header).
        header: u8,
        /// Control values in the layout's field order; missing ones are 0.
        values: Vec<i64>,
        /// Bytes added (positive) or cut (negative) after encoding.
        extra: i8,
        /// A pause before the block, in ms (the motors run meanwhile: movements large enough
        /// for the relations of `fuzz::device::relate` to show).
        #[serde(default, skip_serializing_if = "is_zero")]
        pause_ms: u64,
    },
    /// ^C alone.
    Abort,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// What the operator allows the fuzzer to do to the hand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Allowed {
    /// Motion commands, HI and LOOP.
    pub motion: bool,
    /// RealTime sessions (LOOP and blocks).
    pub realtime: bool,
    /// FSAVE and PSAVE.
    pub eeprom: bool,
    /// ^C landing during motion.
    pub abort_timing: bool,
    /// On a serial line: the rate (bit/s) the line runs at. No action then sets the hand's
    /// line-rate parameter (the profile's `[hand] baud`) to another rate, nor names it in a set
    /// the hand refuses: the hand would move to a rate the port is not at, and every later
    /// answer would be garbled (on a real hand, with a save, for good). `None`: any value.
    pub keep_rate: Option<u32>,
}

impl Default for Allowed {
    fn default() -> Allowed {
        Allowed { motion: true, realtime: true, eeprom: true, abort_timing: true, keep_rate: None }
    }
}

/// A small deterministic source of choices over a PCG.
pub struct Dice(rand_pcg::Pcg32);

impl Dice {
    /// Dice from a seed.
    pub fn new(seed: u64) -> Dice {
        use rand_core::SeedableRng;
        Dice(rand_pcg::Pcg32::seed_from_u64(seed))
    }

    /// A number in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 { 0 } else { (self.0.next_u32() as usize) % n }
    }

    /// True with probability `percent`/100.
    pub fn chance(&mut self, percent: u32) -> bool {
        self.0.next_u32() % 100 < percent
    }

    /// One element of a slice.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> Option<&'a T> {
        if items.is_empty() { None } else { items.get(self.below(items.len())) }
    }

    /// A value in `lo..=hi`.
    pub fn between(&mut self, lo: i64, hi: i64) -> i64 {
        if hi <= lo {
            return lo;
        }
        let span = (hi - lo) as u64 + 1;
        lo + (self.0.next_u64() % span) as i64
    }

    /// A raw 64-bit number.
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }
}

/// Draws host actions from a profile.
pub struct Generator<'p> {
    p: &'p Profile,
    allowed: Allowed,
    held: bool,
}

impl<'p> Generator<'p> {
    /// A generator for `p` within what is `allowed`.
    pub fn new(p: &'p Profile, allowed: Allowed) -> Generator<'p> {
        Generator { p, allowed, held: false }
    }

    /// With `held`, half the RealTime sessions hold one control velocity (small values, the
    /// coefficients set per motor, pauses before the blocks): the sessions whose feedback the
    /// relations (`fuzz::device::relate`) judge on a hand outside this process. Without it the
    /// draws are as they always were.
    pub fn holding_velocities(mut self, held: bool) -> Generator<'p> {
        self.held = held;
        self
    }

    fn command_allowed(&self, c: &CommandSpec) -> bool {
        let k = c.kind;
        (self.allowed.motion || !(k.is_motion() || k == CommandKind::Initialize))
            && ((self.allowed.realtime && self.allowed.motion) || k != CommandKind::Loop)
            && (self.allowed.eeprom || !matches!(k, CommandKind::MotorSave | CommandKind::GlobalSave))
    }

    /// The line-rate parameter when its sets are guarded ([`Allowed::keep_rate`]), with the one
    /// value it may be set to (the line's own rate, when the rate is a whole number of its
    /// units).
    fn guarded_rate(&self) -> Option<(&'p ParamSpec, Option<i64>)> {
        let rate = i64::from(self.allowed.keep_rate?);
        let gcl_model::spec::ValueSource::Param(id) = self.p.hand_sources().baud else { return None };
        Some((self.p.param(id), (rate % 100 == 0).then_some(rate / 100)))
    }

    /// Whether a parameter may be drawn into a set: not the guarded line-rate parameter.
    fn settable(&self, s: &ParamSpec) -> bool {
        self.guarded_rate().is_none_or(|(g, _)| g.name != s.name)
    }

    /// Whether one line of host bytes would change the line's rate ([`Allowed::keep_rate`]): a
    /// set of the line-rate parameter to another value, or a refused set that names it with
    /// another value (a hand's bug may still apply it). Control bytes are read past, as a hand that ignores them
    /// would.
    pub fn changes_rate(&self, line: &[u8]) -> bool {
        let Some((spec, keep)) = self.guarded_rate() else { return false };
        let Some(id) = self.p.param_id(&spec.name) else { return false };
        let clean: Vec<u8> = line.iter().copied().filter(|b| b.is_ascii_graphic() || *b == b' ').collect();
        match gcl_model::parse_line(self.p, &clean) {
            Ok(gcl_model::Line::Command(c)) => match &c.args {
                gcl_model::Args::Pairs(ps) => ps.iter().any(|(p, v)| *p == id && Some(*v) != keep),
                _ => false,
            },
            Ok(gcl_model::Line::Empty) => false,
            Err(_) => {
                let text = String::from_utf8_lossy(&clean).to_ascii_uppercase();
                let words: Vec<&str> = text.split(|c: char| !c.is_ascii_alphanumeric()).collect();
                let setter = self.p.setter(id).to_ascii_uppercase();
                words.contains(&spec.name.to_ascii_uppercase().as_str())
                    && words.iter().any(|w| w.ends_with(setter.as_str()))
                    && words.iter().any(|w| w.parse::<i64>().is_ok_and(|v| Some(v) != keep))
            }
        }
    }

    fn commands(&self, f: impl Fn(&CommandSpec) -> bool) -> Vec<&'p CommandSpec> {
        self.p.commands.iter().filter(|c| self.command_allowed(c) && f(c)).collect()
    }

    /// Whether every action is within what is allowed (corpus entries from elsewhere, the
    /// suite's cases): each line of every action is read by the model's grammar.
    pub fn permits(&self, actions: &[HostAction]) -> bool {
        let term = self.p.framing.terminator;
        actions.iter().all(|a| {
            let bytes: Vec<u8> = match a {
                HostAction::Line(l) | HostAction::PartialThenAbort(l) => l.as_bytes().to_vec(),
                HostAction::LineThenAbort { line, .. } => {
                    if !self.allowed.abort_timing {
                        return false;
                    }
                    line.as_bytes().to_vec()
                }
                HostAction::Raw(b) => b.clone(),
                HostAction::Block { .. } | HostAction::Abort => Vec::new(),
            };
            bytes.split(|b| *b == term).all(|line| {
                !self.changes_rate(line)
                    && match gcl_model::parse_line(self.p, line) {
                        Ok(gcl_model::Line::Command(c)) => self.command_allowed(self.p.command(c.command)),
                        _ => true,
                    }
            })
        })
    }

    /// A new case: 1 to 6 groups of actions.
    pub fn case(&self, d: &mut Dice) -> Vec<HostAction> {
        let mut out = Vec::new();
        let groups = 1 + d.below(6);
        for _ in 0..groups {
            self.group(d, &mut out);
        }
        out
    }

    /// Appends one group of related actions.
    pub fn group(&self, d: &mut Dice, out: &mut Vec<HostAction>) {
        match d.below(100) {
            0..=24 => {
                // A parameter with an effect set away from its default, then what shows it.
                let name = self.set_effect(d, out);
                self.show_effect(d, name.as_deref(), out);
            }
            25..=29 => self.persistence(d, out),
            30..=49 => out.push(HostAction::Line(self.valid_line(d))),
            50..=57 => {
                let l = self.valid_line(d);
                out.push(HostAction::Line(self.variant(d, &l)));
            }
            58..=60 => out.push(HostAction::Line(self.unknown_word(d))),
            61..=62 => out.push(HostAction::Line(self.empty_or_bare(d))),
            63..=65 => out.push(HostAction::Line(self.overlong(d))),
            66..=69 => out.push(HostAction::Raw(self.control_bytes(d))),
            70..=72 => {
                let l = self.valid_line(d);
                let cut = d.below(l.len().max(1));
                out.push(HostAction::PartialThenAbort(l[..cut].to_string()));
            }
            73..=77 if self.allowed.motion && self.allowed.abort_timing => {
                if let Some(l) = self.motion_line(d) {
                    out.push(HostAction::LineThenAbort { line: l, after_ms: d.between(0, 400) as u64 });
                }
            }
            78..=83 => {
                let kinds = [
                    CommandKind::Reset,
                    CommandKind::MotorDefaults,
                    CommandKind::MotorLoad,
                    CommandKind::MotorSave,
                    CommandKind::GlobalDefaults,
                    CommandKind::GlobalLoad,
                    CommandKind::GlobalSave,
                ];
                let k = *d.pick(&kinds).unwrap_or(&CommandKind::Reset);
                if let Some(c) = self.commands(|c| c.kind == k).first() {
                    out.push(HostAction::Line(c.name.clone()));
                }
            }
            _ if self.allowed.realtime && self.allowed.motion => self.realtime(d, out),
            _ => out.push(HostAction::Line(self.valid_line(d))),
        }
    }

    /// A prefix: one or two of the profile's prefix characters (sometimes lower case).
    fn prefix(&self, d: &mut Dice) -> String {
        let mut s = String::new();
        for _ in 0..1 + usize::from(d.chance(20)) {
            if let Some(px) = d.pick(&self.p.prefixes) {
                s.push(if d.chance(15) { px.char.to_ascii_lowercase() } else { px.char });
            }
        }
        s
    }

    /// A value for a parameter: in range, at its edges or just outside.
    fn value(&self, d: &mut Dice, s: &ParamSpec) -> i64 {
        if let Some(vs) = &s.values
            && !d.chance(10)
        {
            return *d.pick(vs).unwrap_or(&0);
        }
        match d.below(10) {
            0 => s.min,
            1 => s.max,
            2 => s.min.saturating_sub(1),
            3 => s.max.saturating_add(1),
            4 => s.default.unwrap_or(0),
            _ => d.between(s.min, s.max),
        }
    }

    fn params_by(&self, f: impl Fn(&ParamSpec) -> bool) -> Vec<&'p ParamSpec> {
        self.p.params.iter().filter(|s| f(s)).collect()
    }

    /// A line the profile's grammar accepts, mostly; some with a bad prefix, argument or value.
    pub fn valid_line(&self, d: &mut Dice) -> String {
        let cmds = self.commands(|c| {
            !matches!(c.kind, CommandKind::Loop | CommandKind::Reset | CommandKind::MotorSave | CommandKind::GlobalSave)
        });
        let Some(c) = d.pick(&cmds).copied() else { return String::new() };
        let mut line = String::new();
        match c.prefix {
            PrefixRule::Allowed if d.chance(50) => line.push_str(&self.prefix(d)),
            PrefixRule::Forbidden if d.chance(8) => line.push_str(&self.prefix(d)),
            _ => {}
        }
        line.push_str(&c.name);
        match c.args {
            ArgRule::None => {
                if d.chance(8) {
                    line.push_str(&format!(" {}", d.between(0, 9)));
                }
            }
            ArgRule::OptionalInteger => {
                if d.chance(60) {
                    let (lo, hi) = (c.arg_min.unwrap_or(0), c.arg_max.unwrap_or(self.p.hand.finger_limit));
                    let v = match d.below(8) {
                        0 => lo,
                        1 => hi,
                        2 => lo.saturating_sub(1),
                        3 => hi.saturating_add(1),
                        _ => d.between(lo, hi),
                    };
                    line.push_str(&format!(" {v}"));
                }
            }
            ArgRule::Names => {
                let names = self.params_by(|s| self.p.param_id(&s.name).is_some_and(|id| self.p.getter(id) == c.name));
                for _ in 0..1 + d.below(3) {
                    if d.chance(5) {
                        line.push_str(&format!(" {}", self.unknown_word(d)));
                    } else if let Some(s) = d.pick(&names) {
                        line.push_str(&format!(" {}", s.name));
                    }
                }
            }
            ArgRule::Pairs => {
                let read_only = d.chance(5);
                let ps = self.params_by(|s| {
                    self.p.param_id(&s.name).is_some_and(|id| self.p.setter(id) == c.name)
                        && (!s.read_only || read_only)
                        && self.settable(s)
                });
                for _ in 0..1 + d.below(2) {
                    if let Some(s) = d.pick(&ps) {
                        let v = self.value(d, s);
                        line.push_str(&format!(" {} {v}", s.name));
                    }
                }
                if d.chance(4) {
                    line.push_str(" DP");
                }
            }
        }
        line
    }

    /// Case and whitespace variants of a line.
    fn variant(&self, d: &mut Dice, line: &str) -> String {
        let mut s: String = line.chars().map(|ch| if d.chance(30) { ch.to_ascii_lowercase() } else { ch }).collect();
        if d.chance(40) {
            s = s.replace(' ', "  ");
        }
        if d.chance(30) {
            s = s.replace(' ', "\t");
        }
        if d.chance(30) {
            s.insert(0, ' ');
        }
        if d.chance(30) {
            s.push(' ');
        }
        s
    }

    /// A word no profile has.
    fn unknown_word(&self, d: &mut Dice) -> String {
        let n = 1 + d.below(6);
        (0..n).map(|_| (b'A' + d.below(26) as u8) as char).collect::<String>() + "Q"
    }

    /// A line past the profile's maximum length.
    fn overlong(&self, d: &mut Dice) -> String {
        let get = self.p.command_of_kind(CommandKind::MotorGet).map(|id| self.p.command(id).name.clone());
        let mut s = get.unwrap_or_else(|| "FGET".into());
        while s.len() <= self.p.framing.max_line + d.below(4) {
            s.push_str(" DP");
        }
        s
    }

    /// A line with a stray control byte (not the terminator, not the abort byte).
    fn control_bytes(&self, d: &mut Dice) -> Vec<u8> {
        let mut line = self.valid_line(d).into_bytes();
        let fr = &self.p.framing;
        let mut b = d.between(0, 31) as u8;
        if b == fr.terminator || b == fr.abort || b == b'\n' {
            b = 0x01;
        }
        let at = d.below(line.len() + 1);
        line.insert(at, b);
        line.push(fr.terminator);
        line
    }

    /// A motion command line, with a prefix or not.
    fn motion_line(&self, d: &mut Dice) -> Option<String> {
        let cmds = self.commands(|c| c.kind.is_motion());
        let c = d.pick(&cmds)?;
        let mut l = if d.chance(40) { self.prefix(d) } else { String::new() };
        l.push_str(&c.name);
        if c.args == ArgRule::OptionalInteger && d.chance(50) {
            l.push_str(&format!(
                " {}",
                d.between(c.arg_min.unwrap_or(0), c.arg_max.unwrap_or(self.p.hand.finger_limit))
            ));
        }
        Some(l)
    }

    /// A set line for a parameter with an effect, away from its default; returns its name.
    fn set_effect(&self, d: &mut Dice, out: &mut Vec<HostAction>) -> Option<String> {
        let ps = self.params_by(|s| s.effect.is_some() && !s.read_only && self.settable(s));
        let s = d.pick(&ps)?;
        let id = self.p.param_id(&s.name)?;
        let mut v = self.value(d, s);
        if Some(v) == s.default {
            v = d.between(s.min, s.max);
        }
        let prefix =
            if s.scope == gcl_model::spec::Scope::Motor && d.chance(50) { self.prefix(d) } else { String::new() };
        out.push(HostAction::Line(format!("{prefix}{} {} {v}", self.p.setter(id), s.name)));
        Some(s.name.clone())
    }

    /// The profile's commands a parameter's `effect` text names (`the target of C`, `the
    /// step of IC and IO`), among those allowed.
    fn named_in_effect(&self, param: &str) -> Vec<&'p CommandSpec> {
        let Some(effect) = self.p.param_id(param).and_then(|id| self.p.param(id).effect.as_deref()) else {
            return Vec::new();
        };
        let words: Vec<&str> = effect.split(|c: char| !c.is_ascii_alphanumeric() && c != '?').collect();
        self.commands(|c| words.contains(&c.name.as_str()))
    }

    /// A read-back of a parameter with its getter, with or without a prefix.
    fn read_back(&self, d: &mut Dice, name: &str) -> Option<String> {
        let id = self.p.param_id(name)?;
        let s = self.p.param(id);
        let prefix =
            if s.scope == gcl_model::spec::Scope::Motor && d.chance(30) { self.prefix(d) } else { String::new() };
        Some(format!("{prefix}{} {name}", self.p.getter(id)))
    }

    /// One to three parameters set, maybe saved, then defaults, loads or a reset, then all
    /// read back.
    fn persistence(&self, d: &mut Dice, out: &mut Vec<HostAction>) {
        let ps = self.params_by(|s| !s.read_only && !s.live && !s.persist.is_empty() && self.settable(s));
        let mut names = Vec::new();
        for _ in 0..1 + d.below(3) {
            let Some(s) = d.pick(&ps) else { return };
            let Some(id) = self.p.param_id(&s.name) else { return };
            let mut v = d.between(s.min, s.max);
            if let Some(vs) = &s.values {
                v = *d.pick(vs).unwrap_or(&v);
            }
            out.push(HostAction::Line(format!("{} {} {v}", self.p.setter(id), s.name)));
            names.push(s.name.clone());
        }
        let after = [
            CommandKind::Reset,
            CommandKind::MotorDefaults,
            CommandKind::MotorLoad,
            CommandKind::GlobalDefaults,
            CommandKind::GlobalLoad,
        ];
        let mut kinds: Vec<CommandKind> = after.to_vec();
        if self.allowed.eeprom && d.chance(40) {
            kinds = vec![CommandKind::MotorSave, CommandKind::GlobalSave];
        }
        for _ in 0..1 + d.below(3) {
            let k = *d.pick(&kinds).unwrap_or(&CommandKind::Reset);
            if let Some(c) = self.commands(|c| c.kind == k).first() {
                out.push(HostAction::Line(c.name.clone()));
            }
            kinds = after.to_vec();
        }
        for n in names {
            if let Some(l) = self.read_back(d, &n) {
                out.push(HostAction::Line(l));
            }
        }
    }

    /// An empty line, separators alone, or a setter with a name and no value.
    fn empty_or_bare(&self, d: &mut Dice) -> String {
        match d.below(3) {
            0 => String::new(),
            1 => " \t ".chars().take(1 + d.below(3)).collect(),
            _ => {
                let ps = self.params_by(|s| !s.read_only);
                match d.pick(&ps).and_then(|s| self.p.param_id(&s.name)) {
                    Some(id) => format!("{} {}", self.p.setter(id), self.p.param(id).name),
                    None => String::new(),
                }
            }
        }
    }

    /// Something that shows what a parameter changes: the commands its effect names (or any
    /// motion command) and a position read, ^C mid-motion and a position read, a RealTime
    /// session, or a read-back.
    fn show_effect(&self, d: &mut Dice, param: Option<&str>, out: &mut Vec<HostAction>) {
        let named = param.map(|n| self.named_in_effect(n)).unwrap_or_default();
        match d.below(6) {
            0..=2 if self.allowed.motion => {
                let line = match d.pick(&named) {
                    Some(c) if d.chance(50) => {
                        let px = if c.prefix == PrefixRule::Allowed && d.chance(30) {
                            self.prefix(d)
                        } else {
                            String::new()
                        };
                        Some(format!("{px}{}", c.name))
                    }
                    _ => self.motion_line(d),
                };
                if let Some(l) = line {
                    // From closed, so that opening moves too.
                    if d.chance(35)
                        && let Some(c) = self.commands(|c| c.kind == CommandKind::Close).first()
                    {
                        out.push(HostAction::Line(c.name.clone()));
                    }
                    if self.allowed.abort_timing && d.chance(35) {
                        out.push(HostAction::LineThenAbort { line: l, after_ms: d.between(20, 400) as u64 });
                    } else {
                        out.push(HostAction::Line(l));
                    }
                }
                out.push(HostAction::Line(self.position_read()));
            }
            3 if self.allowed.realtime && self.allowed.motion => self.realtime(d, out),
            4 => {
                // The parameter, and the parameters its effect names (SGFLIP: SG).
                let Some(n) = param else { return };
                let effect = self.p.param_id(n).and_then(|id| self.p.param(id).effect.clone()).unwrap_or_default();
                let mut names = vec![n.to_string()];
                names.extend(
                    effect
                        .split(|c: char| !c.is_ascii_alphanumeric())
                        .filter(|w| self.p.param_id(w).is_some())
                        .map(str::to_string),
                );
                for n in names {
                    if let Some(l) = self.read_back(d, &n) {
                        out.push(HostAction::Line(l));
                    }
                }
            }
            _ => out.push(HostAction::Line(self.valid_line(d))),
        }
    }

    /// The line that reads every motor's position.
    fn position_read(&self) -> String {
        let get = self.p.command_of_kind(CommandKind::MotorGet).map(|id| self.p.command(id).name.clone());
        format!("{} P", get.unwrap_or_else(|| "FGET".into()))
    }

    /// A RealTime session: flags, LOOP, blocks with edge values and headers, ^C.
    fn realtime(&self, d: &mut Dice, out: &mut Vec<HostAction>) {
        if self.held && d.chance(50) {
            return self.held_session(d, out);
        }
        let flags = self.params_by(|s| s.rt.is_some() || (s.effect.is_some() && s.name.starts_with('L')));
        for _ in 0..d.below(4) {
            if let Some(s) = d.pick(&flags)
                && let Some(id) = self.p.param_id(&s.name)
            {
                let v =
                    if d.chance(80) { d.between(s.min.max(0), s.max.min(s.min.max(0) + 3)) } else { self.value(d, s) };
                out.push(HostAction::Line(format!("{} {} {v}", self.p.setter(id), s.name)));
            }
        }
        let Some(lp) = self.commands(|c| c.kind == CommandKind::Loop).first().map(|c| c.name.clone()) else { return };
        let prefix = if d.chance(70) { self.prefix(d) } else { String::new() };
        out.push(HostAction::Line(format!("{prefix}{lp}")));
        for _ in 0..1 + d.below(4) {
            let header = match d.below(20) {
                0..=6 => b'C',
                7..=10 => b'c',
                11..=14 => b'A',
                15..=17 => b'a',
                _ => (b'D' + d.below(20) as u8).max(4),
            };
            let values = (0..8)
                .map(|_| match d.below(5) {
                    0 => i64::MIN,
                    1 => i64::MAX,
                    2 => 0,
                    _ => d.between(-128, 127),
                })
                .collect();
            let extra = match d.below(20) {
                0 => -1,
                1 => 1,
                _ => 0,
            };
            out.push(HostAction::Block { header, values, extra, pause_ms: 0 });
            if extra < 0 {
                break;
            }
        }
        out.push(HostAction::Abort);
    }

    /// A RealTime session that holds one control velocity: some RealTime flags set (mostly on),
    /// one of the coefficients of the velocity, of its feedback and of LFDP (by their roles)
    /// set to 2..4 for one motor, its flag on (so the motors' coefficients differ: the clause
    /// the feedback's relations check), the others now and then, LOOP (mostly every motor),
    /// then 3 to 6 well-formed blocks, each after a pause, whose data are one set of small values.
    fn held_session(&self, d: &mut Dice, out: &mut Vec<HostAction>) {
        for s in self.params_by(|s| s.rt.is_some() && !s.read_only) {
            if d.chance(20)
                && let Some(id) = self.p.param_id(&s.name)
            {
                let v = if d.chance(70) { s.max.min(s.min.max(0) + 1) } else { s.min.max(0) };
                out.push(HostAction::Line(format!("{} {} {v}", self.p.setter(id), s.name)));
            }
        }
        // The clause the session checks: one coefficient set apart for one motor (the flag it
        // scales on), the others now and then.
        let roles = [Role::VelocityCoefficient, Role::FeedbackVelocityCoefficient, Role::DeltaCoefficient];
        let chosen = d.below(roles.len());
        let single: Vec<char> = self.p.prefixes.iter().filter(|px| px.motors.len() == 1).map(|px| px.char).collect();
        for (i, role) in roles.into_iter().enumerate() {
            let Some(id) = self.p.role(role) else { continue };
            let s = self.p.param(id);
            if i == chosen {
                if let gcl_model::spec::Absence::RequiredWith(flag) = role.absence()
                    && let Some(f) = self.p.param_id(flag.name())
                {
                    let on = self.p.param(f).max.min(1);
                    out.push(HostAction::Line(format!("{} {} {on}", self.p.setter(f), flag.name())));
                }
                let px = d.pick(&single).map(char::to_string).unwrap_or_default();
                let v = d.between(s.min.max(2), s.max.min(4));
                out.push(HostAction::Line(format!("{px}{} {} {v}", self.p.setter(id), s.name)));
            } else if d.chance(30) {
                let v = d.between(s.min.max(1), s.max.min(4));
                out.push(HostAction::Line(format!("{}{} {} {v}", self.prefix(d), self.p.setter(id), s.name)));
            }
        }
        let Some(lp) = self.commands(|c| c.kind == CommandKind::Loop).first().map(|c| c.name.clone()) else { return };
        // (mostly every motor: a ratio between motors needs two of them)
        let prefix = if d.chance(20) { self.prefix(d) } else { String::new() };
        out.push(HostAction::Line(format!("{prefix}{lp}")));
        // (mostly closing: after the preamble's HI the fingers are open, at the end an opening
        // velocity stops at)
        let sign = if d.chance(80) { 1 } else { -1 };
        let values: Vec<i64> = (0..8).map(|_| sign * d.between(2, 12)).collect();
        for _ in 0..3 + d.below(4) {
            let header = *d.pick(b"CCAca").unwrap_or(&b'C');
            out.push(HostAction::Block {
                header,
                values: values.clone(),
                extra: 0,
                // (a pause moves the motors only on a hand whose motions take time: the same
                // requirement as a ^C landing mid-motion)
                pause_ms: if self.allowed.abort_timing { d.between(10, 40) as u64 } else { 0 },
            });
        }
        out.push(HostAction::Abort);
    }

    /// A mutation of a corpus entry: drop, duplicate, replace or insert a group.
    pub fn mutate(&self, d: &mut Dice, base: &[HostAction]) -> Vec<HostAction> {
        let mut v = base.to_vec();
        for _ in 0..1 + d.below(3) {
            match d.below(4) {
                0 if v.len() > 1 => {
                    v.remove(d.below(v.len()));
                }
                1 => {
                    let mut g = Vec::new();
                    self.group(d, &mut g);
                    let at = d.below(v.len() + 1);
                    v.splice(at..at, g);
                }
                2 if !v.is_empty() => {
                    let i = d.below(v.len());
                    let a = v[i].clone();
                    v.insert(i, a);
                }
                _ => {
                    let mut g = Vec::new();
                    self.group(d, &mut g);
                    v.extend(g);
                }
            }
        }
        v.truncate(24);
        v
    }
}

/// Simpler forms of one action, simplest first, for the minimizer.
pub fn simpler(a: &HostAction) -> Vec<HostAction> {
    match a {
        HostAction::Line(l) => {
            let mut out = Vec::new();
            let words: Vec<&str> = l.split_whitespace().collect();
            if words.len() > 1 {
                out.push(HostAction::Line(words[..words.len() - 1].join(" ")));
            }
            let canon = words.join(" ");
            if canon != *l {
                out.push(HostAction::Line(canon));
            }
            out
        }
        HostAction::Raw(b) => {
            vec![HostAction::Line(String::from_utf8_lossy(b).chars().filter(|c| !c.is_control()).collect::<String>())]
        }
        HostAction::LineThenAbort { line, after_ms } if *after_ms > 0 => {
            vec![HostAction::LineThenAbort { line: line.clone(), after_ms: 0 }, HostAction::Line(line.clone())]
        }
        HostAction::Block { header, values, extra, pause_ms } => {
            let mut out = Vec::new();
            let block = |values: Vec<i64>, extra: i8, pause_ms: u64| HostAction::Block {
                header: *header,
                values,
                extra,
                pause_ms,
            };
            if values.iter().any(|v| *v != 0) {
                out.push(block(vec![0; values.len()], *extra, *pause_ms));
            }
            if *extra != 0 {
                out.push(block(values.clone(), 0, *pause_ms));
            }
            if *pause_ms != 0 {
                out.push(block(values.clone(), *extra, 0));
            }
            out
        }
        _ => Vec::new(),
    }
}

/// The host side of a suite case after its preamble, as actions: the suite's goldens are the
/// first corpus. Lines become [`HostAction::Line`], ^C [`HostAction::Abort`] (after a line
/// not awaited, [`HostAction::LineThenAbort`] with the case's pause), a partial line before
/// ^C [`HostAction::PartialThenAbort`], and anything else (RealTime blocks, several lines at
/// once) [`HostAction::Raw`].
pub fn from_transcript(p: &Profile, t: &gcl_transcript::Transcript) -> Vec<HostAction> {
    let fr = &p.framing;
    // The preamble ends where the suite's check comment stands.
    let check = crate::suite::build::CHECK_COMMENT;
    let start = t.steps.iter().position(|s| s.comments.iter().any(|c| c == check)).unwrap_or(0);
    let mut out: Vec<HostAction> = Vec::new();
    for s in &t.steps[start..] {
        let Some(h) = &s.send else { continue };
        let b = &h.bytes;
        if b.as_slice() == [fr.abort] {
            let pause = s.pause.map_or(0, |d| d.as_millis() as u64);
            match out.pop() {
                Some(HostAction::Line(l)) if pause > 0 => {
                    out.push(HostAction::LineThenAbort { line: l, after_ms: pause })
                }
                Some(HostAction::Raw(r)) if !r.ends_with(&[fr.terminator]) => {
                    out.push(HostAction::PartialThenAbort(String::from_utf8_lossy(&r).into_owned()))
                }
                Some(a) => {
                    out.push(a);
                    out.push(HostAction::Abort);
                }
                None => out.push(HostAction::Abort),
            }
            continue;
        }
        let one_line = b.last() == Some(&fr.terminator)
            && b.iter().filter(|x| **x == fr.terminator).count() == 1
            && b.iter().all(|x| *x == fr.terminator || *x == b'\t' || (0x20..0x7f).contains(x))
            && h.form == gcl_transcript::Form::Text;
        if one_line {
            out.push(HostAction::Line(String::from_utf8_lossy(&b[..b.len() - 1]).into_owned()));
        } else {
            out.push(HostAction::Raw(b.clone()));
        }
    }
    out.truncate(24);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn generator_lines(p: &Profile, allowed: Allowed, seed: u64, cases: usize) -> Vec<Vec<u8>> {
        let g = Generator::new(p, allowed);
        let mut d = Dice::new(seed);
        let mut lines = Vec::new();
        let mut base = Vec::new();
        for i in 0..cases {
            let actions = if i % 2 == 0 || base.is_empty() { g.case(&mut d) } else { g.mutate(&mut d, &base) };
            for a in &actions {
                if let HostAction::Line(l) | HostAction::PartialThenAbort(l) = a {
                    lines.push(l.as_bytes().to_vec());
                }
                if let HostAction::Raw(b) = a {
                    lines.extend(b.split(|c| *c == p.framing.terminator).map(<[u8]>::to_vec));
                }
            }
            base = actions;
        }
        lines
    }

    #[test]
    fn a_guarded_line_rate_is_never_set_to_another_rate() {
        for name in ["bh8-262-4.3", "seed"] {
            let p = Profile::builtin(name).unwrap();
            let guarded = Allowed { keep_rate: Some(9600), ..Allowed::default() };
            let g = Generator::new(&p, guarded);
            // Unguarded, the generator does set it (so the guard is what keeps it out).
            let free = generator_lines(&p, Allowed::default(), 7, 3000);
            assert!(free.iter().any(|l| g.changes_rate(l)), "{name}: no rate change drawn unguarded");
            let kept = generator_lines(&p, guarded, 7, 3000);
            let bad: Vec<String> =
                kept.iter().filter(|l| g.changes_rate(l)).map(|l| String::from_utf8_lossy(l).into_owned()).collect();
            assert!(bad.is_empty(), "{name}: {bad:?}");
        }
    }

    #[test]
    fn what_changes_the_rate_is_read_as_a_hand_would() {
        let p = Profile::builtin("bh8-262-4.3").unwrap();
        let g = Generator::new(&p, Allowed { keep_rate: Some(9600), ..Allowed::default() });
        for l in ["PSET BAUD 384", "pset baud 384", "PSET LFT 1 BAUD 192", "PSET BA\x01UD 384", "PSET BAUD 385"] {
            assert!(g.changes_rate(l.as_bytes()), "{l:?} changes the rate");
        }
        for l in ["PSET BAUD 96", "PGET BAUD", "FGET BAUD", "PSET LFT 1", "PLIST", "PSET BAUD"] {
            assert!(!g.changes_rate(l.as_bytes()), "{l:?} leaves the rate");
        }
        assert!(!g.permits(&[HostAction::Line("PSET BAUD 384".into())]));
        assert!(g.permits(&[HostAction::Line("PSET BAUD 96".into())]));
        // Not guarded (no serial line): anything goes.
        let free = Generator::new(&p, Allowed::default());
        assert!(!free.changes_rate(b"PSET BAUD 384"));
        // At 38400 the one value allowed is 384.
        let fast = Generator::new(&p, Allowed { keep_rate: Some(38400), ..Allowed::default() });
        assert!(fast.changes_rate(b"PSET BAUD 96") && !fast.changes_rate(b"PSET BAUD 384"));
    }
}
