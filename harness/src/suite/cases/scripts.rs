//! Hand-written cases as data: `harness/suite-cases/<area>/<id>.gcls`, embedded in the binary.
//!
//! A case script is a `gcl record` script ([`gcl_transcript::script`]) whose header says what
//! the suite needs besides the steps:
//!
//! ```text
//! id: framing-echo                    the case id (also the file name)
//! title: Every byte of a line is echoed as sent
//! clause: decision:framing-echo       a decision the case checks, cited when the profile has it
//! clause: src:Command ^C              a clause of the profile's own source (`seed:`/`manual:`)
//! clause: seed: Example Programs      any other clause, literally (clauses keep their order)
//! x-preamble: motion                  none | idle (^C, RESET, FDEF, PDEF) | motion (idle + HI)
//! x-when: command:PSAVE param:OTEMP   only for profiles with all of these (command:NAME,
//!                                     param:NAME, alias:NAME (a parameter that names
//!                                     another's value), decision:ID); `a|b` holds when
//!                                     either does
//! profile: seed                       only for these profiles (default: every profile)
//! level: MUST  requires: motion  note: ...   as in a transcript
//! ```
//!
//! Steps are the script's: host lines, `line:`, `nowait:`, `raw:`, `partial:`, `abort`,
//! `wait`, `pause:`; every answer is written exactly as the model gives it, unless an
//! `expect:` line after the step gives it a shape (the suite's own key, read here and not by
//! the script parser):
//!
//! ```text
//! expect: banner          a RESET banner: `{any}BarrettHand Firmware{any}`
//! expect: banner-lines    a banner checked for the line endings hosts rely on
//! expect: any-lines       the echo, then any lines (only their presence is checked)
//! expect: list-values     `NAME value...` lines, live values elided to their ranges
//! expect: values          a get line's values (`[motors]FGET|PGET NAME...`), each live value
//!                         elided to its parameter's range, as the generators' `get` does
//! expect: near 5000 5000 5000 0   as `values`, positions (P) within MPE of these goals, one
//!                         per motor (the profile's MPE defaults)
//! ```
//!
//! A `timeout:` line gives the step after it a `within` floor. Cases whose answers need
//! per-value ranges or RealTime blocks, or whose lines are computed from the profile, stay in
//! the generators.

use gcl_transcript::ParseError;
use gcl_transcript::script::{ScriptStep, parse_script};

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
];

/// Why a case script does not make a case.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ScriptError {
    /// No script has this id.
    #[error("no case script `{0}`")]
    Missing(String),
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
    /// A script that does not make a case adds nothing; the tests below name it.
    pub(super) fn scripts(&mut self, ids: &[&str]) {
        for id in ids {
            if let Ok(Some(k)) = self.script_case(id) {
                self.add(k);
            }
        }
    }

    /// The case of one script for this profile: `None` when the script names other profiles.
    pub(super) fn script_case(&self, id: &str) -> Result<Option<CaseB>, ScriptError> {
        let text = SCRIPTS.iter().find(|(i, _)| *i == id).map(|(_, t)| *t).ok_or(ScriptError::Missing(id.into()))?;
        let invalid = |reason: String| ScriptError::Invalid { id: id.into(), reason };
        let (text, expects) = split_expects(text).map_err(invalid)?;
        let script = parse_script(&text).map_err(|error| ScriptError::Parse { id: id.into(), error })?;
        let f = &script.fields;
        if f.id.as_deref() != Some(id) {
            return Err(invalid(format!("its `id:` is {:?}, not its file name", f.id)));
        }
        let title = f.title.clone().ok_or_else(|| invalid("no `title:`".into()))?;
        if !f.profiles.is_empty() && !f.profiles.contains(&self.p.id) {
            return Ok(None);
        }
        let mut k = self.case(id.to_string(), title);
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
                    for cond in value.split_whitespace() {
                        let mut holds = false;
                        for alt in cond.split('|') {
                            holds |= match alt.split_once(':') {
                                Some(("command", n)) => self.has_cmd(n),
                                Some(("param", n)) => self.has_param(n),
                                Some(("alias", n)) => self.param(n).is_some_and(|x| x.alias_of.is_some()),
                                Some(("decision", d)) => self.has_decision(d),
                                _ => {
                                    return Err(invalid(format!(
                                        "x-when `{alt}`: command:, param:, alias: or decision:"
                                    )));
                                }
                            };
                        }
                        if !holds {
                            return Ok(None);
                        }
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
                _ => return Err(invalid(format!("unknown key `{key}` (x-preamble, x-when)"))),
            }
        }
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
        for (i, step) in script.steps.iter().enumerate() {
            k = Self::script_step(k, step, timeout);
            timeout = step.timeout;
            let next = script.steps.get(i + 1).map_or(usize::MAX, |s| s.line);
            if let Some((n, shape)) = expects.next_if(|(n, _)| *n < next) {
                if expects.peek().is_some_and(|(m, _)| *m < next) {
                    return Err(invalid(format!("line {n}: two `expect:` lines for one step")));
                }
                k = match shape {
                    Expected::Shape(shape) => k.shape_last(shape),
                    Expected::Values(goals) => {
                        k.values_last(goals.map(|g| self.near(g))).map_err(|e| invalid(format!("line {n}: {e}")))?
                    }
                };
            }
        }
        if let Some((n, _)) = expects.next() {
            return Err(invalid(format!("line {n}: `expect:` before any step")));
        }
        Ok(Some(k))
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

/// What an `expect:` line names.
enum Expected {
    /// A shape that needs nothing more.
    Shape(Shape),
    /// The values of the step's get line; positions within MPE of these goals, if given.
    Values(Option<[i64; 4]>),
}

/// The script without its `expect:` lines (blanked, so line numbers stay), and each one's
/// line with the shape it names, in order. An `expect:` line shapes the step before it.
fn split_expects(text: &str) -> Result<(String, Vec<(usize, Expected)>), String> {
    let mut out = String::with_capacity(text.len());
    let mut expects = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if let Some(v) = line.trim_start().strip_prefix("expect:") {
            let shape = match v.trim() {
                "banner" => Expected::Shape(Shape::Banner),
                "banner-lines" => Expected::Shape(Shape::BannerLines),
                "any-lines" => Expected::Shape(Shape::AnyLines),
                "list-values" => Expected::Shape(Shape::ListValues),
                "values" => Expected::Values(None),
                near if near.starts_with("near ") => {
                    let goals: Vec<i64> = near.split_whitespace().skip(1).filter_map(|g| g.parse().ok()).collect();
                    let goals = <[i64; 4]>::try_from(goals)
                        .map_err(|_| format!("line {}: `expect: near` takes four positions", i + 1))?;
                    Expected::Values(Some(goals))
                }
                other => {
                    return Err(format!(
                        "line {}: expect `{other}`: banner, banner-lines, any-lines, list-values, values or near",
                        i + 1
                    ));
                }
            };
            expects.push((i + 1, shape));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    Ok((out, expects))
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
                let g = Gen { p: p.clone(), out: Vec::new() };
                let made = g.script_case(id).unwrap_or_else(|e| panic!("{e}"));
                applies |= made.is_some();
                let placed = catalogue(&p).iter().filter(|c| c.id == *id).count();
                assert_eq!(placed, usize::from(made.is_some()), "{name}: case script `{id}` placed {placed} times");
            }
            assert!(applies, "case script `{id}` applies to no built-in profile");
        }
    }

    #[test]
    fn bad_scripts_are_clear_errors() {
        let p = Profile::builtin("seed").unwrap();
        let g = Gen { p, out: Vec::new() };
        assert!(matches!(g.script_case("no-such-case"), Err(ScriptError::Missing(_))));
    }

    /// `expect:` lines leave the script's line numbers as they were and say what is wrong.
    #[test]
    fn expect_lines_are_read_and_checked() {
        let (text, expects) = split_expects("id: x\nRESET\nexpect: banner\nFGET P\nexpect: near 1 2 3 4\n").unwrap();
        assert_eq!(text, "id: x\nRESET\n\nFGET P\n\n");
        assert!(matches!(
            expects.as_slice(),
            [(3, Expected::Shape(Shape::Banner)), (5, Expected::Values(Some([1, 2, 3, 4])))]
        ));
        let e = split_expects("RESET\nexpect: banners\n").map(|_| ()).unwrap_err();
        assert!(e.starts_with("line 2: expect `banners`"), "{e}");
        let e = split_expects("FGET P\nexpect: near 1 2\n").map(|_| ()).unwrap_err();
        assert!(e.contains("four positions"), "{e}");
        // `values` needs a get line of the first name's getter.
        let p = Profile::builtin("seed").unwrap();
        let k = CaseB::new(&p, "x", "x").line("FSET DP 5");
        let e = k.values_last(None).map(|_| ()).unwrap_err();
        assert!(e.contains("not a FGET line"), "{e}");
        let k = CaseB::new(&p, "x", "x").abort();
        assert!(k.values_last(None).map(|_| ()).is_err());
    }
}
