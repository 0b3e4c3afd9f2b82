//! Properties of the grammar of a command line, in every built-in profile: typed commands
//! survive printing and parsing, case and separators do not change what a line means, and
//! each kind of mistake earns exactly its own status bit.

use std::sync::Arc;

use gcl_model::grammar::Problem;
use gcl_model::spec::{ArgRule, CommandId, CommandKind, ParamId, PrefixRule};
use gcl_model::{Args, Command, Line, MotorSet, Profile, StatusBits, parse_line};
use proptest::prelude::*;
use proptest::sample::select;
use proptest::strategy::ValueTree;
use proptest::test_runner::TestRunner;

const PROFILES: [&str; 3] = ["seed", "bh8-262-4.3", "bh8-262-4.4"];

fn profile(name: &str) -> Arc<Profile> {
    Profile::builtin(name).unwrap()
}

fn command_ids(p: &Profile) -> impl Iterator<Item = CommandId> + '_ {
    (0..p.commands.len()).map(|i| CommandId(i as u16))
}

/// Parameters `cmd` can read.
fn gettable(p: &Profile, cmd: &str) -> Vec<ParamId> {
    p.param_ids().filter(|id| p.getter(*id) == cmd).collect()
}

/// Parameters `cmd` can write.
fn settable(p: &Profile, cmd: &str) -> Vec<ParamId> {
    p.param_ids().filter(|id| p.setter(*id) == cmd && !p.param(*id).read_only).collect()
}

/// The status of a line: 0 when it parses.
fn status(p: &Profile, line: &str) -> u32 {
    match parse_line(p, line.as_bytes()) {
        Ok(_) => 0,
        Err(r) => r.status.code(),
    }
}

fn motor_set() -> impl Strategy<Value = MotorSet> {
    (1u8..16).prop_map(MotorSet::from_bits)
}

fn valid_value(p: &Profile, id: ParamId) -> BoxedStrategy<i64> {
    let ps = p.param(id);
    match &ps.values {
        Some(vs) => select(vs.clone()).boxed(),
        None => prop_oneof![Just(ps.min), Just(ps.max), ps.min..=ps.max].boxed(),
    }
}

fn args_for(p: &Arc<Profile>, id: CommandId) -> BoxedStrategy<Args> {
    let spec = p.command(id);
    match spec.args {
        ArgRule::None if spec.kind == CommandKind::Help => {
            let n = p.commands.len() as u16;
            prop_oneof![Just(Args::None), (0..n).prop_map(|t| Args::Topic(CommandId(t)))].boxed()
        }
        ArgRule::None => Just(Args::None).boxed(),
        ArgRule::OptionalInteger => {
            let (lo, hi) = (spec.arg_min.unwrap(), spec.arg_max.unwrap());
            prop_oneof![Just(Args::None), (lo..=hi).prop_map(Args::Integer)].boxed()
        }
        ArgRule::Names => {
            proptest::collection::vec(select(gettable(p, &spec.name)), 1..5).prop_map(Args::Names).boxed()
        }
        ArgRule::Pairs => {
            let p2 = p.clone();
            let pair = select(settable(p, &spec.name)).prop_flat_map(move |id| (Just(id), valid_value(&p2, id)));
            proptest::collection::vec(pair, 1..4).prop_map(Args::Pairs).boxed()
        }
    }
}

/// A valid typed command of a profile: a command, a prefix when it takes one, arguments per
/// its rule.
fn command(p: Arc<Profile>) -> BoxedStrategy<Command> {
    let usable: Vec<CommandId> = command_ids(&p)
        .filter(|id| {
            let c = p.command(*id);
            match c.args {
                ArgRule::Names => !gettable(&p, &c.name).is_empty(),
                ArgRule::Pairs => !settable(&p, &c.name).is_empty(),
                _ => true,
            }
        })
        .collect();
    select(usable)
        .prop_flat_map(move |id| {
            let prefix = match p.command(id).prefix {
                PrefixRule::Allowed => proptest::option::of(motor_set()).boxed(),
                PrefixRule::Forbidden => Just(None).boxed(),
            };
            (prefix, args_for(&p, id)).prop_map(move |(prefix, args)| Command { prefix, command: id, args })
        })
        .boxed()
}

fn profile_and_command() -> impl Strategy<Value = (&'static str, Command)> {
    select(PROFILES.to_vec()).prop_flat_map(|name| (Just(name), command(profile(name))))
}

/// A small deterministic generator for the cosmetic choices of a spelling (splitmix64).
struct Dice(u64);

impl Dice {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }

    fn coin(&mut self) -> bool {
        self.next() & 1 == 1
    }

    /// `min` to `min + 2` separators, each a space or a tab.
    fn separators(&mut self, min: u64) -> String {
        (0..min + self.below(3)).map(|_| if self.coin() { ' ' } else { '\t' }).collect()
    }

    /// The same text with each letter's case chosen at random.
    fn any_case(&mut self, s: &str) -> String {
        s.chars().map(|c| if self.coin() { c.to_ascii_lowercase() } else { c.to_ascii_uppercase() }).collect()
    }

    /// A prefix naming exactly `set`: digits in any order, maybe repeated, `G` for 1+2+3 and
    /// `S` for 4.
    fn prefix(&mut self, set: MotorSet) -> String {
        let mut parts: Vec<String> = set.iter().map(|m| m.to_string()).collect();
        if set.contains(1) && set.contains(2) && set.contains(3) && self.coin() {
            parts.retain(|d| !["1", "2", "3"].contains(&d.as_str()));
            parts.push("G".into());
        }
        if set.contains(4) && self.coin() {
            parts.retain(|d| d != "4");
            parts.push("S".into());
        }
        if self.coin() {
            let i = self.below(parts.len() as u64) as usize;
            parts.push(parts[i].clone());
        }
        for i in (1..parts.len()).rev() {
            let j = self.below(i as u64 + 1) as usize;
            parts.swap(i, j);
        }
        self.any_case(&parts.concat())
    }
}

/// Spells a command the way a sloppy host might: any case, runs of spaces and tabs, prefix
/// letters, input aliases, leading zeros.
fn sloppy(p: &Profile, c: &Command, seed: u64) -> String {
    let mut dice = Dice(seed);
    let mut s = dice.separators(0);
    if let Some(set) = c.prefix {
        s.push_str(&dice.prefix(set));
        s.push_str(&dice.separators(0));
    }
    let word = &p.command(c.command).name;
    let mut tokens: Vec<String> = Vec::new();
    let number = |dice: &mut Dice, v: i64| {
        let zeros = if v >= 0 { "0".repeat(dice.below(3) as usize) } else { String::new() };
        format!("{zeros}{v}")
    };
    let name = |dice: &mut Dice, id: ParamId| {
        let ps = p.param(id);
        let mut names = vec![ps.name.clone()];
        names.extend(ps.input_aliases.iter().cloned());
        names[dice.below(names.len() as u64) as usize].clone()
    };
    match &c.args {
        Args::None => {}
        Args::Integer(v) => tokens.push(number(&mut dice, *v)),
        Args::Names(ns) => tokens.extend(ns.iter().map(|n| name(&mut dice, *n))),
        Args::Pairs(ps) => {
            for (n, v) in ps {
                tokens.push(name(&mut dice, *n));
                tokens.push(number(&mut dice, *v));
            }
        }
        Args::Topic(_) => {}
    }
    let word = match &c.args {
        Args::Topic(t) => format!("{word}{}", p.command(*t).name),
        _ => word.clone(),
    };
    s.push_str(&dice.any_case(&word));
    for t in tokens {
        s.push_str(&dice.separators(1));
        s.push_str(&dice.any_case(&t));
    }
    s.push_str(&dice.separators(0));
    s
}

/// Words that are no command of the profile and do not start with a prefix character.
fn unknown_word(p: Arc<Profile>) -> impl Strategy<Value = String> {
    "[A-Za-z][A-Za-z0-9]{0,7}".prop_filter("not a command, no prefix", move |w| {
        p.command_id(w).is_none() && p.prefix_motors(w.chars().next().unwrap()).is_none()
    })
}

/// Tokens a line is made of when nobody takes care: real words, numbers, noise.
fn token(p: &Profile) -> BoxedStrategy<String> {
    let commands: Vec<String> = p.commands.iter().map(|c| c.name.clone()).collect();
    let mut names: Vec<String> = p.params.iter().map(|q| q.name.clone()).collect();
    names.extend(p.params.iter().flat_map(|q| q.input_aliases.iter().cloned()));
    prop_oneof![
        1 => select(commands),
        3 => select(names),
        1 => select(vec!["1", "2", "3", "4", "G", "S", "12", "GS", "s4"]).prop_map(str::to_string),
        3 => (-100i64..70_000).prop_map(|v| v.to_string()),
        1 => "[A-Za-z?]{1,4}",
        1 => "[!-~]{1,3}",
    ]
    .boxed()
}

/// A line made of random tokens: an optional prefix and a command word, then anything.
fn careless_line() -> impl Strategy<Value = (&'static str, String)> {
    select(PROFILES.to_vec()).prop_flat_map(|name| {
        let p = profile(name);
        let words: Vec<String> = p.commands.iter().map(|c| c.name.clone()).collect();
        let head = (proptest::option::of(motor_set()), select(words));
        let tail = proptest::collection::vec(token(&p), 0..5);
        (Just(name), head, tail, any::<u64>()).prop_map(|(name, (prefix, word), tail, seed)| {
            let mut dice = Dice(seed);
            let mut s = dice.separators(0);
            if let Some(set) = prefix {
                s.push_str(&dice.prefix(set));
                s.push_str(&dice.separators(0));
            }
            s.push_str(&dice.any_case(&word));
            for t in tail {
                s.push_str(&dice.separators(1));
                s.push_str(&dice.any_case(&t));
            }
            (name, s)
        })
    })
}

/// `parse(to_line(parse(x))) == parse(x)` when `x` parses; returns whether it did.
fn reparse_is_stable(name: &str, line: &str) -> Result<bool, TestCaseError> {
    let p = profile(name);
    match parse_line(&p, line.as_bytes()) {
        Ok(Line::Command(c)) => {
            let again = parse_line(&p, c.to_line(&p).as_bytes());
            prop_assert_eq!(again, Ok(Line::Command(c)), "{:?} in {}", line, name);
            Ok(true)
        }
        Ok(Line::Empty) => Ok(false),
        Err(r) => {
            prop_assert!(!r.problems.is_empty());
            let or = r.problems.iter().fold(StatusBits::empty(), |s, pr| s | pr.status());
            prop_assert_eq!(r.status, or);
            Ok(false)
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn printed_commands_parse_back((name, c) in profile_and_command()) {
        let p = profile(name);
        let line = c.to_line(&p);
        prop_assert_eq!(parse_line(&p, line.as_bytes()), Ok(Line::Command(c)), "{:?} in {}", line, name);
    }

    #[test]
    fn case_separators_and_prefix_letters_do_not_matter((name, c) in profile_and_command(), seed in any::<u64>()) {
        let p = profile(name);
        let line = sloppy(&p, &c, seed);
        prop_assert_eq!(parse_line(&p, line.as_bytes()), Ok(Line::Command(c)), "{:?} in {}", line, name);
    }

    #[test]
    fn whatever_parses_reparses_the_same((name, line) in careless_line()) {
        reparse_is_stable(name, &line)?;
    }

    #[test]
    fn any_bytes_parse_or_are_rejected_with_a_status(name in select(PROFILES.to_vec()), bytes in proptest::collection::vec(any::<u8>(), 0..100)) {
        let p = profile(name);
        match parse_line(&p, &bytes) {
            Ok(Line::Command(c)) => {
                prop_assert_eq!(parse_line(&p, c.to_line(&p).as_bytes()), Ok(Line::Command(c)));
            }
            Ok(Line::Empty) => prop_assert!(bytes.iter().all(|b| b" \t\n".contains(b))),
            Err(r) => {
                prop_assert!(!r.status.is_empty());
                let or = r.problems.iter().fold(StatusBits::empty(), |s, pr| s | pr.status());
                prop_assert_eq!(r.status, or);
            }
        }
    }

    #[test]
    fn unknown_words_give_32(
        (name, word) in select(PROFILES.to_vec()).prop_flat_map(|name| (Just(name), unknown_word(profile(name)))),
        prefix in proptest::option::of(motor_set()),
        help_form in any::<bool>(),
        tail in proptest::collection::vec("[A-Za-z0-9]{1,5}", 0..3),
    ) {
        let p = profile(name);
        let word = if help_form { format!("?{word}") } else { word };
        let mut line = prefix.map(|s| s.to_string()).unwrap_or_default();
        line.push_str(&word);
        for t in &tail {
            line.push(' ');
            line.push_str(t);
        }
        let r = parse_line(&p, line.as_bytes()).unwrap_err();
        prop_assert_eq!(r.status, StatusBits::UNKNOWN_COMMAND, "{:?} in {}", line, name);
        prop_assert_eq!(r.problems.len(), 1);
    }

    #[test]
    fn out_of_range_values_give_128(
        (name, cmd, id) in select(PROFILES.to_vec()).prop_flat_map(|name| {
            let p = profile(name);
            let setters: Vec<(CommandId, ParamId)> = command_ids(&p)
                .filter(|c| p.command(*c).args == ArgRule::Pairs)
                .flat_map(|c| settable(&p, &p.command(c).name).into_iter().map(move |id| (c, id)))
                .collect();
            (Just(name), select(setters)).prop_map(|(n, (c, id))| (n, c, id))
        }),
        prefix in proptest::option::of(motor_set()),
        how in 0u8..4,
        offset in 1i64..100_000,
        lead_valid in any::<bool>(),
    ) {
        let p = profile(name);
        let spec = p.command(cmd);
        let ps = p.param(id);
        let value = match how {
            0 => (ps.max + offset).to_string(),
            1 => (ps.min - offset).to_string(),
            2 => format!("{}x", ps.min),
            _ => match &ps.values {
                Some(vs) => (ps.min..=ps.max).find(|v| !vs.contains(v)).unwrap().to_string(),
                None => format!("+{}", ps.min),
            },
        };
        let mut line = String::new();
        if spec.prefix == PrefixRule::Allowed && let Some(s) = prefix {
            line.push_str(&s.to_string());
        }
        line.push_str(&spec.name);
        if lead_valid {
            line.push_str(&format!(" {} {}", ps.name, ps.values.as_ref().map_or(ps.min, |v| v[0])));
        }
        line.push_str(&format!(" {} {value}", ps.name));
        prop_assert_eq!(status(&p, &line), 128, "{:?} in {}", line, name);
    }

    #[test]
    fn integer_arguments_out_of_range_give_128(
        (name, cmd) in select(PROFILES.to_vec()).prop_flat_map(|name| {
            let p = profile(name);
            let ids: Vec<CommandId> = command_ids(&p).filter(|c| p.command(*c).args == ArgRule::OptionalInteger).collect();
            (Just(name), select(ids))
        }),
        above in any::<bool>(),
        offset in 1i64..1_000_000,
    ) {
        let p = profile(name);
        let spec = p.command(cmd);
        let v = if above { spec.arg_max.unwrap() + offset } else { spec.arg_min.unwrap() - offset };
        let line = format!("{} {v}", spec.name);
        prop_assert_eq!(status(&p, &line), 128, "{:?} in {}", line, name);
    }

    #[test]
    fn names_a_command_does_not_know_give_64(
        name in select(PROFILES.to_vec()),
        pick in any::<proptest::sample::Index>(),
        word in "[A-Z]{1,3}[0-9Q]{1,2}",
    ) {
        let p = profile(name);
        let cmds: Vec<CommandId> =
            command_ids(&p).filter(|c| matches!(p.command(*c).args, ArgRule::Names | ArgRule::Pairs)).collect();
        let spec = p.command(*pick.get(&cmds));
        prop_assume!(p.param_id(&word).is_none());
        let line = match spec.args {
            ArgRule::Names => format!("{} {word}", spec.name),
            _ => format!("{} {word} 1", spec.name),
        };
        prop_assert_eq!(status(&p, &line), 64, "{:?} in {}", line, name);
        // A real name that belongs to another command is just as unknown here.
        let foreign: Vec<ParamId> = p
            .param_ids()
            .filter(|id| match spec.args {
                ArgRule::Names => p.getter(*id) != spec.name,
                _ => p.setter(*id) != spec.name && !p.param(*id).read_only,
            })
            .collect();
        if !foreign.is_empty() {
            let q = p.param(foreign[pick.index(foreign.len())]);
            let line = match spec.args {
                ArgRule::Names => format!("{} {}", spec.name, q.name),
                _ => format!("{} {} {}", spec.name, q.name, q.min),
            };
            prop_assert_eq!(status(&p, &line), 64, "{:?} in {}", line, name);
        }
    }

    #[test]
    fn a_prefix_where_none_is_allowed_gives_4096((name, c) in profile_and_command(), set in motor_set(), extra in any::<bool>()) {
        let p = profile(name);
        let spec = p.command(c.command);
        prop_assume!(spec.prefix == PrefixRule::Forbidden);
        let mut line = format!("{set}{}", c.to_line(&p));
        let mut want = StatusBits::PREFIX_NOT_ALLOWED;
        if extra && spec.args == ArgRule::None {
            line.push_str(" 1 2");
            want |= StatusBits::TOO_MANY_ARGUMENTS;
        }
        let r = parse_line(&p, line.as_bytes()).unwrap_err();
        prop_assert_eq!(r.status, want, "{:?} in {}", line, name);
    }

    #[test]
    fn extra_arguments_give_1024(
        (name, c) in profile_and_command(),
        extra in proptest::collection::vec("[A-Za-z0-9]{1,4}", 1..3),
    ) {
        let p = profile(name);
        let spec = p.command(c.command);
        let base = match (spec.args, &c.args) {
            (ArgRule::None, _) => c.to_line(&p),
            // A second integer after the first.
            (ArgRule::OptionalInteger, Args::Integer(_)) => c.to_line(&p),
            (ArgRule::OptionalInteger, _) => format!("{} {}", c.to_line(&p), spec.arg_min.unwrap()),
            _ => return Ok(()),
        };
        let line = format!("{base} {}", extra.join(" "));
        let r = parse_line(&p, line.as_bytes()).unwrap_err();
        prop_assert_eq!(r.status, StatusBits::TOO_MANY_ARGUMENTS, "{:?} in {}", line, name);
    }
}

#[test]
fn read_only_writes_give_256_in_every_profile() {
    for name in PROFILES {
        let p = profile(name);
        let mut checked = 0;
        for c in command_ids(&p)
            .filter(|c| p.command(*c).kind == CommandKind::MotorSet || p.command(*c).kind == CommandKind::GlobalSet)
        {
            let spec = p.command(c);
            let get_kind =
                if spec.kind == CommandKind::MotorSet { CommandKind::MotorGet } else { CommandKind::GlobalGet };
            let get = &p.command(p.command_of_kind(get_kind).unwrap()).name;
            for id in p.param_ids().filter(|id| p.param(*id).read_only && p.getter(*id) == get) {
                let ps = p.param(id);
                let line = format!("{} {} {}", spec.name, ps.name, ps.min);
                let r = parse_line(&p, line.as_bytes()).unwrap_err();
                assert_eq!(r.status, StatusBits::READ_ONLY, "{line:?} in {name}");
                assert_eq!(r.problems, vec![Problem::ReadOnly(ps.name.clone())]);
                checked += 1;
            }
        }
        assert!(checked >= 3, "{name}: only {checked} read-only parameters");
    }
}

/// The careless-line property above is not vacuous: a fair share of those lines parse.
#[test]
fn careless_lines_often_parse() {
    let mut runner = TestRunner::deterministic();
    let strategy = careless_line();
    let (mut parsed, total) = (0, 400);
    for _ in 0..total {
        let (name, line) = strategy.new_tree(&mut runner).unwrap().current();
        if reparse_is_stable(name, &line).unwrap() {
            parsed += 1;
        }
    }
    assert!(parsed * 10 > total, "only {parsed} of {total} lines parsed");
}
