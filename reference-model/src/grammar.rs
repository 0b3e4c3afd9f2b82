//! The grammar of a supervisory command line: bytes in, a typed [`Command`] or a
//! [`Rejected`] with the status the firmware gives.
//!
//! This module owns tokenising, prefix rules, argument rules and static value checks (range,
//! read-only). It never looks at the hand's state: whether a motor is initialised or a
//! position is reachable is the device's business.

use std::fmt;

use serde::Serialize;

use crate::motor::MotorSet;
use crate::spec::{ArgRule, CommandId, CommandKind, ParamId, PrefixRule, Profile};
use crate::status::StatusBits;

/// A parsed line.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub enum Line {
    /// Nothing but separators: the hand prints a fresh prompt.
    Empty,
    /// A command.
    Command(Command),
}

/// A typed supervisory command.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Command {
    /// The motor prefix, if one was given.
    pub prefix: Option<MotorSet>,
    /// The command.
    pub command: CommandId,
    /// What followed the command word.
    pub args: Args,
}

/// The arguments of a command, already checked against the profile.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub enum Args {
    /// No arguments.
    None,
    /// One integer (M, IC, IO, ERR).
    Integer(i64),
    /// Parameter names (FGET, PGET).
    Names(Vec<ParamId>),
    /// Name/value pairs (FSET, PSET).
    Pairs(Vec<(ParamId, i64)>),
    /// The command `?CMD` asks about.
    Topic(CommandId),
}

/// One thing wrong with a line. Each maps to one status bit.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub enum Problem {
    /// The command word is not in the profile (32).
    UnknownCommand(String),
    /// A prefix on a command that takes none (4096).
    PrefixNotAllowed,
    /// More arguments than the command takes, or a line past the length limit (1024).
    TooManyArguments,
    /// A parameter name the command does not know (64).
    UnknownParameter(String),
    /// A value that is not a decimal integer, is out of range, or is missing (128).
    InvalidValue(String),
    /// A write to a read-only parameter (256).
    ReadOnly(String),
}

impl Problem {
    /// The status bit this problem sets.
    pub fn status(&self) -> StatusBits {
        match self {
            Problem::UnknownCommand(_) => StatusBits::UNKNOWN_COMMAND,
            Problem::PrefixNotAllowed => StatusBits::PREFIX_NOT_ALLOWED,
            Problem::TooManyArguments => StatusBits::TOO_MANY_ARGUMENTS,
            Problem::UnknownParameter(_) => StatusBits::UNKNOWN_PARAMETER,
            Problem::InvalidValue(_) => StatusBits::INVALID_VALUE,
            Problem::ReadOnly(_) => StatusBits::READ_ONLY,
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Problem::UnknownCommand(w) => write!(f, "unknown command `{w}`"),
            Problem::PrefixNotAllowed => write!(f, "this command takes no motor prefix"),
            Problem::TooManyArguments => write!(f, "too many arguments"),
            Problem::UnknownParameter(n) => write!(f, "unknown parameter `{n}` for this command"),
            Problem::InvalidValue(v) => write!(f, "invalid value: {v}"),
            Problem::ReadOnly(n) => write!(f, "`{n}` is read-only"),
        }
    }
}

/// A line the hand refuses, with every problem found in it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[error("rejected with status {}", status.code())]
pub struct Rejected {
    /// The OR of the problems' bits: what follows `ERR`.
    pub status: StatusBits,
    /// What was wrong, in the order found.
    pub problems: Vec<Problem>,
    /// For a refused set line: the command with only the pairs that were valid on their own
    /// (what a hand that applies half a line would apply); `None` otherwise.
    #[serde(skip)]
    pub partial: Option<Command>,
}

impl Rejected {
    fn new(problems: Vec<Problem>) -> Rejected {
        let status = problems.iter().fold(StatusBits::empty(), |s, p| s | p.status());
        Rejected { status, problems, partial: None }
    }
}

/// Knobs that change the grammar. The defaults are the protocol; the others exist for the
/// simulator's deliberate faults.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ParseOptions {
    /// Refuse command words that are not upper case (a plausible firmware bug).
    pub case_sensitive_commands: bool,
    /// A prefix on a command that takes none is ignored, when it is the line's only problem.
    pub ignore_forbidden_prefix: bool,
    /// A set line whose last name has no value runs without that name, when that is the
    /// line's only problem.
    pub drop_last_name_without_value: bool,
    /// A value one past a parameter's maximum is accepted, when such values are the line's
    /// only problems.
    pub accept_one_past_max: bool,
    /// The `G` prefix names the spread too.
    pub g_includes_spread: bool,
}

fn is_sep(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n')
}

fn tokens(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    bytes.split(|b| is_sep(*b)).filter(|t| !t.is_empty())
}

fn show(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Parses a decimal integer as GCL writes them: an optional minus sign and 1 to 18 digits.
pub fn parse_integer(token: &[u8]) -> Option<i64> {
    let (neg, digits) = match token.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, token),
    };
    if digits.is_empty() || digits.len() > 18 || !digits.iter().all(u8::is_ascii_digit) {
        return None;
    }
    let v = digits.iter().fold(0i64, |a, d| a * 10 + i64::from(d - b'0'));
    Some(if neg { -v } else { v })
}

/// Parses one command line (without its CR) under the protocol's rules.
pub fn parse_line(profile: &Profile, line: &[u8]) -> Result<Line, Rejected> {
    parse_line_with(profile, line, ParseOptions::default())
}

/// Parses one command line with explicit options.
pub fn parse_line_with(profile: &Profile, line: &[u8], opts: ParseOptions) -> Result<Line, Rejected> {
    let skip_seps = |s: &[u8]| -> usize { s.iter().take_while(|b| is_sep(**b)).count() };
    let mut rest = line.get(skip_seps(line)..).unwrap_or_default();
    if rest.is_empty() {
        return Ok(Line::Empty);
    }
    // The prefix: the leading run of prefix characters.
    let mut prefix = MotorSet::EMPTY;
    let mut has_prefix = false;
    while let Some((&c, after)) = rest.split_first() {
        match profile.prefix_motors(c as char) {
            Some(ms) if c.is_ascii() => {
                prefix = prefix | MotorSet::from_motors(ms.iter().copied());
                if opts.g_includes_spread && c.eq_ignore_ascii_case(&b'G') {
                    prefix = prefix | MotorSet::SPREAD;
                }
                has_prefix = true;
                rest = after;
            }
            _ => break,
        }
    }
    let rest = rest.get(skip_seps(rest)..).unwrap_or_default();
    let word_end = rest.iter().position(|b| is_sep(*b)).unwrap_or(rest.len());
    let (word, after_word) = rest.split_at_checked(word_end).unwrap_or((rest, &[]));
    let mut args = tokens(after_word);
    let mut problems = Vec::new();

    if word.is_empty() {
        return Err(Rejected::new(vec![Problem::UnknownCommand(String::new())]));
    }
    let lookup = |w: &[u8]| -> Option<CommandId> {
        let w = std::str::from_utf8(w).ok()?;
        let id = profile.command_id(w)?;
        if opts.case_sensitive_commands && profile.command(id).name != w {
            return None;
        }
        Some(id)
    };

    // `?CMD`: the help command with the topic glued on.
    let (id, topic) = match lookup(word) {
        Some(id) => (id, None),
        None if let Some(topic) = word.strip_prefix(b"?") => match profile.command_of_kind(CommandKind::Help) {
            Some(help) => match lookup(topic) {
                Some(t) => (help, Some(t)),
                None => return Err(Rejected::new(vec![Problem::UnknownCommand(show(topic))])),
            },
            None => return Err(Rejected::new(vec![Problem::UnknownCommand(show(word))])),
        },
        None => return Err(Rejected::new(vec![Problem::UnknownCommand(show(word))])),
    };
    let spec = profile.command(id);
    let forbidden_prefix = has_prefix && spec.prefix == PrefixRule::Forbidden;
    if forbidden_prefix {
        problems.push(Problem::PrefixNotAllowed);
    }
    let mut partial = None;

    let parsed_args = if let Some(t) = topic {
        if args.next().is_some() {
            problems.push(Problem::TooManyArguments);
        }
        Args::Topic(t)
    } else {
        match spec.args {
            ArgRule::None => {
                if args.next().is_some() {
                    problems.push(Problem::TooManyArguments);
                }
                Args::None
            }
            ArgRule::OptionalInteger => match (args.next(), args.next()) {
                (None, _) => Args::None,
                (Some(_), Some(_)) => {
                    problems.push(Problem::TooManyArguments);
                    Args::None
                }
                (Some(tok), None) => {
                    let (lo, hi) = (spec.arg_min.unwrap_or(i64::MIN), spec.arg_max.unwrap_or(i64::MAX));
                    match parse_integer(tok) {
                        Some(v) if (lo..=hi).contains(&v) => Args::Integer(v),
                        _ => {
                            problems.push(Problem::InvalidValue(format!("`{}` (expected {lo}..{hi})", show(tok))));
                            Args::None
                        }
                    }
                }
            },
            ArgRule::Names => {
                let mut names = Vec::new();
                for tok in args {
                    match name_for(profile, tok, &spec.name, false) {
                        Ok(p) => names.push(p),
                        Err(pr) => problems.push(pr),
                    }
                }
                if names.is_empty() && problems.is_empty() {
                    problems.push(Problem::InvalidValue("a parameter name is required".into()));
                }
                Args::Names(names)
            }
            ArgRule::Pairs => {
                let mut pairs = Vec::new();
                // Pairs valid only one past the maximum (with `accept_one_past_max`), and
                // their problems in case they are not the only ones.
                let mut one_past = Vec::new();
                let mut missing_last = false;
                let mut any = false;
                while let Some(name) = args.next() {
                    any = true;
                    let value = args.next();
                    let param = name_for(profile, name, &spec.name, true);
                    match (param, value) {
                        (Err(pr), _) => problems.push(pr),
                        (Ok(_), None) => {
                            missing_last = true;
                            problems.push(Problem::InvalidValue(format!("no value for `{}`", show(name))))
                        }
                        (Ok(p), Some(text)) => match parse_integer(text) {
                            Some(v) if profile.value_ok(p, v) => pairs.push((p, v)),
                            parsed => {
                                let ps = profile.param(p);
                                let pr = Problem::InvalidValue(format!(
                                    "`{}` for {} (expected {})",
                                    show(text),
                                    ps.name,
                                    match &ps.values {
                                        Some(vs) => format!("one of {vs:?}"),
                                        None => format!("{}..{}", ps.min, ps.max),
                                    }
                                ));
                                match parsed {
                                    Some(v) if opts.accept_one_past_max && ps.values.is_none() && v == ps.max + 1 => {
                                        one_past.push((pairs.len(), (p, v), pr))
                                    }
                                    _ => problems.push(pr),
                                }
                            }
                        },
                    }
                }
                if !any {
                    problems.push(Problem::InvalidValue("a name and a value are required".into()));
                }
                if opts.drop_last_name_without_value && missing_last && problems.len() == 1 && one_past.is_empty() {
                    problems.clear();
                }
                // `one_past` is empty unless `accept_one_past_max`.
                if !problems.is_empty() {
                    problems.extend(one_past.into_iter().map(|(_, _, pr)| pr));
                } else {
                    for (at, pair, _) in one_past.into_iter().rev() {
                        pairs.insert(at.min(pairs.len()), pair);
                    }
                }
                if !problems.is_empty() && !forbidden_prefix && !pairs.is_empty() {
                    partial = Some(Command {
                        prefix: has_prefix.then_some(prefix),
                        command: id,
                        args: Args::Pairs(pairs.clone()),
                    });
                }
                Args::Pairs(pairs)
            }
        }
    };
    if opts.ignore_forbidden_prefix && problems == [Problem::PrefixNotAllowed] {
        return Ok(Line::Command(Command { prefix: None, command: id, args: parsed_args }));
    }
    if !problems.is_empty() {
        return Err(Rejected { partial, ..Rejected::new(problems) });
    }
    Ok(Line::Command(Command { prefix: has_prefix.then_some(prefix), command: id, args: parsed_args }))
}

/// Resolves a parameter name for a get (`set == false`) or a set command.
fn name_for(profile: &Profile, tok: &[u8], command: &str, set: bool) -> Result<ParamId, Problem> {
    let unknown = || Problem::UnknownParameter(show(tok));
    let name = std::str::from_utf8(tok).map_err(|_| unknown())?;
    let id = profile.param_id(name).ok_or_else(unknown)?;
    let p = profile.param(id);
    if set {
        // A read-only parameter read by the matching get command is "read-only", not unknown.
        let matching_get = match command {
            "FSET" => "FGET",
            "PSET" => "PGET",
            _ => "",
        };
        if p.read_only && profile.getter(id) == matching_get {
            return Err(Problem::ReadOnly(p.name.clone()));
        }
        if profile.setter(id) != command || p.read_only {
            return Err(unknown());
        }
    } else if profile.getter(id) != command {
        return Err(unknown());
    }
    Ok(id)
}

impl Command {
    /// The canonical text of the command (no CR): prefix digits ascending, the command word,
    /// then the arguments separated by single spaces. Parsing it gives back `self`.
    pub fn to_line(&self, profile: &Profile) -> String {
        let mut s = String::new();
        if let Some(p) = self.prefix {
            s.push_str(&p.to_string());
        }
        s.push_str(&profile.command(self.command).name);
        match &self.args {
            Args::None => {}
            Args::Integer(v) => s.push_str(&format!(" {v}")),
            Args::Names(ns) => {
                for n in ns {
                    s.push(' ');
                    s.push_str(&profile.param(*n).name);
                }
            }
            Args::Pairs(ps) => {
                for (n, v) in ps {
                    s.push_str(&format!(" {} {v}", profile.param(*n).name));
                }
            }
            Args::Topic(t) => s.push_str(&profile.command(*t).name),
        }
        s
    }

    /// The kind of the command.
    pub fn kind(&self, profile: &Profile) -> CommandKind {
        profile.command(self.command).kind
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seed() -> std::sync::Arc<Profile> {
        Profile::builtin("seed").unwrap()
    }

    #[test]
    fn prefixes_and_case() {
        let p = seed();
        let Ok(Line::Command(c)) = parse_line(&p, b"12fset lcv 1 LFDPC 2") else { panic!() };
        assert_eq!(c.prefix, Some(MotorSet::from_motors([1, 2])));
        assert_eq!(c.to_line(&p), "12FSET LCV 1 LFDPC 2");
        let Ok(Line::Command(c)) = parse_line(&p, b"  GS  C") else { panic!() };
        assert_eq!(c.prefix, Some(MotorSet::ALL));
        let Ok(Line::Command(c)) = parse_line(&p, b"SFSET DS 100") else { panic!() };
        assert_eq!(c.prefix, Some(MotorSet::SPREAD));
        assert_eq!(parse_line(&p, b"   "), Ok(Line::Empty));
    }

    #[test]
    fn fault_options_bend_only_the_line_they_are_for() {
        let p = seed();
        let parse = |line: &str, opts: ParseOptions| parse_line_with(&p, line.as_bytes(), opts);
        let code = |r: Result<Line, Rejected>| r.err().map_or(0, |r| r.status.code());
        let prefix = ParseOptions { ignore_forbidden_prefix: true, ..ParseOptions::default() };
        let Ok(Line::Command(c)) = parse("1RESET", prefix) else { panic!("1RESET runs as RESET") };
        assert_eq!(c.prefix, None);
        assert_eq!(code(parse("1VERS 3", prefix)), 4096 | 1024, "not the only problem");
        let missing = ParseOptions { drop_last_name_without_value: true, ..ParseOptions::default() };
        let Ok(Line::Command(c)) = parse("FSET DP 5 MCV", missing) else { panic!("runs without MCV") };
        assert_eq!(c.to_line(&p), "FSET DP 5");
        assert_eq!(code(parse("FSET NOPE 1 DP", missing)), 64 | 128, "not the only problem");
        let past = ParseOptions { accept_one_past_max: true, ..ParseOptions::default() };
        let max = p.param(p.param_id("DP").unwrap()).max;
        let line = format!("FSET MCV 5 DP {}", max + 1);
        let Ok(Line::Command(c)) = parse(&line, past) else { panic!("one past the maximum accepted") };
        assert_eq!(c.to_line(&p), line);
        assert_eq!(code(parse(&format!("FSET DP {}", max + 2), past)), 128, "two past is still refused");
        assert_eq!(code(parse(&format!("FSET NOPE 1 DP {}", max + 1), past)), 64 | 128, "not the only problem");
        let g = ParseOptions { g_includes_spread: true, ..ParseOptions::default() };
        let Ok(Line::Command(c)) = parse("GC", g) else { panic!() };
        assert_eq!(c.prefix, Some(MotorSet::ALL));
        // A refused set line carries the pairs that were valid on their own.
        let r = parse_line(&p, b"12FSET DP 5 MCV 999999 DS 7").unwrap_err();
        let partial = r.partial.map(|c| c.to_line(&p));
        assert_eq!(partial.as_deref(), Some("12FSET DP 5 DS 7"));
        assert_eq!(parse_line(&p, b"1RESET").unwrap_err().partial, None);
    }

    #[test]
    fn case_sensitive_fault_refuses_lower_case() {
        let p = seed();
        let opts = ParseOptions { case_sensitive_commands: true, ..ParseOptions::default() };
        assert!(parse_line_with(&p, b"hi", opts).is_err());
        assert!(parse_line_with(&p, b"HI", opts).is_ok());
    }
}
