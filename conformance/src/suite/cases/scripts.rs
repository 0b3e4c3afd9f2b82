//! Hand-written cases as data: `conformance/suite-cases/<area>/<id>.gcls`, embedded in the binary.
//! Every case the suite has that is not generated from a profile table (or computed, see
//! `conformance/suite-cases/generated.toml`) is one of these.
//!
//! A case script is a `gcl record` script ([`gcl_transcript::script`]) whose header says what
//! the suite needs besides the steps:
//!
//! ```text
//! id: framing-echo                    the case id; the file is named by it, with any
//!                                     `{expression}` dropped (`status-{code:abort}-abort`
//!                                     is `status-abort.gcls`)
//! title: Every byte of a line is echoed as sent
//! clause: decision:framing-echo       a decision the case checks, cited when the profile has it
//! clause: src:Command ^C              a clause of the profile's own source (`seed:`/`manual:`)
//! clause: seed: Example Programs      any other clause, literally (clauses keep their order)
//! x-preamble: motion                  none | idle (^C, RESET, FDEF, PDEF) | motion (idle + HI)
//! x-when: command:PSAVE param:OTEMP   only for profiles with all of these conditions
//! x-title-when: param:LCT => Title    this title instead where the conditions hold
//! profile: seed                       only for these profiles (default: every profile)
//! level: MUST  requires: motion  note: ...   as in a transcript
//! ```
//!
//! Conditions (`x-when:`, `x-title-when:`, `step-when:`) are space-separated, all must hold,
//! and `a|b` holds when either does: `command:NAME`, `param:NAME`, `alias:NAME` (a parameter
//! that names another's value), `zero-min:NAME` (a parameter whose minimum is 0),
//! `status:NAME` (a status the hand sends, as in `code:`) and `decision:ID`.
//!
//! **Expressions.** `{...}` anywhere in a script (header, steps, `expect:` lines) is replaced
//! by its value for the profile before the script is read. An expression is one term, or
//! number terms joined by ` + ` and ` - ` (spaces around the operator: names hold dashes).
//! Terms: a whole number; `limit:M` (the joint limit of motor M, 1 to 4), `mpe:M` (MPE's
//! default), `close-target:M` (where C goes), `code:STATUS` (the wire number of
//! `missed-position`, `uninitialized`, `terminate-uninitialized`, `bad-header`, `overtemp`,
//! `abort`), `uninitialized-state` (what S reads before HI); and two names, used alone:
//! `status-text:N` (status N's text) and `first-param:A|B` (the first of these parameters the
//! profile has, else the last). Anything else is an [`ExprError`] with its line.
//!
//! Steps are the script's: host lines, `line:`, `nowait:`, `raw:`, `partial:`, `block:`,
//! `abort`, `wait`, `pause:`; every answer is written exactly as the model gives it, unless an
//! `expect:` line after the step gives it a shape. These lines are the suite's own, read here
//! and not by the script parser:
//!
//! ```text
//! expect: banner          a RESET banner: `{any}BarrettHand Firmware{any}`
//! expect: banner-lines    a banner checked for the line endings hosts rely on
//! expect: any-lines       the echo, then `{text}`: lines that are not a status
//! expect: list-values     `NAME value...` lines, live values elided to their ranges
//! expect: values          a get line's values (`[motors]FGET|PGET NAME...`), each live value
//!                         elided to its parameter's range, as the generators' `get` does
//! expect: near 5000 5000 5000 0   as `values`, positions (P) within MPE of these goals, one
//!                         per motor (the profile's MPE defaults)
//! expect: positions 0..{mpe:1} 0..10 0..10 0..10   as `values`, positions in these ranges
//! expect: block 1:LFAP=0..{mpe:1} LFT=0..60   a RealTime feedback block, each field as the
//!                         model gives it except strain and temperature (their ranges) and
//!                         the fields named here ([MOTOR:]FLAG=LO..HI; no motor: hand-wide)
//! step-when: command:PDEF   the next step only where these conditions hold
//! rt-flags: 1 LCV LFAP    before the next step, the set lines that turn these RealTime flags
//!                         on and every other off (for the motors of an optional prefix)
//! ```
//!
//! A `timeout:` line gives the step after it a `within` floor. What a shape expands to is the
//! builder's ([`CaseB`]), as for the generators: one way of writing each answer.

use gcl_transcript::ParseError;
use gcl_transcript::script::{ScriptStep, parse_script};

use gcl_model::realtime::RtFlag;

use super::*;

/// Every case script, by id, in no particular order (the generators place them).
pub(crate) const SCRIPTS: &[(&str, &str)] = &[
    ("framing-echo", include_str!("../../../suite-cases/framing/framing-echo.gcls")),
    ("framing-empty-line", include_str!("../../../suite-cases/framing/framing-empty-line.gcls")),
    ("framing-case", include_str!("../../../suite-cases/framing/framing-case.gcls")),
    ("framing-whitespace", include_str!("../../../suite-cases/framing/framing-whitespace.gcls")),
    ("framing-numbers", include_str!("../../../suite-cases/framing/framing-numbers.gcls")),
    ("framing-errors-combine", include_str!("../../../suite-cases/framing/framing-errors-combine.gcls")),
    ("framing-line-atomic", include_str!("../../../suite-cases/framing/framing-line-atomic.gcls")),
    ("framing-backspace", include_str!("../../../suite-cases/framing/framing-backspace.gcls")),
    ("framing-busy-input", include_str!("../../../suite-cases/framing/framing-busy-input.gcls")),
    ("framing-abort-partial-line", include_str!("../../../suite-cases/framing/framing-abort-partial-line.gcls")),
    ("abort-idle", include_str!("../../../suite-cases/abort/abort-idle.gcls")),
    ("abort-motion-discards-queue", include_str!("../../../suite-cases/abort/abort-motion-discards-queue.gcls")),
    ("abort-loop", include_str!("../../../suite-cases/abort/abort-loop.gcls")),
    ("param-scope-commands", include_str!("../../../suite-cases/params/param-scope-commands.gcls")),
    ("persist-fdef", include_str!("../../../suite-cases/persistence/persist-fdef.gcls")),
    ("persist-fload", include_str!("../../../suite-cases/persistence/persist-fload.gcls")),
    ("persist-pdef", include_str!("../../../suite-cases/persistence/persist-pdef.gcls")),
    ("persist-pload", include_str!("../../../suite-cases/persistence/persist-pload.gcls")),
    ("banner-lines", include_str!("../../../suite-cases/firmware/banner-lines.gcls")),
    ("param-temp-global", include_str!("../../../suite-cases/params/param-temp-global.gcls")),
    ("param-tmp-alias", include_str!("../../../suite-cases/params/param-tmp-alias.gcls")),
    ("param-msg-hsg-alias", include_str!("../../../suite-cases/params/param-msg-hsg-alias.gcls")),
    ("param-en-narrows-motion", include_str!("../../../suite-cases/params/param-en-narrows-motion.gcls")),
    ("motion-goal-within-mpe", include_str!("../../../suite-cases/motion/motion-goal-within-mpe.gcls")),
    ("param-spread-finger-defaults", include_str!("../../../suite-cases/params/param-spread-finger-defaults.gcls")),
    ("persist-fdef-ram-only", include_str!("../../../suite-cases/persistence/persist-fdef-ram-only.gcls")),
    ("persist-fsave-reset", include_str!("../../../suite-cases/persistence/persist-fsave-reset.gcls")),
    ("persist-reset-discards-ram", include_str!("../../../suite-cases/persistence/persist-reset-discards-ram.gcls")),
    ("persist-psave-reset", include_str!("../../../suite-cases/persistence/persist-psave-reset.gcls")),
    ("abort-motion", include_str!("../../../suite-cases/abort/abort-motion.gcls")),
    ("motion-strain-limit", include_str!("../../../suite-cases/motion/motion-strain-limit.gcls")),
    ("motion-close-stall-no-status", include_str!("../../../suite-cases/motion/motion-close-stall-no-status.gcls")),
    ("motion-mpe-boundary", include_str!("../../../suite-cases/motion/motion-mpe-boundary.gcls")),
    ("motion-hi-stall", include_str!("../../../suite-cases/motion/motion-hi-stall.gcls")),
    ("example-realtime-seed", include_str!("../../../suite-cases/examples/example-realtime-seed.gcls")),
    ("example-realtime-program", include_str!("../../../suite-cases/examples/example-realtime-program.gcls")),
    ("example-supervisory-program", include_str!("../../../suite-cases/examples/example-supervisory-program.gcls")),
    ("firmware-shared-tables", include_str!("../../../suite-cases/firmware/firmware-shared-tables.gcls")),
    ("param-44-rt-flags", include_str!("../../../suite-cases/params/param-44-rt-flags.gcls")),
    ("rt-header-upper-c", include_str!("../../../suite-cases/realtime/rt-header-upper-c.gcls")),
    ("rt-header-lower-c", include_str!("../../../suite-cases/realtime/rt-header-lower-c.gcls")),
    ("rt-header-upper-a", include_str!("../../../suite-cases/realtime/rt-header-upper-a.gcls")),
    ("rt-header-lower-a", include_str!("../../../suite-cases/realtime/rt-header-lower-a.gcls")),
    ("rt-lfap-byte-order", include_str!("../../../suite-cases/realtime/rt-lfap-byte-order.gcls")),
    (
        "rt-bad-header-returns-to-supervisory",
        include_str!("../../../suite-cases/realtime/rt-bad-header-returns-to-supervisory.gcls"),
    ),
    ("rt-loop-en-motors", include_str!("../../../suite-cases/realtime/rt-loop-en-motors.gcls")),
    ("rt-coefficients-no-field", include_str!("../../../suite-cases/realtime/rt-coefficients-no-field.gcls")),
    ("status-1024-too-many-arguments", include_str!("../../../suite-cases/status/status-1024-too-many-arguments.gcls")),
    ("status-128-invalid-value", include_str!("../../../suite-cases/status/status-128-invalid-value.gcls")),
    ("status-256-read-only", include_str!("../../../suite-cases/status/status-256-read-only.gcls")),
    ("status-32-unknown-command", include_str!("../../../suite-cases/status/status-32-unknown-command.gcls")),
    ("status-4096-prefix-not-allowed", include_str!("../../../suite-cases/status/status-4096-prefix-not-allowed.gcls")),
    ("status-64-unknown-parameter", include_str!("../../../suite-cases/status/status-64-unknown-parameter.gcls")),
    ("status-abort", include_str!("../../../suite-cases/status/status-abort.gcls")),
    ("status-bad-header", include_str!("../../../suite-cases/status/status-bad-header.gcls")),
    (
        "status-combined-grammar-and-not-initialized",
        include_str!("../../../suite-cases/status/status-combined-grammar-and-not-initialized.gcls"),
    ),
    (
        "status-combined-invalid-and-read-only",
        include_str!("../../../suite-cases/status/status-combined-invalid-and-read-only.gcls"),
    ),
    (
        "status-combined-prefix-and-arguments",
        include_str!("../../../suite-cases/status/status-combined-prefix-and-arguments.gcls"),
    ),
    (
        "status-combined-unknown-and-invalid",
        include_str!("../../../suite-cases/status/status-combined-unknown-and-invalid.gcls"),
    ),
    (
        "status-combined-unknown-and-read-only",
        include_str!("../../../suite-cases/status/status-combined-unknown-and-read-only.gcls"),
    ),
    ("status-missed-position", include_str!("../../../suite-cases/status/status-missed-position.gcls")),
    ("status-not-initialized", include_str!("../../../suite-cases/status/status-not-initialized.gcls")),
    ("status-overtemperature", include_str!("../../../suite-cases/status/status-overtemperature.gcls")),
    ("status-terminate-before-hi", include_str!("../../../suite-cases/status/status-terminate-before-hi.gcls")),
    ("param-dp-effect", include_str!("../../../suite-cases/params/param-dp-effect.gcls")),
    ("param-ds-effect", include_str!("../../../suite-cases/params/param-ds-effect.gcls")),
    ("param-ct-effect", include_str!("../../../suite-cases/params/param-ct-effect.gcls")),
    ("param-ot-effect", include_str!("../../../suite-cases/params/param-ot-effect.gcls")),
    ("param-mpe-effect", include_str!("../../../suite-cases/params/param-mpe-effect.gcls")),
    ("param-lsg-effect", include_str!("../../../suite-cases/params/param-lsg-effect.gcls")),
    ("param-unknown-name-fget", include_str!("../../../suite-cases/params/param-unknown-name-fget.gcls")),
    ("param-unknown-name-fset", include_str!("../../../suite-cases/params/param-unknown-name-fset.gcls")),
    ("param-unknown-name-pget", include_str!("../../../suite-cases/params/param-unknown-name-pget.gcls")),
    ("param-unknown-name-pset", include_str!("../../../suite-cases/params/param-unknown-name-pset.gcls")),
];

/// Why a case script does not make a case.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ScriptError {
    /// No script has this id.
    #[error("no case script `{0}`")]
    Missing(String),
    /// An `{expression}` has no value for the profile.
    #[error("case script `{id}`, line {line}: {error}")]
    Expr {
        /// The script's id.
        id: String,
        /// The line of the expression.
        line: usize,
        /// Why it has no value.
        error: ExprError,
    },
    /// The text is not a script.
    #[error("case script `{id}`: {error}")]
    Parse {
        /// The script's id (its file name).
        id: String,
        /// Where and why it does not parse.
        error: ParseError,
    },
    /// The script parses but says something the suite cannot use.
    #[error("case script `{id}`: {reason}")]
    Invalid {
        /// The script's id.
        id: String,
        /// What is wrong.
        reason: String,
    },
}

/// How a case starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Preamble {
    None,
    Idle,
    Motion,
}

impl Gen {
    /// Adds the cases of these scripts, in this order (each only for the profiles it names).
    /// A script that makes no case for this profile is kept as the catalogue's error.
    pub(super) fn scripts(&mut self, ids: &[&str]) {
        for id in ids {
            match self.script_case(id) {
                Ok(Some(k)) => self.add(k),
                Ok(None) => {}
                Err(e) => {
                    self.failed.get_or_insert(e);
                }
            }
        }
    }

    /// The case of one script for this profile: `None` when the script names other profiles.
    pub(super) fn script_case(&self, id: &str) -> Result<Option<CaseB>, ScriptError> {
        let text = SCRIPTS.iter().find(|(i, _)| *i == id).map(|(_, t)| *t).ok_or(ScriptError::Missing(id.into()))?;
        let invalid = |reason: String| ScriptError::Invalid { id: id.into(), reason };
        let raw_id = text.lines().find_map(|l| l.trim().strip_prefix("id:")).map(str::trim);
        if raw_id.map(script_name).as_deref() != Some(id) {
            return Err(invalid(format!("its `id:` is {raw_id:?}, which does not name the file")));
        }
        let text = self.expand(text).map_err(|(line, error)| ScriptError::Expr { id: id.into(), line, error })?;
        let SuiteLines { text, expects, whens, rt_flags } = split_suite_lines(&text).map_err(invalid)?;
        let script = parse_script(&text).map_err(|error| ScriptError::Parse { id: id.into(), error })?;
        let f = &script.fields;
        let case_id = f.id.clone().ok_or_else(|| invalid("no `id:`".into()))?;
        let mut title = f.title.clone().ok_or_else(|| invalid("no `title:`".into()))?;
        if !f.profiles.is_empty() && !f.profiles.contains(&self.p.id) {
            return Ok(None);
        }
        let mut k = self.case(case_id, title.clone());
        for c in &f.clauses {
            k = if let Some(d) = c.strip_prefix(DECISION_PREFIX) {
                k.decision(d.trim())
            } else if let Some(what) = c.strip_prefix(SRC_PREFIX) {
                k.src(what.trim())
            } else {
                k.clause(c)
            };
        }
        let mut preamble = Preamble::Idle;
        for (key, value) in &f.extensions {
            match key.as_str() {
                "x-when" => {
                    if !self.conditions_hold(value).map_err(invalid)? {
                        return Ok(None);
                    }
                }
                "x-title-when" => {
                    let (conds, t) =
                        value.split_once("=>").ok_or_else(|| invalid("x-title-when: CONDITIONS => TITLE".into()))?;
                    if self.conditions_hold(conds).map_err(invalid)? {
                        t.trim().clone_into(&mut title);
                    }
                }
                "x-preamble" => {
                    preamble = match value.as_str() {
                        "none" => Preamble::None,
                        "idle" => Preamble::Idle,
                        "motion" => Preamble::Motion,
                        _ => return Err(invalid(format!("x-preamble `{value}`: none, idle or motion"))),
                    }
                }
                _ => return Err(invalid(format!("unknown key `{key}` (x-preamble, x-when, x-title-when)"))),
            }
        }
        k = k.title_set(title);
        if let Some(l) = f.level {
            k = k.level(l);
        }
        for r in &f.requires {
            k = k.requires(r.clone());
        }
        for n in &f.notes {
            k = k.note(n.clone());
        }
        if preamble != Preamble::None {
            k = k.preamble(preamble == Preamble::Motion);
        }
        let mut timeout = None;
        let mut expects = expects.into_iter().peekable();
        let mut whens = whens.into_iter().peekable();
        let mut rt_flags = rt_flags.into_iter().peekable();
        for (i, step) in script.steps.iter().enumerate() {
            while let Some((n, args)) = rt_flags.next_if(|(n, _)| *n < step.line) {
                let (prefix, on) = self.rt_flags_args(&args).map_err(|e| invalid(format!("line {n}: {e}")))?;
                for l in self.rt_flags(prefix, &on) {
                    k = k.line(&l);
                }
            }
            // The `step-when:` lines before this step (and after the one before it).
            let mut runs = true;
            while let Some((n, conds)) = whens.next_if(|(n, _)| *n < step.line) {
                runs &= self.conditions_hold(&conds).map_err(|e| invalid(format!("line {n}: {e}")))?;
            }
            let next = script.steps.get(i + 1).map_or(usize::MAX, |s| s.line);
            let expect = expects.next_if(|(n, _)| *n < next);
            if let Some((n, _)) = &expect
                && expects.peek().is_some_and(|(m, _)| *m < next)
            {
                return Err(invalid(format!("line {n}: two `expect:` lines for one step")));
            }
            if !runs {
                continue;
            }
            k = Self::script_step(k, step, timeout);
            timeout = step.timeout;
            if let Some((n, shape)) = expect {
                k = match shape {
                    Expected::Shape(shape) => k.shape_last(shape),
                    Expected::Values(pos) => {
                        let pos = pos.map(|p| match p {
                            Positions::Near(goals) => self.near(goals),
                            Positions::Ranges(ranges) => ranges,
                        });
                        k.values_last(pos).map_err(|e| invalid(format!("line {n}: {e}")))?
                    }
                };
            }
        }
        if let Some((n, _)) = expects.next() {
            return Err(invalid(format!("line {n}: `expect:` before any step")));
        }
        if let Some((n, _)) = rt_flags.next() {
            return Err(invalid(format!("line {n}: `rt-flags:` after the last step")));
        }
        if let Some((n, _)) = whens.next() {
            return Err(invalid(format!("line {n}: `step-when:` after the last step")));
        }
        Ok(Some(k))
    }

    /// The arguments of an `rt-flags:` line: a motor prefix (if the first word is one) and
    /// the RealTime flags to turn on, each a flag the model knows.
    fn rt_flags_args<'a>(&self, args: &'a str) -> Result<(&'a str, Vec<&'a str>), String> {
        let mut words: Vec<&str> = args.split_whitespace().collect();
        let prefix = match words.first() {
            Some(w) if w.chars().all(|c| self.p.prefix_motors(c).is_some()) => words.remove(0),
            _ => "",
        };
        if let Some(bad) = words.iter().find(|w| RtFlag::from_name(w).is_none()) {
            return Err(format!("rt-flags: `{bad}` is no RealTime flag"));
        }
        Ok((prefix, words))
    }

    /// Whether a profile has what every space-separated condition names (`a|b`: either).
    fn conditions_hold(&self, conds: &str) -> Result<bool, String> {
        for cond in conds.split_whitespace() {
            let mut holds = false;
            for alt in cond.split('|') {
                holds |= match alt.split_once(':') {
                    Some(("command", n)) => self.has_cmd(n),
                    Some(("param", n)) => self.has_param(n),
                    Some(("alias", n)) => self.param(n).is_some_and(|x| x.alias_of.is_some()),
                    Some(("zero-min", n)) => self.param(n).is_some_and(|x| x.min == 0),
                    Some(("status", n)) => self.status_bits(n).map_err(|e| e.to_string())? != 0,
                    Some(("decision", d)) => self.has_decision(d),
                    _ => {
                        return Err(format!(
                            "condition `{alt}`: command:, param:, alias:, zero-min:, status: or decision:"
                        ));
                    }
                };
            }
            if !holds {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// The script with every `{expression}` replaced by its value for this profile, or the
    /// line and error of the first that has none.
    fn expand(&self, text: &str) -> Result<String, (usize, ExprError)> {
        let mut out = String::with_capacity(text.len());
        for (i, line) in text.lines().enumerate() {
            let mut rest = line;
            while let Some(at) = rest.find('{') {
                out.push_str(&rest[..at]);
                let end = rest[at..].find('}').ok_or((i + 1, ExprError::Unclosed))?;
                let value = self.eval(&rest[at + 1..at + end]).map_err(|e| (i + 1, e))?;
                match value {
                    Value::Int(v) => out.push_str(&v.to_string()),
                    Value::Text(t) => out.push_str(&t),
                }
                rest = &rest[at + end + 1..];
            }
            out.push_str(rest);
            out.push('\n');
        }
        Ok(out)
    }

    /// One expression: terms joined by ` + ` and ` - ` (spaces around the operator, since
    /// names hold dashes), or one text term alone.
    fn eval(&self, expr: &str) -> Result<Value, ExprError> {
        let mut words = expr.split_whitespace();
        let first = self.term(words.next().ok_or_else(|| ExprError::Empty(expr.into()))?)?;
        let Some(op) = words.next() else { return Ok(first) };
        let number = |v: Value| match v {
            Value::Int(v) => Ok(v),
            Value::Text(t) => Err(ExprError::NotANumber(t)),
        };
        let mut sum = number(first)?;
        let mut op = Some(op);
        while let Some(o) = op {
            let t = number(self.term(words.next().ok_or_else(|| ExprError::Empty(expr.into()))?)?)?;
            sum = match o {
                "+" => sum.saturating_add(t),
                "-" => sum.saturating_sub(t),
                other => return Err(ExprError::Operator(other.into())),
            };
            op = words.next();
        }
        Ok(Value::Int(sum))
    }

    /// The status bits of a status the hand sends on its own (0: the profile never sends it).
    fn status_bits(&self, name: &str) -> Result<u32, ExprError> {
        let h = &self.p.hand;
        Ok(match name {
            "missed-position" => h.missed_position_status,
            "uninitialized" => h.uninitialized_status,
            "terminate-uninitialized" => h.terminate_uninitialized_status,
            "bad-header" => h.bad_header_status,
            "overtemp" => h.overtemp_status,
            "abort" => h.abort_status,
            _ => return Err(ExprError::UnknownStatus(name.into())),
        })
    }

    /// One term: a whole number or a name of the profile's (see the module doc).
    fn term(&self, t: &str) -> Result<Value, ExprError> {
        if let Ok(v) = t.parse::<i64>() {
            return Ok(Value::Int(v));
        }
        let motor = |m: &str| match m.parse::<u8>() {
            Ok(m @ 1..=4) => Ok(m),
            _ => Err(ExprError::BadMotor(t.into())),
        };
        Ok(Value::Int(match t.split_once(':') {
            Some(("limit", m)) => self.limit(motor(m)?),
            Some(("mpe", m)) => self.mpe(motor(m)?),
            Some(("close-target", m)) => self.close_target(motor(m)?),
            Some(("code", s)) => i64::from(self.code(self.status_bits(s)?)),
            Some(("status-text", n)) => {
                let text = n.parse().ok().and_then(|bit| self.p.status_text(bit));
                return text.map(|t| Value::Text(t.to_string())).ok_or_else(|| ExprError::UnknownStatus(n.into()));
            }
            Some(("first-param", names)) => {
                let names: Vec<&str> = names.split('|').collect();
                let found = names.iter().find(|n| self.has_param(n)).or(names.last());
                return Ok(Value::Text(found.map_or(String::new(), |n| (*n).to_string())));
            }
            None if t == "uninitialized-state" => self.p.hand.uninitialized_state_value,
            _ => return Err(ExprError::UnknownName(t.into())),
        }))
    }

    /// One script step as a planned step; a `timeout:` new since the step before is its floor.
    fn script_step(mut k: CaseB, step: &ScriptStep, before: Option<Duration>) -> CaseB {
        for c in &step.comments {
            k = k.comment(c.clone());
        }
        if let Some(p) = step.pause {
            k = k.pause_ms(u64::try_from(p.as_millis()).unwrap_or(u64::MAX));
        }
        k = k.step(step.action.clone());
        match step.timeout {
            Some(t) if step.timeout != before => k.within(t),
            _ => k,
        }
    }
}

/// The name of a script's file (and its key in [`SCRIPTS`]): its `id:` with every
/// `{expression}` dropped, and the dashes around it merged (`status-{code:abort}-abort` is
/// `status-abort`).
fn script_name(raw_id: &str) -> String {
    let mut out = String::with_capacity(raw_id.len());
    let mut rest = raw_id;
    while let Some(at) = rest.find('{') {
        out.push_str(&rest[..at]);
        rest = rest[at..].find('}').map_or("", |end| &rest[at + end + 1..]);
    }
    out.push_str(rest);
    while out.contains("--") {
        out = out.replace("--", "-");
    }
    out.trim_matches('-').to_string()
}

/// What an expression in braces gives.
enum Value {
    /// A number (limits, MPE, status codes, sums).
    Int(i64),
    /// A name (`first-param:`).
    Text(String),
}

/// Why an `{expression}` has no value for a profile.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum ExprError {
    /// A `{` with no `}` after it on its line.
    #[error("`{{` without a closing `}}`")]
    Unclosed,
    /// Nothing where a term belongs.
    #[error("`{{{0}}}`: a term is missing")]
    Empty(String),
    /// A name the grammar does not have.
    #[error(
        "unknown name `{0}` (limit:M, mpe:M, close-target:M, code:STATUS, status-text:N, uninitialized-state, \
         first-param:A|B)"
    )]
    UnknownName(String),
    /// A motor outside 1 to 4.
    #[error("`{0}`: the motor is 1, 2, 3 or 4")]
    BadMotor(String),
    /// A status the hand does not name, or a status number the profile has no text for.
    #[error(
        "unknown status `{0}` (missed-position, uninitialized, terminate-uninitialized, bad-header, overtemp, \
         abort; status-text: a number the profile has)"
    )]
    UnknownStatus(String),
    /// Text where arithmetic needs a number.
    #[error("`{0}` is a name, not a number")]
    NotANumber(String),
    /// An operator other than `+` or `-`.
    #[error("operator `{0}`: `+` or `-`, with spaces around it")]
    Operator(String),
}

/// Where an `expect: values` step's positions (P) must read.
enum Positions {
    /// Within MPE of these goals (`expect: near`).
    Near([i64; 4]),
    /// In these ranges (`expect: positions`).
    Ranges([Range; 4]),
}

/// What an `expect:` line names.
enum Expected {
    /// A shape that needs nothing more.
    Shape(Shape),
    /// The values of the step's get line, positions as given (else their parameter's range).
    Values(Option<Positions>),
}

/// The lines of a case script that the suite reads and the script parser does not.
struct SuiteLines {
    /// The script with those lines blanked, so that line numbers stay.
    text: String,
    /// Each `expect:` line's number and shape, in order; it shapes the step before it.
    expects: Vec<(usize, Expected)>,
    /// Each `step-when:` line's number and conditions; they gate the step after it.
    whens: Vec<(usize, String)>,
    /// Each `rt-flags:` line's number and arguments; its set lines go before the step after it.
    rt_flags: Vec<(usize, String)>,
}

/// Splits the `expect:` and `step-when:` lines off a script.
fn split_suite_lines(text: &str) -> Result<SuiteLines, String> {
    let mut out = SuiteLines {
        text: String::with_capacity(text.len()),
        expects: Vec::new(),
        whens: Vec::new(),
        rt_flags: Vec::new(),
    };
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        if let Some(v) = line.trim_start().strip_prefix("expect:") {
            out.expects.push((n, expected(v.trim()).map_err(|e| format!("line {n}: {e}"))?));
        } else if let Some(v) = line.trim_start().strip_prefix("step-when:") {
            out.whens.push((n, v.trim().to_string()));
        } else if let Some(v) = line.trim_start().strip_prefix("rt-flags:") {
            out.rt_flags.push((n, v.trim().to_string()));
        } else {
            out.text.push_str(line);
        }
        out.text.push('\n');
    }
    Ok(out)
}

/// The shape an `expect:` line names.
fn expected(v: &str) -> Result<Expected, String> {
    let (word, rest) = v.split_once(' ').unwrap_or((v, ""));
    Ok(match word {
        "banner" => Expected::Shape(Shape::Banner),
        "banner-lines" => Expected::Shape(Shape::BannerLines),
        "any-lines" => Expected::Shape(Shape::AnyLines),
        "list-values" => Expected::Shape(Shape::ListValues),
        "values" => Expected::Values(None),
        "near" => {
            let goals: Vec<i64> = rest
                .split_whitespace()
                .map(str::parse)
                .collect::<Result<_, _>>()
                .map_err(|_| "`expect: near` takes four positions".to_string())?;
            let goals = <[i64; 4]>::try_from(goals).map_err(|_| "`expect: near` takes four positions".to_string())?;
            Expected::Values(Some(Positions::Near(goals)))
        }
        "positions" => {
            let ranges = rest.split_whitespace().map(range).collect::<Result<Vec<_>, _>>()?;
            let ranges = <[Range; 4]>::try_from(ranges)
                .map_err(|_| "`expect: positions` takes four ranges LO..HI".to_string())?;
            Expected::Values(Some(Positions::Ranges(ranges)))
        }
        "block" => Expected::Shape(Shape::Block(rest.split_whitespace().map(field_rule).collect::<Result<_, _>>()?)),
        other => {
            return Err(format!(
                "expect `{other}`: banner, banner-lines, any-lines, list-values, values, near, positions or block"
            ));
        }
    })
}

/// `LO..HI`, both whole numbers.
fn range(r: &str) -> Result<Range, String> {
    let bad = || format!("`{r}` is not a range LO..HI");
    let (lo, hi) = r.split_once("..").ok_or_else(bad)?;
    let (lo, hi) = (lo.parse().map_err(|_| bad())?, hi.parse().map_err(|_| bad())?);
    if lo > hi {
        return Err(bad());
    }
    Ok((lo, hi))
}

/// `[MOTOR:]FLAG=LO..HI`: a feedback field's accepted range (no motor: a hand-wide field).
fn field_rule(r: &str) -> Result<FieldRule, String> {
    let (field, lohi) = r.split_once('=').ok_or_else(|| format!("`{r}` is not [MOTOR:]FLAG=LO..HI"))?;
    let (motor, flag) = match field.split_once(':') {
        Some((m, f)) => match m.parse::<u8>() {
            Ok(m @ 1..=4) => (Some(m), f),
            _ => return Err(format!("`{r}`: the motor is 1, 2, 3 or 4")),
        },
        None => (None, field),
    };
    let flag = RtFlag::from_name(flag).ok_or_else(|| format!("`{r}`: `{flag}` is no RealTime flag"))?;
    Ok(FieldRule { motor, name: flag.name(), range: Some(range(lohi)?) })
}

/// The clause prefix that names a decision (`clause: decision:framing-echo`).
const DECISION_PREFIX: &str = super::super::build::DECISION_CLAUSE;

/// The clause prefix that names a clause of the profile's source (`clause: src:Command HI`).
const SRC_PREFIX: &str = "src:";

#[cfg(test)]
mod tests {
    use super::*;

    /// Every script makes a case for some built-in profile, and every script is placed by a
    /// generator exactly once for each profile it applies to.
    #[test]
    fn every_script_parses_and_is_placed() {
        for (id, _) in SCRIPTS {
            let mut applies = false;
            for name in Profile::builtin_names() {
                let p = Profile::builtin(name).unwrap();
                let g = Gen { p: p.clone(), out: Vec::new(), failed: None };
                let made = g.script_case(id).unwrap_or_else(|e| panic!("{e}"));
                applies |= made.is_some();
                let case_id = made.as_ref().map(|k| k.def.id.clone());
                let placed = catalogue(&p).unwrap().iter().filter(|c| Some(&c.id) == case_id.as_ref()).count();
                assert_eq!(placed, usize::from(made.is_some()), "{name}: case script `{id}` placed {placed} times");
            }
            assert!(applies, "case script `{id}` applies to no built-in profile");
        }
    }

    #[test]
    fn bad_scripts_are_clear_errors() {
        let p = Profile::builtin("seed").unwrap();
        let g = Gen { p, out: Vec::new(), failed: None };
        assert!(matches!(g.script_case("no-such-case"), Err(ScriptError::Missing(_))));
    }

    /// `expect:`, `step-when:` and `rt-flags:` lines leave the script's line numbers as they
    /// were and say what is wrong.
    #[test]
    fn suite_lines_are_read_and_checked() {
        let lines = split_suite_lines(
            "id: x\nRESET\nexpect: banner\nFGET P\nexpect: near 1 2 3 4\nstep-when: command:PDEF\nPDEF\nrt-flags: 1 LFAP\n\
             1LOOP\nblock: 41\nexpect: block 1:LFAP=0..20 LFT=-5..5\nFGET P\nexpect: positions 0..1 0..2 0..3 -4..4\n",
        )
        .unwrap();
        assert_eq!(lines.text, "id: x\nRESET\n\nFGET P\n\n\nPDEF\n\n1LOOP\nblock: 41\n\nFGET P\n\n");
        let [
            (3, Expected::Shape(Shape::Banner)),
            (5, Expected::Values(Some(Positions::Near([1, 2, 3, 4])))),
            (11, Expected::Shape(Shape::Block(rules))),
            (13, Expected::Values(Some(Positions::Ranges(ranges)))),
        ] = lines.expects.as_slice()
        else {
            panic!("expects read wrong")
        };
        assert_eq!(ranges, &[(0, 1), (0, 2), (0, 3), (-4, 4)]);
        assert_eq!(rules.len(), 2);
        assert_eq!((rules[0].motor, rules[0].name, rules[0].range), (Some(1), "LFAP", Some((0, 20))));
        assert_eq!((rules[1].motor, rules[1].name, rules[1].range), (None, "LFT", Some((-5, 5))));
        assert_eq!(lines.whens, vec![(6, "command:PDEF".to_string())]);
        assert_eq!(lines.rt_flags, vec![(8, "1 LFAP".to_string())]);

        let err = |t: &str| split_suite_lines(t).map(|_| ()).unwrap_err();
        let e = err("RESET\nexpect: banners\n");
        assert!(e.starts_with("line 2: expect `banners`"), "{e}");
        assert!(err("FGET P\nexpect: near 1 2\n").contains("four positions"));
        assert!(err("FGET P\nexpect: positions 0..1 0..2 0..3 5..4\n").contains("not a range"));
        assert!(err("A\nexpect: block 5:LFAP=0..1\n").contains("motor is 1, 2, 3 or 4"));
        assert!(err("A\nexpect: block 1:LFXX=0..1\n").contains("no RealTime flag"));
        assert!(err("A\nexpect: block 1:LFAP\n").contains("FLAG=LO..HI"));
        // `values` needs a get line of the first name's getter.
        let p = Profile::builtin("seed").unwrap();
        let k = CaseB::new(&p, "x", "x").line("FSET DP 5");
        let e = k.values_last(None).map(|_| ()).unwrap_err();
        assert!(e.contains("not a FGET line"), "{e}");
        let k = CaseB::new(&p, "x", "x").abort();
        assert!(k.values_last(None).map(|_| ()).is_err());
    }

    /// Expressions take the profile's numbers and names; anything else is a typed error with
    /// its line, never a panic.
    #[test]
    fn expressions_read_the_profile_and_refuse_unknown_names() {
        let p = Profile::builtin("seed").unwrap();
        let g = Gen { p: p.clone(), out: Vec::new(), failed: None };
        let (l4, mpe4) = (p.hand.spread_limit, g.mpe(4));
        let mp = StatusBits::from_bits_truncate(p.hand.missed_position_status).code();
        assert_eq!(
            g.expand("SM {limit:4 + mpe:4 + 1}\ngives {code:missed-position}\n{limit:4 - 10}..{limit:4}\n").unwrap(),
            format!("SM {}\ngives {mp}\n{}..{l4}\n", l4 + mpe4 + 1, l4 - 10)
        );
        let msg = if g.has_param("HSG") { "HSG" } else { "MSG" };
        assert_eq!(g.expand("GFSET {first-param:HSG|MSG} 0").unwrap(), format!("GFSET {msg} 0\n"));
        assert_eq!(g.expand("{first-param:NOPE|ALSO-NOT}").unwrap(), "ALSO-NOT\n");
        let e = |t: &str| g.expand(t).unwrap_err();
        assert_eq!(e("ok\nSM {limt:4}"), (2, ExprError::UnknownName("limt:4".into())));
        assert_eq!(e("{mpe:5}"), (1, ExprError::BadMotor("mpe:5".into())));
        assert_eq!(e("{mpe:x}"), (1, ExprError::BadMotor("mpe:x".into())));
        assert_eq!(e("{code:missed}"), (1, ExprError::UnknownStatus("missed".into())));
        assert_eq!(e("{status-text:3}"), (1, ExprError::UnknownStatus("3".into())));
        assert_eq!(e("{first-param:HSG|MSG + 1}"), (1, ExprError::NotANumber(msg.into())));
        assert_eq!(e("{limit:4 * 2}"), (1, ExprError::Operator("*".into())));
        assert_eq!(e("{limit:4 +}"), (1, ExprError::Empty("limit:4 +".into())));
        assert_eq!(e("{}"), (1, ExprError::Empty(String::new())));
        assert_eq!(e("SM {limit:4"), (1, ExprError::Unclosed));
        assert!(matches!(g.conditions_hold("status:nope"), Err(e) if e.contains("unknown status")));
        assert!(matches!(g.conditions_hold("nope:X"), Err(e) if e.contains("condition `nope:X`")));
        assert_eq!(g.conditions_hold("command:HI zero-min:NOPE|command:FGET"), Ok(true));
        assert_eq!(g.conditions_hold("command:HI param:NOPE"), Ok(false));
    }

    /// A profile a script cannot answer (here: no text for status 32) gets an error that
    /// names the script and line, not a suite with a case silently missing.
    #[test]
    fn a_profile_a_script_cannot_answer_is_an_error() {
        let mut p = (*Profile::builtin("seed").unwrap()).clone();
        p.status.retain(|s| s.bit != 32);
        let e = catalogue(&Arc::new(p)).map(|_| ()).unwrap_err();
        assert!(
            matches!(&e, ScriptError::Expr { id, line: 2, error: ExprError::UnknownStatus(n) }
                if id == "status-32-unknown-command" && n == "32"),
            "{e}"
        );
    }

    /// Every `.gcls` file under `conformance/suite-cases/` is embedded under its file name, and
    /// nothing else is: a script left out of [`SCRIPTS`] would silently check nothing.
    #[test]
    fn every_script_file_is_embedded() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("suite-cases");
        let mut files = Vec::new();
        for area in std::fs::read_dir(&root).unwrap() {
            let area = area.unwrap().path();
            if !area.is_dir() {
                continue;
            }
            for f in std::fs::read_dir(&area).unwrap() {
                let f = f.unwrap().path();
                assert_eq!(f.extension().and_then(|e| e.to_str()), Some("gcls"), "{}", f.display());
                let stem = f.file_stem().and_then(|s| s.to_str()).unwrap().to_string();
                let text = std::fs::read_to_string(&f).unwrap();
                let embedded = SCRIPTS.iter().find(|(id, _)| *id == stem).map(|(_, t)| *t);
                assert_eq!(embedded, Some(text.as_str()), "{} is not embedded as `{stem}`", f.display());
                files.push(stem);
            }
        }
        files.sort();
        let mut keys: Vec<String> = SCRIPTS.iter().map(|(id, _)| (*id).to_string()).collect();
        keys.sort();
        assert_eq!(files, keys, "SCRIPTS and the files under conformance/suite-cases differ");
    }

    /// A file is named by its id with the expressions dropped.
    #[test]
    fn script_names_drop_expressions() {
        assert_eq!(script_name("status-{code:abort}-abort"), "status-abort");
        assert_eq!(script_name("framing-echo"), "framing-echo");
        assert_eq!(script_name("{code:abort}-x-{mpe:1}"), "x");
    }

    /// One family of `conformance/suite-cases/generated.toml`.
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Family {
        ids: String,
        #[serde(default)]
        only: Vec<String>,
        kind: String,
        source: String,
        why: String,
    }

    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Generated {
        family: Vec<Family>,
    }

    /// Whether `id` is one of the family's ids for this profile: its placeholder stands for
    /// an entry of the profile's table (limited to `only` where given).
    fn family_has(f: &Family, p: &Profile, id: &str) -> bool {
        let Some((head, rest)) = f.ids.split_once('{') else { return f.ids == id };
        let Some((table, tail)) = rest.split_once('}') else { return false };
        let entries: Vec<String> = match table {
            "command" => p.commands.iter().map(|c| c.name.clone()).collect(),
            "param" => p.params.iter().map(|x| x.name.clone()).collect(),
            "rt-flag" => p.params.iter().filter(|x| x.rt.is_some()).map(|x| x.name.clone()).collect(),
            "status" => p.status.iter().map(|s| s.bit.to_string()).collect(),
            _ => return false,
        };
        entries
            .iter()
            .filter(|e| f.only.is_empty() || f.only.contains(e))
            .any(|e| id.strip_prefix(head).and_then(|r| r.strip_suffix(tail)) == Some(slug(e).as_str()))
    }

    /// Architecture invariant: a case written by hand is a script. Every case the code builds
    /// belongs to a family `conformance/suite-cases/generated.toml` lists with its reason (a
    /// profile table it iterates, or arithmetic scripts cannot say), and every family listed
    /// still builds a case.
    #[test]
    fn every_case_in_code_is_a_listed_generator() {
        let generated: Generated = toml::from_str(include_str!("../../../suite-cases/generated.toml"))
            .unwrap_or_else(|e| panic!("generated.toml: {e}"));
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/suite/cases");
        for f in &generated.family {
            assert!(["table", "computed"].contains(&f.kind.as_str()), "{}: kind `{}`", f.ids, f.kind);
            assert!(dir.join(&f.source).is_file(), "{}: no source {}", f.ids, f.source);
            assert!(!f.why.trim().is_empty(), "{}: no reason", f.ids);
        }
        let mut used = vec![false; generated.family.len()];
        let mut bad = Vec::new();
        for name in Profile::builtin_names() {
            let p = Profile::builtin(name).unwrap();
            let g = Gen { p: p.clone(), out: Vec::new(), failed: None };
            let scripted: Vec<String> =
                SCRIPTS.iter().filter_map(|(id, _)| g.script_case(id).ok().flatten().map(|k| k.def.id)).collect();
            for case in catalogue(&p).unwrap().iter().filter(|c| !scripted.contains(&c.id)) {
                let mut listed = false;
                for (f, u) in generated.family.iter().zip(used.iter_mut()) {
                    if family_has(f, &p, &case.id) {
                        (listed, *u) = (true, true);
                    }
                }
                if !listed {
                    bad.push(format!("{name}: {}", case.id));
                }
            }
        }
        assert!(
            bad.is_empty(),
            "cases built in code that no family of conformance/suite-cases/generated.toml names (write a \
             hand-written case as a script):\n{}",
            bad.join("\n")
        );
        let dead: Vec<&str> =
            generated.family.iter().zip(&used).filter(|(_, u)| !**u).map(|(f, _)| f.ids.as_str()).collect();
        assert!(dead.is_empty(), "families in generated.toml that build no case: {dead:?}");
    }
}
