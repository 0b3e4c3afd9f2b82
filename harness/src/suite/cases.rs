//! The catalogue: which cases each profile gets. Most are generated from the profile's tables
//! (every command with its prefix and argument rules, every parameter's default, range and
//! access, every status bit); a few are written by hand (the seed's examples, RealTime worked
//! examples, abort timing). Each case starts from the same preamble, so cases are independent
//! on a real hand, and takes its level from the decisions it checks.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::realtime::lfdp_step;
use gcl_model::spec::{ArgRule, CommandKind, CommandSpec, ParamSpec, PrefixRule, Scope};
use gcl_model::{Profile, StatusBits};

use super::build::{CaseB, CaseDef, FieldRule, Range, Shape};
use gcl_transcript::{Level, Requirement};

/// Every case of a profile, in catalogue order.
pub(crate) fn catalogue(p: &Arc<Profile>) -> Vec<CaseDef> {
    let mut g = Gen { p: p.clone(), out: Vec::new() };
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
    g.out
}

struct Gen {
    p: Arc<Profile>,
    out: Vec<CaseDef>,
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
        } else if motor == 4 {
            self.p.hand.spread_close_target.unwrap_or(self.p.hand.spread_limit)
        } else {
            self.p.hand.finger_close_target.unwrap_or(self.p.hand.finger_limit)
        }
    }

    /// The status a hand constant names, as the wire number.
    fn code(&self, bits: u32) -> u32 {
        StatusBits::from_bits_truncate(bits).code()
    }

    // ------------------------------------------------------------------ framing

    fn framing(&mut self) {
        let p = self.p.clone();
        let c = self
            .case(
                "framing-echo",
                "Every byte of a line is echoed as sent; answers start with LF CR; the CR is not echoed",
            )
            .decision("framing-echo")
            .preamble(false)
            .line("FGET DP")
            .line("BOGUS")
            .line("FGET DP MCV");
        self.add(c);

        let c = self
            .case("framing-empty-line", "A bare CR, or separators then CR, prints a fresh prompt and no status")
            .decision("framing-empty-line")
            .preamble(false)
            .line("")
            .line("   ")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case(
                "framing-case",
                "Command words, parameter names and prefix letters are case-insensitive; the echo keeps the case",
            )
            .decision("framing-case")
            .preamble(false)
            .line("fget dp")
            .line("Fget Dp Mcv")
            .line("sfget dp")
            .line("gFGET dp")
            .line("fset dp 1234")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case(
                "framing-whitespace",
                "Runs of spaces and tabs separate tokens; leading separators and a space after the prefix are accepted",
            )
            .decision("framing-whitespace")
            .preamble(false)
            .line("  FGET   DP")
            .line("FGET\tDP")
            .line("12 FGET DP")
            .line("FGET DP   ");
        self.add(c);

        let max = p.framing.max_line;
        let fits = fill_line("FGET", " DP", max);
        let over = format!("{fits}P");
        let c = self
            .case(
                "framing-max-line",
                format!("A line of {max} bytes is accepted; one byte more gives ERR {}", p.framing.overlong_status),
            )
            .decision("framing-max-line")
            .decision("framing-whitespace")
            .preamble(false)
            .line(&fits)
            .line(&over)
            .line("FGET DS");
        self.add(c);

        let c = self
            .case("framing-numbers", "Values are decimal integers only: hex, a plus sign, a fraction or a word is 128")
            .decision("framing-numbers")
            .preamble(false)
            .line("FSET DP 0x10")
            .line("FSET DP +5")
            .line("FSET DP 1.5")
            .line("FSET DP TRUE")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case("framing-errors-combine", "Problems in one line are OR'ed into one ERR")
            .decision("framing-errors-combine")
            .preamble(false)
            .line("FSET NOPE 1 DP 99999")
            .line("1FGET NOPE")
            .line("1FGET DP");
        self.add(c);

        let c = self
            .case("framing-line-atomic", "A line with an error changes nothing and prints no value line")
            .decision("framing-line-atomic")
            .decision("bh8-partial-errors")
            .preamble(false)
            .line("FSET DP 1234 MCV 99999")
            .line("FGET DP NOPE")
            .line("FGET DP MCV");
        self.add(c);

        let c = self
            .case("framing-backspace", "No line editing: backspace is an ordinary byte, echoed and kept")
            .decision("framing-backspace")
            .preamble(false)
            .raw(b"FGET DX\x08P\r")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case("framing-busy-input", "A line sent while a command runs is echoed and run after the prompt")
            .decision("framing-busy-input")
            .preamble(true)
            .raw(b"GC\rFGET DP\r")
            .within(Duration::from_secs(30))
            .wait();
        self.add(c);

        let c = self
            .case("framing-abort-partial-line", "^C discards a partial line and prints a fresh prompt")
            .decision("framing-abort-idle")
            .preamble(false)
            .partial(b"FGET D")
            .abort()
            .line("P")
            .line("FGET DP");
        self.add(c);
    }

    // ------------------------------------------------------------------ commands

    fn commands(&mut self) {
        let cmds = self.p.commands.clone();
        for c in &cmds {
            self.command_prefix(c);
            self.command_args(c);
            if c.kind.is_motion() || c.kind == CommandKind::Loop {
                self.command_before_hi(c);
            }
            if c.kind.is_motion() && self.p.hand.overtemp_status != 0 && self.has_param("OTEMP") {
                self.command_overtemp(c);
            }
            self.command_run(c);
        }
    }

    /// Arguments that make a valid line for a command.
    fn valid_args(&self, c: &CommandSpec) -> String {
        match c.args {
            ArgRule::None | ArgRule::OptionalInteger => String::new(),
            ArgRule::Names => self
                .p
                .params
                .iter()
                .find(|x| {
                    self.p.param_id(&x.name).is_some_and(|id| self.p.getter(id) == c.name) && x.alias_of.is_none()
                })
                .map_or(String::new(), |x| format!(" {}", x.name)),
            ArgRule::Pairs => self
                .writable_for(&c.name)
                .first()
                .map_or(String::new(), |x| format!(" {} {}", x.name, self.default(&x.name, 1))),
        }
    }

    /// Writable parameters set by `setter`, BAUD last (a change would move the line rate).
    fn writable_for(&self, setter: &str) -> Vec<ParamSpec> {
        let mut v: Vec<ParamSpec> = self
            .p
            .params
            .iter()
            .filter(|x| {
                !x.read_only
                    && !x.live
                    && x.alias_of.is_none()
                    && self.p.param_id(&x.name).is_some_and(|id| self.p.setter(id) == setter)
            })
            .cloned()
            .collect();
        v.sort_by_key(|x| x.name == "BAUD");
        v
    }

    fn command_prefix(&mut self, c: &CommandSpec) {
        let id = format!("cmd-{}-prefix", slug(&c.name));
        match c.prefix {
            PrefixRule::Forbidden => {
                let mut k = self
                    .case(id, format!("{} takes no motor prefix: a prefix gives 4096", c.name))
                    .src(&format!("Command {}", c.name));
                let cited: &[&str] = match c.name.as_str() {
                    "VERS" | "?" => &["seed-prefix-rules", "bh8-admin-prefixes"],
                    "FLISTA" => &["seed-flista", "bh8-list-prefixes"],
                    "FLISTAV" => &["seed-flista"],
                    "A?" | "RESET" | "ERR" => &["bh8-admin-prefixes"],
                    _ => &[],
                };
                k = self.cite_or_must(k, cited);
                let line = format!("1{}{}", c.name, self.valid_args(c));
                k = k.preamble(false).line(&line).line("FGET DP");
                self.add(k);
            }
            PrefixRule::Allowed => {
                let mut k = self
                    .case(id, format!("{} takes a motor prefix and acts on the motors it names", c.name))
                    .src(&format!("Command {}", c.name));
                if matches!(
                    c.kind,
                    CommandKind::MotorDefaults
                        | CommandKind::MotorLoad
                        | CommandKind::MotorSave
                        | CommandKind::Terminate
                ) {
                    k = k.decision("seed-prefix-rules");
                }
                if c.kind == CommandKind::MotorListAllValues {
                    k = k.decision("bh8-list-prefixes");
                }
                if matches!(c.kind, CommandKind::MotorListValues | CommandKind::MotorListAllValues) {
                    k = k.decision("seed-flista").decision("bh8-list-values-format");
                }
                k = self.prefixed_run(k, c);
                self.add(k);
            }
        }
    }

    /// The body of a prefix-allowed command's prefix case.
    fn prefixed_run(&self, k: CaseB, c: &CommandSpec) -> CaseB {
        let n = &c.name;
        match c.kind {
            CommandKind::Initialize => k
                .decision("seed-motion-before-hi")
                .decision("bh8-motion-before-hi")
                .preamble(false)
                .requires(Requirement::Motion)
                .line(&format!("1{n}"))
                .line("1M 1000")
                .line("2M 1000"),
            CommandKind::Terminate => k.preamble(true).line(&format!("1{n}")).line("FGET DP"),
            CommandKind::Loop => k.preamble(true).requires(Requirement::Realtime).line(&format!("1{n}")).abort(),
            kind if kind.is_motion() => {
                let (setup, goals) = self.motion_recipe(kind, "1");
                let mut k = k.preamble(true);
                if kind == CommandKind::Close {
                    k = k.decision("seed-close-open-targets");
                }
                for s in setup {
                    k = k.line(&s);
                }
                k.line(&format!("1{n}")).get("", &["P"], Some(goals))
            }
            CommandKind::MotorSet => k.preamble(false).line(&format!("2{n} DP 1234")).line("FGET DP"),
            CommandKind::MotorGet => {
                k.preamble(false).line(&format!("2{n} DP")).line(&format!("S{n} DP")).line(&format!("G{n} DP"))
            }
            CommandKind::MotorDefaults => k.preamble(false).line("FSET DP 1234").line(&format!("2{n}")).line("FGET DP"),
            CommandKind::MotorLoad => k
                .requires(Requirement::Eeprom)
                .preamble(false)
                .line("FSAVE")
                .line("FSET DP 1234")
                .line(&format!("2{n}"))
                .line("FGET DP"),
            CommandKind::MotorSave => k
                .requires(Requirement::Eeprom)
                .preamble(false)
                .line("FSET DP 1234")
                .line(&format!("2{n}"))
                .line_shaped("RESET", Shape::Banner)
                .line("FGET DP"),
            CommandKind::MotorListValues | CommandKind::MotorListAllValues => {
                k.preamble(false).line_shaped(&format!("2{n}"), Shape::ListValues)
            }
            _ => k.preamble(false).line(&format!("1{n}{}", self.valid_args(c))),
        }
    }

    /// Setup lines and the positions each motor reaches after `{prefix}CMD` for a motion kind.
    fn motion_recipe(&self, kind: CommandKind, prefix: &str) -> (Vec<String>, [Range; 4]) {
        let sel = super::build::prefix_motors(&self.p, prefix);
        let mut pos = [0i64; 4];
        let mut setup = Vec::new();
        let mut exact: [Option<Range>; 4] = [None; 4];
        let stage = |setup: &mut Vec<String>, pos: &mut [i64; 4]| {
            setup.push("M 3000".to_string());
            *pos = [3000; 4];
        };
        match kind {
            CommandKind::Close => {
                for m in &sel {
                    pos[*m as usize - 1] = self.close_target(*m);
                }
            }
            CommandKind::Open | CommandKind::Home | CommandKind::TorqueOpen => {
                stage(&mut setup, &mut pos);
                for m in &sel {
                    pos[*m as usize - 1] = if kind == CommandKind::Open { self.default("OT", *m) } else { 0 };
                }
            }
            CommandKind::Move => {
                for m in &sel {
                    pos[*m as usize - 1] = self.default("DP", *m).min(self.limit(*m));
                }
            }
            CommandKind::IncrementalClose => {
                for m in &sel {
                    pos[*m as usize - 1] = self.default("DS", *m).min(self.limit(*m));
                }
            }
            CommandKind::IncrementalOpen => {
                stage(&mut setup, &mut pos);
                for m in &sel {
                    let i = *m as usize - 1;
                    pos[i] = (pos[i] - self.default("DS", *m)).max(0);
                }
            }
            CommandKind::TorqueClose => {
                for m in &sel {
                    let l = self.limit(*m);
                    exact[*m as usize - 1] = Some((l - self.mpe(*m), l));
                }
            }
            _ => {}
        }
        let mut r = self.near(pos);
        for (i, e) in exact.iter().enumerate() {
            if let Some(e) = e {
                r[i] = *e;
            }
        }
        (setup, r)
    }

    fn command_args(&mut self, c: &CommandSpec) {
        let id = format!("cmd-{}-args", slug(&c.name));
        let n = &c.name;
        let mut k = self.case(id, format!("{n} refuses arguments it does not take")).src(&format!("Command {n}"));
        match c.args {
            ArgRule::None => {
                k = k.src("Status codes 1024");
                if matches!(c.kind, CommandKind::IncrementalClose | CommandKind::IncrementalOpen) {
                    k = k.decision("seed-ic-io-args");
                }
                if c.kind == CommandKind::Help {
                    k = k.decision("seed-help").decision("bh8-help-format");
                }
                // A motion command is checked on initialised motors, so that its answer does
                // not also depend on which of two problems a hand reports.
                let ready = c.kind.is_motion() || c.kind == CommandKind::Loop;
                k = k.preamble(ready).line(&format!("{n} 1")).line(&format!("{n} 1 2"));
            }
            ArgRule::OptionalInteger => {
                let (lo, hi) = (c.arg_min.unwrap_or(0), c.arg_max.unwrap_or(0));
                k = k.src("Status codes 128").src("Status codes 1024");
                if c.kind == CommandKind::ErrorText {
                    k = k.decision("seed-err-command").decision("bh8-err-format");
                }
                if c.kind.is_motion() {
                    k = k.decision("bh8-ic-io-range");
                }
                k = k.preamble(c.kind.is_motion()).line(&format!("{n} 1 2")).line(&format!("{n} {}", hi + 1));
                if lo > -(1 << 40) {
                    k = k.line(&format!("{n} {}", lo - 1));
                }
            }
            ArgRule::Names => {
                k = k
                    .title_set(format!("{n} without a name gives 128"))
                    .decision("framing-missing-value")
                    .preamble(false)
                    .line(n);
            }
            ArgRule::Pairs => {
                let first = self.writable_for(n).first().map(|x| x.name.clone()).unwrap_or_default();
                k = k
                    .title_set(format!("{n} without a value gives 128"))
                    .decision("framing-missing-value")
                    .preamble(false)
                    .line(n)
                    .line(&format!("{n} {first}"));
            }
        }
        k = k.line("FGET DP");
        self.add(k);
    }

    fn command_before_hi(&mut self, c: &CommandSpec) {
        let n = &c.name;
        let id = format!("cmd-{}-before-hi", slug(n));
        let code = if c.kind == CommandKind::Terminate {
            self.code(self.p.hand.terminate_uninitialized_status)
        } else {
            self.code(self.p.hand.uninitialized_status)
        };
        let mut k = self
            .case(id, format!("{n} before HI gives {code} and moves nothing"))
            .src(&format!("Command {n}"))
            .src("Command HI");
        k = match c.kind {
            CommandKind::Terminate => {
                k.decision("seed-terminate-uninitialized").decision("bh8-terminate-uninitialized")
            }
            CommandKind::Loop => k
                .decision("seed-motion-before-hi")
                .decision("seed-param-prefix-en")
                .decision("bh8-loop-failure")
                .decision("bh8-motion-before-hi")
                .decision("bh8-loop-motors"),
            _ => k.decision("seed-motion-before-hi").decision("bh8-motion-before-hi"),
        };
        k = k.preamble(false).line(n);
        self.add(k);
    }

    fn command_overtemp(&mut self, c: &CommandSpec) {
        let n = &c.name;
        let code = self.code(self.p.hand.overtemp_status);
        let k = self
            .case(
                format!("cmd-{}-overtemp", slug(n)),
                format!("{n} over temperature (OTEMP below TEMP) gives {code} and moves nothing"),
            )
            .src(&format!("Command {n}"))
            .src("Parameter OTEMP")
            .decision("bh8-otemp-units")
            .preamble(true)
            .line("PSET OTEMP 1")
            .line(n)
            .get("", &["P"], Some(self.near([0; 4])))
            .line("T")
            .line("PSET OTEMP 0");
        self.add(k);
    }

    fn command_run(&mut self, c: &CommandSpec) {
        let n = c.name.clone();
        let id = format!("cmd-{}", slug(&n));
        let k = self.case(id, format!("{n} does its job")).src(&format!("Command {n}"));
        let k = match c.kind {
            kind if kind.is_motion() => {
                let (setup, goals) = self.motion_recipe(kind, "");
                let mut k = k.preamble(true);
                if matches!(kind, CommandKind::Close | CommandKind::Open) {
                    k = k.decision("seed-close-open-targets");
                }
                if kind == CommandKind::TorqueClose {
                    k = k.decision("bh8-position-bounds");
                }
                for s in setup {
                    k = k.line(&s);
                }
                k.line(&n).get("", &["P"], Some(goals))
            }
            CommandKind::Initialize => {
                let k = k.preamble(false).requires(Requirement::Motion).line(&n).within(Duration::from_secs(30));
                k.get("", &["S", "P"], Some(self.near([0; 4])))
            }
            CommandKind::Terminate => k.preamble(true).line(&n).get("", &["S"], None),
            CommandKind::Loop => k
                .decision("seed-param-prefix-en")
                .decision("bh8-loop-motors")
                .preamble(true)
                .requires(Requirement::Realtime)
                .line(&n)
                .abort()
                .line("FGET DP"),
            CommandKind::MotorSet | CommandKind::GlobalSet => {
                let params: Vec<ParamSpec> =
                    self.writable_for(&n).into_iter().filter(|x| x.name != "BAUD").take(2).collect();
                if params.is_empty() {
                    return;
                }
                let pairs: Vec<String> =
                    params.iter().map(|x| format!("{} {}", x.name, other_value(x, self.default(&x.name, 1)))).collect();
                let names: Vec<&str> = params.iter().map(|x| x.name.as_str()).collect();
                let getter = if c.kind == CommandKind::MotorSet { "FGET" } else { "PGET" };
                let k = k.decision("seed-fget-format").decision("bh8-fget-format");
                k.level(Level::Must)
                    .preamble(false)
                    .line(&format!("{n} {}", pairs.join(" ")))
                    .line(&format!("{getter} {}", names.join(" ")))
            }
            CommandKind::MotorGet | CommandKind::GlobalGet => {
                let readable: Vec<&ParamSpec> = self
                    .p
                    .params
                    .iter()
                    .filter(|x| self.p.param_id(&x.name).is_some_and(|id| self.p.getter(id) == n))
                    .collect();
                let mut names: Vec<String> =
                    readable.iter().filter(|x| !x.live).take(3).map(|x| x.name.clone()).collect();
                if names.is_empty() {
                    names = readable.iter().take(1).map(|x| x.name.clone()).collect();
                }
                if names.is_empty() {
                    return;
                }
                let refs: Vec<&str> = names.iter().map(String::as_str).collect();
                let k = k.decision("seed-fget-format").decision("bh8-fget-format");
                k.level(Level::Must).preamble(false).get("", &refs, None)
            }
            CommandKind::MotorList
            | CommandKind::MotorListAll
            | CommandKind::GlobalList
            | CommandKind::GlobalListAll => {
                let k = k.decision("seed-flista").decision("bh8-list-names-format");
                self.listing_order(k, c.kind).preamble(false).line(&n)
            }
            CommandKind::MotorListValues
            | CommandKind::MotorListAllValues
            | CommandKind::GlobalListValues
            | CommandKind::GlobalListAllValues => {
                let k = k.decision("seed-flista").decision("bh8-list-values-format");
                self.listing_order(k, c.kind).preamble(false).line_shaped(&n, Shape::ListValues)
            }
            CommandKind::Reset => {
                let k = k.decision("seed-reset-output").decision("bh8-reset").decision("bh8-banner-text");
                k.decision("seed-motion-before-hi")
                    .decision("bh8-motion-before-hi")
                    .preamble(true)
                    .line_shaped(&n, Shape::Banner)
                    .line("C")
            }
            CommandKind::ErrorText => {
                let k = k.decision("seed-err-command").decision("bh8-err-format");
                k.preamble(false).line(&format!("{n} 3")).line(&format!("{n} 4160")).line(&n)
            }
            CommandKind::Version => {
                // What VERS says is checked where the profile decides it; elsewhere it is INFO.
                let k =
                    if self.has_decision("bh8-vers-text") { k.decision("bh8-vers-text") } else { k.level(Level::Info) };
                k.preamble(false).line_shaped(&n, Shape::AnyLines)
            }
            CommandKind::Help => {
                let k = k.decision("seed-help").decision("bh8-help-format");
                k.preamble(false).line(&n).line(&format!("{n}HI")).line(&format!("{n}BOGUS")).line(&format!("{n} HI"))
            }
            CommandKind::HelpAll => k.decision("bh8-help-format").preamble(false).line(&n),
            // Persistence commands have their own cases.
            _ => return,
        };
        self.add(k);
    }

    /// A listing prints its parameters in the profile's listing order; the order of the
    /// parameters new in firmware 4.4x concerns the motor listings only.
    fn listing_order(&self, k: CaseB, kind: CommandKind) -> CaseB {
        let k = k.decision("bh8-listing-order");
        match kind {
            CommandKind::MotorList
            | CommandKind::MotorListAll
            | CommandKind::MotorListValues
            | CommandKind::MotorListAllValues => k.decision("bh8-44-listing-order"),
            _ => k,
        }
    }

    // ------------------------------------------------------------------ parameters

    fn params(&mut self) {
        let params = self.p.params.clone();
        for x in &params {
            self.param_default(x);
            if !x.read_only && !x.live {
                self.param_set(x);
                self.param_range(x);
            }
            if x.read_only {
                self.param_read_only(x);
            }
        }
        for (cmd, line) in
            [("FGET", "FGET NOPE"), ("FSET", "FSET NOPE 1"), ("PGET", "PGET NOPE"), ("PSET", "PSET NOPE 1")]
        {
            if self.has_cmd(cmd) {
                let k = self
                    .case(format!("param-unknown-name-{}", slug(cmd)), format!("{cmd} of an unknown name gives 64"))
                    .src(&format!("Command {cmd}"))
                    .src("Status codes 64")
                    .level(Level::Must)
                    .preamble(false)
                    .line(line)
                    .line("FGET DP");
                self.add(k);
            }
        }
        if self.p.decisions.iter().any(|d| d.id == "bh8-global-names-on-fset") {
            let k = self
                .case(
                    "param-scope-commands",
                    "FSET and FGET know only motor parameters, PSET and PGET only global ones (64)",
                )
                .decision("bh8-global-names-on-fset")
                .preamble(false)
                .line("FGET BAUD")
                .line("FSET BAUD 96")
                .line("PGET DP")
                .line("PSET DP 1000");
            self.add(k);
        }
        if self.p.decisions.iter().any(|d| d.id == "seed-temp-global") {
            let k = self
                .case("param-temp-global", "TEMP is read only through PGET; FGET TEMP and FSET TEMP give 64")
                .decision("seed-temp-global")
                .preamble(false)
                .get("", &["TEMP"], None)
                .line("FGET TEMP")
                .line("FSET TEMP 5");
            self.add(k);
        }
        if self.has_cmd("PGET") {
            let id =
                if self.p.decisions.iter().any(|d| d.id == "seed-pget-tmp") { "seed-pget-tmp" } else { "bh8-no-tmp" };
            let mut k = self
                .case("param-tmp-alias", "Whether PGET accepts the seed's name TMP for TEMP")
                .decision(id)
                .preamble(false);
            k = match self.param("TEMP") {
                Some(t) if t.input_aliases.iter().any(|a| a == "TMP") => {
                    let r = (t.min, t.max);
                    k.line_shaped("PGET TMP", Shape::Values(vec![vec![Some(r)]]))
                }
                _ => k.line("PGET TMP"),
            };
            self.add(k);
        }
        if self.has_param("HSG") && self.param("MSG").is_some_and(|m| m.alias_of.is_some()) {
            let k = self
                .case("param-msg-hsg-alias", "MSG and HSG name one value per motor")
                .decision("bh8-msg-alias")
                .preamble(false)
                .line("2FSET MSG 100")
                .line("FGET HSG MSG")
                .line("3FSET HSG 200")
                .line("FGET MSG HSG");
            self.add(k);
        }
        let k = self
            .case("param-en-narrows-motion", "EN narrows motion commands without a prefix, never parameter commands")
            .src("Parameter EN")
            .decision("seed-param-prefix-en")
            .decision("bh8-param-prefix-en")
            .preamble(true)
            .line("SFSET EN 0")
            .line("FGET EN DP")
            .line("M 3000")
            .get("", &["P"], Some(self.near([3000, 3000, 3000, 0])));
        self.add(k);

        if self.p.decisions.iter().any(|d| d.id == "bh8-spread-defaults") {
            let k = self
                .case(
                    "param-spread-finger-defaults",
                    "Where the manual gives the spread no default (BDAT, BS), the spread starts at the finger default and can be set",
                )
                .src("Parameter BDAT")
                .src("Parameter BS")
                .decision("bh8-spread-defaults")
                .preamble(false)
                .get("", &["BDAT", "BS"], None)
                .line("SFSET BDAT 1000 BS 1")
                .get("", &["BDAT", "BS"], None)
                .line("SFDEF")
                .get("S", &["BDAT", "BS"], None);
            self.add(k);
        }

        if self.p.decisions.iter().any(|d| d.id == "bh8-new-rt-fields-defaults") {
            let new = ["LCT", "LFBP", "LFAIN"];
            let known = new.iter().all(|n| self.has_param(n));
            let title = if known {
                "Firmware 4.4x knows LCT, LFBP and LFAIN; each defaults to 0 on every motor"
            } else {
                "Firmware 4.3x does not know LCT, LFBP or LFAIN: FGET and FSET of them give 64"
            };
            let k = self
                .case("param-44-rt-flags", title)
                .src("Command FGET")
                .src("Command FSET")
                .decision("bh8-new-rt-fields-defaults")
                .decision("bh8-43-no-44-params")
                .preamble(false)
                .get("", &new, None)
                .line("FSET LCT 0 LFBP 0 LFAIN 0")
                .get("", &["LCT"], None)
                .get("", &["LFBP"], None)
                .get("", &["LFAIN"], None)
                .line("FGET DP");
            self.add(k);
        }
    }

    /// The source clause of a parameter case, and the decisions that govern it: those about
    /// defaults only for the default case.
    fn param_level(&self, mut k: CaseB, x: &ParamSpec, default_case: bool) -> CaseB {
        k = k.src(&format!("Parameter {}", x.name));
        match (x.name.as_str(), default_case) {
            ("S", _) => k.decision("seed-s-values").decision("bh8-s-before-hi"),
            ("BAUD", _) => k.decision("seed-baud"),
            ("SGFLIP", true) => k.decision("seed-sgflip-spread").decision("bh8-sgflip-default"),
            ("MSG" | "HSG", _) => k.decision("bh8-msg-alias"),
            ("LCT" | "LFBP" | "LFAIN", _) => k.decision("bh8-new-rt-fields-defaults"),
            ("OD" | "UPSECS" | "PTEMP" | "SN", _) => k.decision("bh8-self-stored"),
            ("BP", _) => k.decision("bh8-bp-range"),
            _ => k,
        }
    }

    fn param_default(&mut self, x: &ParamSpec) {
        let what = if x.live { "reads" } else { "reads its factory default" };
        let k = self.case(format!("param-{}-default", slug(&x.name)), format!("{} {what}", x.name));
        let k = self.param_level(k, x, true).preamble(false).get("", &[&x.name], None);
        self.add(k);
    }

    fn param_set(&mut self, x: &ParamSpec) {
        let id = self.p.param_id(&x.name);
        let Some(id) = id else { return };
        let setter = self.p.setter(id).to_string();
        let prefix = if x.scope == Scope::Motor { "2" } else { "" };
        let values: Vec<i64> = match &x.values {
            Some(_) => vec![self.default(&x.name, 1)],
            None => vec![x.min, x.max],
        };
        let k = self.case(
            format!("param-{}-set", slug(&x.name)),
            format!("{} takes values in its range and reads them back", x.name),
        );
        let mut k = self.param_level(k, x, false).src(&format!("Command {setter}")).preamble(false);
        if values.contains(&0) && matches!(x.name.as_str(), "LCVC" | "LFVC" | "LFDPC") {
            k = k.decision("bh8-coefficient-range");
        }
        for v in values {
            k = k.line(&format!("{prefix}{setter} {} {v}", x.name)).get("", &[&x.name], None);
        }
        self.add(k);
    }

    fn param_range(&mut self, x: &ParamSpec) {
        let Some(id) = self.p.param_id(&x.name) else { return };
        let setter = self.p.setter(id).to_string();
        let mut bad: Vec<i64> = match &x.values {
            Some(vs) => (x.min..=x.max + 1).filter(|v| !vs.contains(v)).take(1).chain([x.max + 1]).collect(),
            None => vec![x.max + 1, x.min - 1],
        };
        bad.dedup();
        let k = self.case(
            format!("param-{}-range", slug(&x.name)),
            format!("{} out of range gives 128 and changes nothing", x.name),
        );
        let mut k = self.param_level(k, x, false).src("Status codes 128").preamble(false);
        if x.min == 0 && x.max == 1 && self.has_decision("seed-booleans") {
            k = k.decision("seed-booleans").level(Level::Must);
        }
        for v in bad {
            k = k.line(&format!("{setter} {} {v}", x.name));
        }
        k = k.get("", &[&x.name], None);
        self.add(k);
    }

    fn param_read_only(&mut self, x: &ParamSpec) {
        let Some(id) = self.p.param_id(&x.name) else { return };
        let getter = self.p.getter(id);
        let setter = match getter {
            "PGET" if self.has_cmd("PSET") => "PSET",
            _ => "FSET",
        };
        let writable_through = (getter == "FGET" && setter == "FSET") || (getter == "PGET" && setter == "PSET");
        let code = if writable_through { 256 } else { 64 };
        let k = self.case(
            format!("param-{}-read-only", slug(&x.name)),
            if code == 256 {
                format!("{setter} {} gives 256: it is read-only", x.name)
            } else {
                format!("{setter} {} gives 64: {} is read-only and only {getter} knows it", x.name, x.name)
            },
        );
        let mut k = self.param_level(k, x, false).src(&format!("Status codes {code}"));
        if !writable_through {
            k = k.decision("seed-temp-global");
        }
        let k = k.preamble(false).line(&format!("{setter} {} 0", x.name)).get("", &[&x.name], None);
        self.add(k);
    }

    // ------------------------------------------------------------------ status bits

    fn status(&mut self) {
        let h = self.p.hand.clone();
        let t1 = self.code(h.terminate_uninitialized_status);
        let mut k =
            self.case(format!("status-{t1}-terminate-before-hi"), format!("T before HI gives {t1}")).src("Command T");
        k = k.decision("seed-terminate-uninitialized").decision("bh8-terminate-uninitialized");
        let k = k.preamble(false).line("T").line("HI").requires(Requirement::Motion).line("T");
        self.add(k);

        let u = self.code(h.uninitialized_status);
        let k = self
            .case(format!("status-{u}-not-initialized"), format!("A motion command before HI gives {u}"))
            .src(&format!("Status codes {u}"))
            .decision("seed-motion-before-hi")
            .decision("bh8-motion-before-hi")
            .preamble(false)
            .line("M 1000")
            .line("1C");
        self.add(k);

        let simple: [(u32, &str, &[&str]); 6] = [
            (32, "unknown-command", &["BOGUS", "1BOGUS", "FGETX DP"]),
            (64, "unknown-parameter", &["FGET NOPE", "FSET NOPE 5"]),
            (128, "invalid-value", &["FSET DP 99999999", "FSET DP -1"]),
            (256, "read-only", &["FSET P 5", "FSET S 0"]),
            (1024, "too-many-arguments", &["FDEF 1", "ERR 1 2", "RESET 1"]),
            (4096, "prefix-not-allowed", &["1RESET", "GRESET"]),
        ];
        for (code, name, lines) in simple {
            let mut k = self
                .case(
                    format!("status-{code}-{name}"),
                    format!("ERR {code}: {}", self.p.status_text(code).unwrap_or(name)),
                )
                .src(&format!("Status codes {code}"))
                .level(Level::Must)
                .preamble(false);
            for l in lines {
                k = k.line(l);
            }
            self.add(k.line("FGET DP"));
        }

        // A status the profile defines but never sends: only ERR shows it.
        for s in self.p.status.clone().iter().filter(|s| !s.sent) {
            let id = format!("seed-status-{}", s.bit);
            if !self.p.decisions.iter().any(|d| d.id == id) {
                continue;
            }
            let k = self
                .case(
                    format!("status-{}-text-only", s.bit),
                    format!("ERR {} prints `{}: {}`; no command ever sends {}", s.bit, s.bit, s.text, s.bit),
                )
                .src(&format!("Status codes {}", s.bit))
                .src("Command ERR")
                .decision(&id)
                .decision("seed-err-command")
                .preamble(false)
                .line(&format!("ERR {}", s.bit))
                .line("FGET DP");
            self.add(k);
        }

        let combos: [(&str, &[&str]); 4] = [
            ("prefix-and-arguments", &["1VERS 3", "1RESET 5"]),
            ("unknown-and-invalid", &["FSET NOPE 1 DP 99999"]),
            ("unknown-and-read-only", &["FSET NOPE 1 P 0"]),
            ("invalid-and-read-only", &["FSET DP 99999 P 0"]),
        ];
        for (name, lines) in combos {
            let mut k = self
                .case(
                    format!("status-combined-{name}"),
                    format!("Several problems in one line OR their bits: {}", lines.join(", ")),
                )
                .src("Status codes")
                .decision("framing-errors-combine")
                .preamble(false);
            for l in lines {
                k = k.line(l);
            }
            self.add(k.line("FGET DP"));
        }

        // A grammar problem and a condition found only when running meet on one line.
        let u = self.code(h.uninitialized_status);
        let k = self
            .case(
                "status-combined-grammar-and-not-initialized",
                format!("A refused line never runs: before HI, C 1 gives only 1024 and M 99999 only 128, not {u}"),
            )
            .src("Status codes")
            .decision("framing-parse-before-run")
            .preamble(false)
            .line("C 1")
            .line("M 99999")
            .line("1FGET DP");
        self.add(k);

        let mp = self.code(h.missed_position_status);
        let l4 = self.limit(4);
        let k = self
            .case(format!("status-{mp}-missed-position"), format!("M past the spread's joint stop gives {mp}"))
            .src(&format!("Status codes {mp}"))
            .src("Command M")
            .decision("bh8-missed-position-code")
            .decision("seed-motion-model")
            .decision("bh8-position-bounds")
            .preamble(true)
            .line(&format!("SM {}", l4 + 850))
            .get("", &["P"], Some([(0, self.mpe(1)), (0, self.mpe(2)), (0, self.mpe(3)), (l4 - self.mpe(4), l4)]));
        self.add(k);

        let bh = self.code(h.bad_header_status);
        let k = self
            .case(
                format!("status-{bh}-bad-header"),
                format!("An invalid RealTime header gives {bh} and ends RealTime mode"),
            )
            .src(&format!("Status codes {bh}"))
            .src("RealTime Control")
            .level(Level::Must)
            .requires(Requirement::Realtime)
            .preamble(true)
            .line("1LOOP")
            .block(b"Z", Shape::Exact)
            .line("FGET DP");
        self.add(k);

        if h.overtemp_status != 0 && self.has_param("OTEMP") {
            let ot = self.code(h.overtemp_status);
            let k = self
                .case(format!("status-{ot}-overtemperature"), format!("A motion command over temperature gives {ot}"))
                .src(&format!("Status codes {ot}"))
                .decision("bh8-otemp-units")
                .preamble(true)
                .line("PSET OTEMP 1")
                .line("GM 3000")
                .line("FSET DP 3000")
                .line("PSET OTEMP 0")
                .line("GM 3000")
                .get("", &["P"], Some(self.near([3000, 3000, 3000, 0])));
            self.add(k);
        }
        if h.abort_status != 0 {
            let ab = self.code(h.abort_status);
            let k = self
                .case(format!("status-{ab}-abort"), format!("^C during motion gives {ab}"))
                .src(&format!("Status codes {ab}"))
                .decision("bh8-abort-motion")
                .requires(Requirement::AbortTiming)
                .preamble(true)
                .nowait("GC")
                .pause_ms(200)
                .abort()
                .get(
                    "",
                    &["P"],
                    Some([
                        (0, self.close_target(1)),
                        (0, self.close_target(2)),
                        (0, self.close_target(3)),
                        (0, self.mpe(4)),
                    ]),
                );
            self.add(k);
        }
    }

    // ------------------------------------------------------------------ persistence

    fn persistence(&mut self) {
        let k = self
            .case("persist-fdef", "FDEF restores the factory values in RAM")
            .src("Command FDEF")
            .level(Level::Must)
            .preamble(false)
            .line("FSET DP 1234 MCV 77")
            .line("FDEF")
            .line("FGET DP MCV");
        self.add(k);

        let k = self
            .case("persist-fdef-ram-only", "FDEF changes RAM only: the saved values come back at RESET")
            .src("Command FDEF")
            .decision("seed-saved-set")
            .decision("bh8-saved-sets")
            .level(Level::Must)
            .requires(Requirement::Eeprom)
            .preamble(false)
            .line("FSET DP 1234")
            .line("FSAVE")
            .line("FDEF")
            .line("1FGET DP")
            .line_shaped("RESET", Shape::Banner)
            .line("1FGET DP");
        self.add(k);

        let k = self
            .case(
                "persist-fsave-reset",
                "FSAVE keeps values across RESET; FDEF and FSAVE bring the factory values back",
            )
            .src("Command FSAVE")
            .src("Command RESET")
            .level(Level::Must)
            .requires(Requirement::Eeprom)
            .preamble(false)
            .line("FSET DP 1234")
            .line("FSAVE")
            .line_shaped("RESET", Shape::Banner)
            .line("FGET DP")
            .comment("restore the factory values in the EEPROM")
            .line("FDEF")
            .line("FSAVE")
            .line_shaped("RESET", Shape::Banner)
            .line("FGET DP");
        self.add(k);

        let k = self
            .case("persist-fload", "FLOAD brings back the saved values")
            .src("Command FLOAD")
            .level(Level::Must)
            .requires(Requirement::Eeprom)
            .preamble(false)
            .line("FSAVE")
            .line("FSET DP 1234")
            .line("FLOAD")
            .line("FGET DP");
        self.add(k);

        let k = self
            .case("persist-reset-discards-ram", "RESET forgets values that were not saved")
            .src("Command RESET")
            .decision("seed-reset-output")
            .decision("bh8-reset")
            .requires(Requirement::Eeprom)
            .preamble(false)
            .line("FSAVE")
            .line("FSET DP 1234")
            .line_shaped("RESET", Shape::Banner)
            .line("FGET DP");
        self.add(k);

        // The whole saved set: every parameter FSAVE covers survives RESET.
        let saved: Vec<ParamSpec> = self
            .p
            .params
            .iter()
            .filter(|x| x.persist.iter().any(|c| c == "FSAVE") && x.alias_of.is_none())
            .cloned()
            .collect();
        if !saved.is_empty() {
            let pairs: Vec<String> =
                saved.iter().map(|x| format!("{} {}", x.name, other_value(x, self.default(&x.name, 1)))).collect();
            let names: Vec<String> = saved.iter().map(|x| x.name.clone()).collect();
            let mut k = self
                .case("persist-saved-set", "Every parameter of the saved set survives FSAVE and RESET")
                .src("Command FSAVE")
                .decision("seed-saved-set")
                .decision("bh8-saved-sets")
                .requires(Requirement::Eeprom)
                .preamble(false);
            for l in chunk_lines("FSET", &pairs, safe_line(&self.p)) {
                k = k.line(&l);
            }
            k = k.line("FSAVE").line_shaped("RESET", Shape::Banner);
            for l in chunk_lines("FGET", &names, safe_line(&self.p)) {
                k = k.line(&l);
            }
            self.add(k);
        }

        if self.has_cmd("PSAVE") && self.has_param("OTEMP") {
            let k = self
                .case("persist-pdef", "PDEF restores the factory global values in RAM")
                .src("Command PDEF")
                .level(Level::Must)
                .preamble(false)
                .line("PSET OTEMP 700")
                .line("PDEF")
                .line("PGET OTEMP");
            self.add(k);
            let k = self
                .case(
                    "persist-psave-reset",
                    "PSAVE keeps global values across RESET; PDEF and PSAVE bring the factory values back",
                )
                .src("Command PSAVE")
                .decision("bh8-saved-sets")
                .requires(Requirement::Eeprom)
                .preamble(false)
                .line("PSET OTEMP 700")
                .line("PSAVE")
                .line_shaped("RESET", Shape::Banner)
                .line("PGET OTEMP")
                .comment("restore the factory values in the EEPROM")
                .line("PDEF")
                .line("PSAVE")
                .line_shaped("RESET", Shape::Banner)
                .line("PGET OTEMP");
            self.add(k);
            let k = self
                .case("persist-pload", "PLOAD brings back the saved global values")
                .src("Command PLOAD")
                .level(Level::Must)
                .requires(Requirement::Eeprom)
                .preamble(false)
                .line("PSAVE")
                .line("PSET OTEMP 700")
                .line("PLOAD")
                .line("PGET OTEMP");
            self.add(k);
        }
    }

    // ------------------------------------------------------------------ ^C

    fn abort(&mut self) {
        let k = self
            .case("abort-idle", "^C while idle prints a fresh prompt and no status")
            .decision("framing-abort-idle")
            .preamble(false)
            .abort()
            .abort()
            .line("FGET DP");
        self.add(k);

        let goals = [(0, self.close_target(1)), (0, self.close_target(2)), (0, self.close_target(3)), (0, self.mpe(4))];
        let k = self
            .case("abort-motion", "^C during motion stops every motor and answers at once")
            .src("Command ^C")
            .decision("seed-abort")
            .decision("bh8-abort-motion")
            .requires(Requirement::AbortTiming)
            .preamble(true)
            .nowait("GC")
            .pause_ms(200)
            .abort()
            .get("", &["P"], Some(goals))
            .line("FGET DP");
        self.add(k);

        let k = self
            .case("abort-motion-discards-queue", "^C during motion also discards the lines queued behind the command")
            .src("Command ^C")
            .decision("framing-busy-input")
            .decision("seed-abort")
            .decision("bh8-abort-motion")
            .requires(Requirement::AbortTiming)
            .preamble(true)
            .nowait("GC\rFGET DP")
            .pause_ms(200)
            .abort()
            .line("FGET DS");
        self.add(k);

        let k = self
            .case("abort-loop", "^C in place of a RealTime header ends the loop and prints the prompt")
            .src("RealTime Control")
            .decision("seed-abort")
            .decision("bh8-abort-loop")
            .requires(Requirement::Realtime)
            .preamble(true)
            .line("1LOOP")
            .abort()
            .line("FGET DP");
        self.add(k);
    }

    // ------------------------------------------------------------------ motion

    fn motion(&mut self) {
        let k = self
            .case("motion-goal-within-mpe", "M ends within MPE of its goal and gives no status")
            .src("Command M")
            .src("Parameter MPE")
            .level(Level::Must)
            .preamble(true)
            .line("GM 5000")
            .get("", &["P"], Some(self.near([5000, 5000, 5000, 0])))
            .line("SM 1000")
            .get("", &["P"], Some(self.near([5000, 5000, 5000, 1000])));
        self.add(k);

        let msg = if self.has_param("HSG") { "HSG" } else { "MSG" };
        let k = self
            .case("motion-strain-limit", format!("With {msg} 0 a move stops at once; M then misses its goal (16)"))
            .src(&format!("Parameter {msg}"))
            .decision("seed-motion-model")
            .decision("bh8-strain-limits-disable")
            .preamble(true)
            .line(&format!("GFSET {msg} 0"))
            .line("GM 5000")
            .get("", &["P"], Some([(0, self.mpe(1)), (0, self.mpe(2)), (0, self.mpe(3)), (0, self.mpe(4))]));
        self.add(k);

        if self.has_param("CT") {
            let l4 = self.limit(4);
            let k = self
                .case(
                    "motion-close-stall-no-status",
                    "C to a target past the joint stop stalls after TSTOP and gives no status",
                )
                .src("Command C")
                .src("Parameter TSTOP")
                .decision("bh8-missed-position-code")
                .preamble(true)
                .line(&format!("SFSET CT {}", l4 + 850))
                .line("SC")
                .get("", &["P"], Some([(0, self.mpe(1)), (0, self.mpe(2)), (0, self.mpe(3)), (l4 - self.mpe(4), l4)]));
            self.add(k);
        }

        // A stall at the spread's joint stop leaves an error of exactly the overshoot: equal
        // to MPE is success, one count more is a missed position.
        let (l4, mpe4) = (self.limit(4), self.mpe(4));
        let mp = self.code(self.p.hand.missed_position_status);
        let rest = [(0, self.mpe(1)), (0, self.mpe(2)), (0, self.mpe(3)), (l4 - mpe4, l4)];
        let k = self
            .case(
                "motion-mpe-boundary",
                format!("A move whose final error equals MPE succeeds; one count more gives {mp}"),
            )
            .src("Command M")
            .src("Parameter MPE")
            .decision("seed-motion-model")
            .decision("bh8-mpe-boundary")
            .decision("bh8-position-bounds")
            .note(format!(
                "The spread stalls at its joint stop ({l4}): SM {} leaves an error of MPE ({mpe4}), SM {} one more.",
                l4 + mpe4,
                l4 + mpe4 + 1
            ))
            .preamble(true)
            .line(&format!("SM {}", l4 + mpe4))
            .get("", &["P"], Some(rest))
            .line(&format!("SM {}", l4 + mpe4 + 1))
            .get("", &["P"], Some(rest));
        self.add(k);

        // HI drives each motor open at its init velocity (IVEL, else MOV); where that can be 0,
        // a motor away from its open stop cannot reach it and HI fails for it.
        let hi_stall =
            ["seed-hi-stall", "bh8-hi-stall"].into_iter().find(|d| self.p.decisions.iter().any(|x| x.id == *d));
        let init = if self.has_param("IVEL") { "IVEL" } else { "MOV" };
        if let (Some(d), Some(x)) = (hi_stall, self.param(init))
            && x.min == 0
        {
            let s_bad = self.p.hand.uninitialized_state_value;
            let u = self.code(self.p.hand.uninitialized_status);
            let k = self
                .case(
                    "motion-hi-stall",
                    format!(
                        "A motor HI cannot open ({init} 0) stays uninitialised: S reads {s_bad}, motion on it gives {u}"
                    ),
                )
                .src("Command HI")
                .src(&format!("Parameter {init}"))
                .decision(d)
                .decision("seed-motion-before-hi")
                .decision("bh8-motion-before-hi")
                .decision("seed-s-values")
                .decision("bh8-s-before-hi")
                .preamble(true)
                .line("1M 3000")
                .line(&format!("1FSET {init} 0"))
                .line("HI")
                .get("", &["S"], None)
                .line("1M 1000")
                .line("M 1000")
                .get("", &["P"], Some(self.near([3000, 0, 0, 0])));
            self.add(k);
        }
    }

    // ------------------------------------------------------------------ parameter effects

    /// For parameters whose value changes what the hand does: a case that sets one to a value
    /// other than its default and shows the difference on the wire.
    fn effects(&mut self) {
        let dp = 3000;
        let k = self
            .case("param-dp-effect", format!("M without an argument goes to DP: 1FSET DP {dp}, 1M"))
            .src("Parameter DP")
            .src("Command M")
            .level(Level::Must)
            .preamble(true)
            .line(&format!("1FSET DP {dp}"))
            .line("1M")
            .get("1", &["P"], Some(self.near([dp; 4])));
        self.add(k);

        let (up, down) = (2500, 1000);
        let k = self
            .case(
                "param-ds-effect",
                format!(
                    "IC and IO without an argument step by DS: DS {up} closes to {up}, DS {down} opens back to {}",
                    up - down
                ),
            )
            .src("Parameter DS")
            .src("Command IC")
            .src("Command IO")
            .level(Level::Must)
            .preamble(true)
            .line(&format!("1FSET DS {up}"))
            .line("1IC")
            .get("1", &["P"], Some(self.near([up; 4])))
            .line(&format!("1FSET DS {down}"))
            .line("1IO")
            .get("1", &["P"], Some(self.near([up - down; 4])));
        self.add(k);

        if self.has_param("CT") {
            let ct = 5000;
            let k = self
                .case("param-ct-effect", format!("C closes to CT: 1FSET CT {ct}, 1C"))
                .src("Parameter CT")
                .src("Command C")
                .level(Level::Must)
                .preamble(true)
                .line(&format!("1FSET CT {ct}"))
                .line("1C")
                .get("1", &["P"], Some(self.near([ct; 4])));
            self.add(k);
        }
        if self.has_param("OT") {
            let ot = 1000;
            let k = self
                .case("param-ot-effect", format!("O opens to OT: 1FSET OT {ot}, 1O from 3000"))
                .src("Parameter OT")
                .src("Command O")
                .level(Level::Must)
                .preamble(true)
                .line("1M 3000")
                .line(&format!("1FSET OT {ot}"))
                .line("1O")
                .get("1", &["P"], Some(self.near([ot; 4])));
            self.add(k);
        }

        // MPE: the spread stalls at its joint stop 850 counts short of the goal; with MPE
        // 1000 that is no error.
        let l4 = self.limit(4);
        let mpe = 1000;
        let k = self
            .case(
                "param-mpe-effect",
                format!("With MPE {mpe} a move that ends 850 counts short of its goal gives no status"),
            )
            .src("Parameter MPE")
            .src("Command M")
            .decision("seed-motion-model")
            .decision("bh8-position-bounds")
            .preamble(true)
            .line(&format!("SFSET MPE {mpe}"))
            .line(&format!("SM {}", l4 + 850))
            .get("S", &["P"], Some([(l4 - mpe, l4); 4]));
        self.add(k);

        if self.has_param("LSG") {
            let k = self
                .case(
                    "param-lsg-effect",
                    "With LSG 100 a move stops at once (a free finger's strain is lower); M then gives 16",
                )
                .src("Parameter LSG")
                .decision("bh8-strain-limits-disable")
                .decision("bh8-missed-position-code")
                .preamble(true)
                .line("1FSET LSG 100")
                .line("1M 5000")
                .get("1", &["P"], Some([(0, self.mpe(1)); 4]));
            self.add(k);
        }

        // SGFLIP turns FGET SG over.
        let f = self.p.hand.free_strain;
        let (plain, flipped) = ((0, (2 * f).min(255)), ((255 - 2 * f).max(0), 255));
        let k = self
            .case("param-sgflip-effect", "With SGFLIP 1 FGET SG reads 255 minus the strain")
            .src("Parameter SGFLIP")
            .src("Parameter SG")
            .decision("seed-strain-at-rest")
            .decision("bh8-strain-at-rest")
            .note(format!(
                "A free finger's strain is near {f}: with SGFLIP 0 it reads {}..{}, with SGFLIP 1 {}..{}.",
                plain.0, plain.1, flipped.0, flipped.1
            ))
            .preamble(false)
            .line("2FSET SGFLIP 1")
            .line_shaped("12FGET SG", Shape::Values(vec![vec![Some(plain), Some(flipped)]]));
        self.add(k);

        self.timed_effects();
    }

    /// Where a motor is `ticks` ms after a position move from `from` to `target` starts, with
    /// ACCEL `accel` and maximum velocity `speed` (MCV or MOV), by the model's trapezoid.
    fn reach(&self, from: i64, target: i64, accel: i64, speed: i64, ticks: u64) -> i64 {
        let h = &self.p.hand;
        let a = accel.max(1) as f64 * h.velocity_units_per_ms_per_accel * h.counts_per_ms_per_velocity_unit;
        let vmax = speed as f64 * h.counts_per_ms_per_velocity_unit;
        let (mut pos, mut v) = (from as f64, 0.0f64);
        let t = target as f64;
        for _ in 0..ticks {
            let d = t - pos;
            if d.abs() < 0.5 {
                break;
            }
            let want = vmax.min((2.0 * a * d.abs()).sqrt()).min(v + a).max(0.0);
            let next = pos + d.signum() * want;
            pos = if (t - pos) * (t - next) <= 0.0 { t } else { next };
            v = want;
        }
        pos.round() as i64
    }

    /// Parameters whose effect is how fast a motor moves or how long it waits: seen through
    /// where a motor is when a ^C lands, or whether its command is still running then. These
    /// need a hand whose motion takes time (`abort-timing`).
    fn timed_effects(&mut self) {
        // The ^C lands between `pause` and `pause + slack` ms after the command: the host's
        // pause, plus the echo and the recorder's quiet time.
        let slack = 150u64;
        let (ct, accel) = (self.close_target(1), self.default("ACCEL", 1));
        for (name, kind) in [("MCV", CommandKind::Close), ("MOV", CommandKind::Open)] {
            let Some(x) = self.param(name).cloned() else { continue };
            let def = self.default(name, 1);
            let slow = (def / 6).max(x.min).max(1);
            let from = if kind == CommandKind::Close { 0 } else { 12000 };
            let to = if kind == CommandKind::Close { ct } else { 0 };
            let pause = 150u64;
            let range = |v: i64| {
                let (a, b) = (self.reach(from, to, accel, v, pause), self.reach(from, to, accel, v, pause + slack));
                (a.min(b) - 2, a.max(b) + 2)
            };
            let (r1, r2) = (range(slow), range(def));
            if r1.1 >= r2.0 && r2.1 >= r1.0 {
                continue;
            }
            let word = if kind == CommandKind::Close { "C" } else { "O" };
            let mut k = self
                .case(
                    format!("param-{}-effect", slug(name)),
                    format!("{name} sets how fast {word} moves: with {name} {slow} motor 1 is behind motor 2 ({name} {def}) when a ^C lands"),
                )
                .src(&format!("Parameter {name}"))
                .src(&format!("Command {word}"))
                .decision("seed-abort").decision("bh8-abort-motion")
                .decision("seed-motion-model").decision("bh8-velocity-units")
                .requires(Requirement::AbortTiming)
                .note(format!(
                    "The ^C lands {pause}..{} ms after the command: motor 1 is then within {}..{}, motor 2 within {}..{}.",
                    pause + slack,
                    r1.0,
                    r1.1,
                    r2.0,
                    r2.1
                ))
                .preamble(true);
            if from > 0 {
                k = k.line(&format!("12M {from}"));
            }
            let k = k.line(&format!("1FSET {name} {slow}")).nowait(&format!("12{word}")).pause_ms(pause).abort().get(
                "12",
                &["P"],
                Some([r1, r2, (0, 0), (0, 0)]),
            );
            self.add(k);
        }

        // ACCEL: where the ramp up takes long enough to see (the seed's units).
        if let Some(x) = self.param("ACCEL").cloned() {
            let fast = (accel * 100).min(x.max);
            let speed = self.param("MCV").map_or(0, |m| m.max);
            let pause = 150u64;
            let slack = 100u64;
            let range = |a: i64| {
                let (lo, hi) = (self.reach(0, ct, a, speed, pause), self.reach(0, ct, a, speed, pause + slack));
                (lo - 2, hi + 2)
            };
            let (r1, r2) = (range(fast), range(accel));
            if r1.0 > r2.1 && r1.1 < ct - self.mpe(1) {
                let k = self
                    .case(
                        "param-accel-effect",
                        format!("ACCEL sets how fast a move speeds up: with ACCEL {fast} motor 1 is ahead of motor 2 (ACCEL {accel}) when a ^C lands"),
                    )
                    .src("Parameter ACCEL")
                    .src("Command C")
                    .decision("seed-abort").decision("bh8-abort-motion")
                    .decision("seed-motion-model").decision("bh8-velocity-units")
                    .requires(Requirement::AbortTiming)
                    .note(format!(
                        "Both motors close at MCV {speed}; the ^C lands {pause}..{} ms after the command: motor 1 is then within {}..{}, motor 2 within {}..{}.",
                        pause + slack,
                        r1.0,
                        r1.1,
                        r2.0,
                        r2.1
                    ))
                    .preamble(true)
                    .line(&format!("12FSET MCV {speed}"))
                    .line(&format!("1FSET ACCEL {fast}"))
                    .nowait("12C")
                    .pause_ms(pause)
                    .abort()
                    .get("12", &["P"], Some([r1, r2, (0, 0), (0, 0)]));
                self.add(k);
            }
        }

        // TSTOP: a motor stalled at its joint stop keeps driving for TSTOP ms. With TSTOP 5000
        // the move is still running a second after the stall began, so the ^C stops it;
        // with the factory TSTOP it would long have ended with 16.
        let l4 = self.limit(4);
        let goal = l4 + 850;
        let (a4, v4) = (self.default("ACCEL", 4), self.default("MCV", 4));
        let mut t_stop = 0u64;
        while t_stop < 60_000 && self.reach(0, goal, a4, v4, t_stop) < l4 {
            t_stop += 10;
        }
        let tstop = 5000;
        let pause = t_stop + 1000;
        let k = self
            .case(
                "param-tstop-effect",
                format!("TSTOP sets how long a stalled motor keeps driving: with TSTOP {tstop} a move stalled at the joint stop is still running when a ^C lands 1 s later"),
            )
            .src("Parameter TSTOP")
            .src("Command M")
            .decision("seed-abort").decision("bh8-abort-motion")
            .decision("seed-motion-model").decision("bh8-position-bounds")
            .requires(Requirement::AbortTiming)
            .note(format!("The spread reaches its joint stop ({l4}) about {t_stop} ms after SM {goal} starts."))
            .preamble(true)
            .line(&format!("SFSET TSTOP {tstop}"))
            .nowait(&format!("SM {goal}"))
            .pause_ms(pause)
            .abort()
            .get("S", &["P"], Some([(l4 - self.mpe(4), l4); 4]));
        self.add(k);
    }

    // ------------------------------------------------------------------ RealTime

    /// FSET (and PSET) lines setting every RealTime flag: 1 for `on`, 0 for the rest.
    fn rt_flags(&self, prefix: &str, on: &[&str]) -> Vec<String> {
        let flags: Vec<&ParamSpec> = self.p.params.iter().filter(|x| x.rt.is_some()).collect();
        let motor: Vec<String> = flags
            .iter()
            .filter(|x| x.scope == Scope::Motor)
            .map(|x| format!("{} {}", x.name, i32::from(on.contains(&x.name.as_str()))))
            .collect();
        let mut lines = chunk_lines(&format!("{prefix}FSET"), &motor, safe_line(&self.p));
        for g in flags.iter().filter(|x| x.scope == Scope::Global) {
            if let Some(id) = self.p.param_id(&g.name) {
                lines.push(format!("{} {} {}", self.p.setter(id), g.name, i32::from(on.contains(&g.name.as_str()))));
            }
        }
        lines
    }

    fn rt_case(&self, id: &str, title: &str, prefix: &str, on: &[&str]) -> CaseB {
        let mut k = self.case(id, title).src("RealTime Control").requires(Requirement::Realtime).preamble(true);
        for l in self.rt_flags(prefix, on) {
            k = k.line(&l);
        }
        k
    }

    fn at_rest(&self) -> Vec<FieldRule> {
        (1..=4u8).map(|m| FieldRule { motor: Some(m), name: "LFAP", range: Some((0, self.mpe(m))) }).collect()
    }

    fn realtime(&mut self) {
        let headers: [(&str, &str, u8, &[u8]); 4] = [
            ("upper-c", "C: control data follows; the answer is a feedback block", b'C', &[0]),
            ("lower-c", "c: control data follows; the answer is * alone", b'c', &[0]),
            ("upper-a", "A: no data; the answer is a feedback block", b'A', &[]),
            ("lower-a", "a: no data; the answer is * alone", b'a', &[]),
        ];
        for (name, title, h, data) in headers {
            let mut block = vec![h];
            block.extend_from_slice(data);
            let k = self
                .rt_case(&format!("rt-header-{name}"), title, "1", &["LCV", "LFAP"])
                .level(Level::Must)
                .line("1LOOP")
                .block(&block, Shape::Block(self.at_rest()))
                .block(&block, Shape::Block(self.at_rest()))
                .abort();
            self.add(k);
        }

        let flags: Vec<ParamSpec> = self.p.params.iter().filter(|x| x.rt.is_some()).cloned().collect();
        for f in &flags {
            let Some(rt) = f.rt else { continue };
            let block = if rt.block == gcl_model::spec::BlockKind::Control { "control" } else { "feedback" };
            let bytes = if rt.size == 1 { "1 byte" } else { "2 bytes" };
            let mut k = self.rt_case(
                &format!("rt-field-{}", slug(&f.name)),
                &format!("{} alone adds {bytes} to the {block} block", f.name),
                if f.scope == Scope::Motor { "1" } else { "" },
                &[&f.name],
            );
            let cited: &[&str] = match f.name.as_str() {
                "LFT" => &["bh8-lft-field"],
                "LCT" | "LFBP" | "LFAIN" => &["bh8-44-rt-field-order", "bh8-new-rt-fields-defaults"],
                _ => &[],
            };
            k = self.cite_or_must(k, cited);
            k = k.src(&format!("Parameter {}", f.name)).line("1LOOP");
            if rt.block == gcl_model::spec::BlockKind::Control {
                let mut b = vec![b'C'];
                b.extend(std::iter::repeat_n(0u8, rt.size));
                let mut c = vec![b'c'];
                c.extend(std::iter::repeat_n(0u8, rt.size));
                k = k.block(&b, Shape::Block(self.at_rest())).block(&c, Shape::Block(self.at_rest()));
            } else {
                k = k.block(b"A", Shape::Block(self.at_rest()));
            }
            // And back: with the flag 0 the field is gone (a C block is its header alone).
            let off = match self.p.param_id(&f.name) {
                Some(id) if f.scope == Scope::Global => format!("{} {} 0", self.p.setter(id), f.name),
                _ => format!("1FSET {} 0", f.name),
            };
            k = k
                .abort()
                .comment(format!("{} 0: no field", f.name))
                .line(&off)
                .line("1LOOP")
                .block(if rt.block == gcl_model::spec::BlockKind::Control { b"C" } else { b"A" }, Shape::Exact)
                .abort();
            self.add(k);
        }

        let all: Vec<&str> = flags.iter().map(|x| x.name.as_str()).collect();
        let control_size: usize = flags
            .iter()
            .filter(|x| x.scope == Scope::Motor && x.rt.is_some_and(|r| r.block == gcl_model::spec::BlockKind::Control))
            .map(|x| x.rt.map_or(0, |r| r.size))
            .sum::<usize>()
            * 4;
        let mut block = vec![b'C'];
        block.extend(std::iter::repeat_n(0u8, control_size));
        let k = self
            .rt_case(
                "rt-all-fields",
                "Every flag on every motor: fields per motor in order, motors ascending, hand fields last",
                "",
                &all,
            )
            .decision("seed-rt-field-order")
            .decision("bh8-44-rt-field-order")
            .line("1234LOOP")
            .block(&block, Shape::Block(self.at_rest()))
            .block(b"A", Shape::Block(self.at_rest()))
            .abort();
        self.add(k);

        let mpe1 = self.mpe(1);
        let k = self
            .rt_case("rt-lfap-byte-order", "LFAP is two bytes, high byte first: 5000 is 13 88", "1", &["LFAP"])
            .level(Level::Must)
            .line("1M 5000")
            .line("1LOOP")
            .block(
                b"A",
                Shape::Block(vec![FieldRule { motor: Some(1), name: "LFAP", range: Some((5000 - mpe1, 5000 + mpe1)) }]),
            )
            .abort();
        self.add(k);

        self.lfdp_case(
            "rt-lfdp-worked-example",
            "The LFDP worked example: LFDPC 2, reported 1500, moved to 2000: 127, 123, 0",
            2,
            1500,
            2000,
            false,
            3,
        );
        if self.has_param("LFDPD") {
            self.lfdp_case(
                "rt-lfdpd-discard",
                "With LFDPD 1 the clipped rest of LFDP is dropped: 127, 0, 0",
                2,
                1500,
                2000,
                true,
                3,
            );
        }
        self.lfdp_case(
            "rt-lfdpc-scaling",
            "LFDP is the movement divided by LFDPC: 1000 counts with LFDPC 10 read 100",
            10,
            0,
            1000,
            false,
            2,
        );

        // LFVC: the feedback velocity is the velocity divided by LFVC.
        let lcvc = ((1i64 << self.p.hand.lcv_fraction_bits) / 4).clamp(1, 255);
        let datum: i64 = 40;
        let lfv = self.lfv_at(datum, lcvc, 2);
        let k = self
            .rt_case(
                "rt-lfvc-scaling",
                &format!(
                    "LFV is the velocity divided by LFVC: LCV {datum} x LCVC {lcvc} reads about {lfv} with LFVC 2"
                ),
                "1",
                &["LCV", "LFV"],
            )
            .src("Parameter LFVC")
            .src("Parameter LCVC")
            .decision("seed-rt-velocity")
            .decision("bh8-velocity-units")
            .note("Velocities during motion are compared with 25% tolerance.")
            .line(&format!("1FSET LCVC {lcvc} LFVC 2"))
            .line("1LOOP")
            .block(&[b'C', datum as u8], Shape::Block(Vec::new()))
            .pause_ms(50)
            .block(b"A", Shape::Block(vec![FieldRule { motor: Some(1), name: "LFV", range: Some(tol(lfv)) }]))
            .abort();
        self.add(k);

        let k = self
            .rt_case(
                "rt-bad-header-returns-to-supervisory",
                "After an invalid header the hand is back in supervisory mode",
                "1",
                &["LFAP"],
            )
            .level(Level::Must)
            .line("1LOOP")
            .block(b"A", Shape::Block(self.at_rest()))
            .block(b"X", Shape::Exact)
            .line("FGET DP")
            .line("1LOOP")
            .abort();
        self.add(k);

        self.realtime_decisions();
    }

    /// The LFV a motor reads while it runs at the control velocity of an LCV `datum` with
    /// `lcvc` (no gain field), reported with `lfvc` (0 acts as 1).
    fn lfv_at(&self, datum: i64, lcvc: i64, lfvc: i64) -> i64 {
        let h = &self.p.hand;
        let raw = datum as f64 * lcvc as f64 / f64::from(1u32 << h.lcv_fraction_bits) * h.rt_velocity_counts_per_ms
            / h.lfv_counts_per_ms;
        (raw / lfvc.max(1) as f64).trunc() as i64
    }

    /// An LCVC for a brisk RealTime move that stays inside the joint range over a case's short
    /// pauses: half of one whole LCV unit (LCV has `lcv_fraction_bits` fraction bits).
    fn brisk_lcvc(&self) -> i64 {
        ((1i64 << self.p.hand.lcv_fraction_bits) / 2).clamp(1, 255)
    }

    /// RealTime cases for decisions about the loop's motors, gains and coefficients.
    fn realtime_decisions(&mut self) {
        // LFV x LFVC is the velocity: two motors at one velocity, LFVC 1 and 2.
        let (datum, lcvc) = (40i64, self.brisk_lcvc());
        let (v1, v2) = (self.lfv_at(datum, lcvc, 1), self.lfv_at(datum, lcvc, 2));
        let mut k = self
            .rt_case(
                "rt-lfv-formula",
                &format!("LFV x LFVC is the velocity: two motors at one velocity read about {v1} with LFVC 1 and {v2} with LFVC 2"),
                "12",
                &["LCV", "LFV"],
            )
            .src("Parameter LFV")
            .src("Parameter LFVC");
        k = k.decision("seed-lfv-formula").decision("seed-rt-velocity").decision("bh8-velocity-units");
        let k = k
            .note("Velocities during motion are compared with 25% tolerance.")
            .line(&format!("12FSET LCVC {lcvc}"))
            .line("1FSET LFVC 1")
            .line("2FSET LFVC 2");
        self.add(two_motor_velocities(k, datum, v1, v2));

        // LCVC multiplies the datum: two motors at one datum, LCVC twice as large on motor 1.
        let (v1, v2) = (self.lfv_at(datum, 2 * lcvc, 1), self.lfv_at(datum, lcvc, 1));
        let mut k = self
            .rt_case(
                "rt-lcvc-scaling",
                &format!("The control velocity is LCV x LCVC: one datum reads about {v1} with LCVC {} and {v2} with LCVC {lcvc}", 2 * lcvc),
                "12",
                &["LCV", "LFV"],
            )
            .src("Parameter LCVC")
            .src("Parameter LCV");
        k = k.decision("seed-rt-velocity").decision("bh8-velocity-units");
        let k = k
            .note("Velocities during motion are compared with 25% tolerance.")
            .line(&format!("1FSET LCVC {}", 2 * lcvc))
            .line(&format!("2FSET LCVC {lcvc}"));
        self.add(two_motor_velocities(k, datum, v1, v2));

        // With LCPG 1 the gain starts at 0: a velocity alone does not move the motor. A motor
        // without LCV keeps its control velocity of 0 whatever its gain.
        let finger = self.limit(1);
        let v = self.lfv_at(datum, lcvc, 1);
        let still = |g: &Gen| -> Vec<FieldRule> {
            (1..=2u8).map(|m| FieldRule { motor: Some(m), name: "LFAP", range: Some((0, g.mpe(m))) }).collect()
        };
        let moving = vec![
            FieldRule { motor: Some(1), name: "LFV", range: Some(tol(v)) },
            FieldRule { motor: Some(1), name: "LFAP", range: Some((0, finger)) },
            FieldRule { motor: Some(2), name: "LFAP", range: Some((0, self.mpe(2))) },
        ];
        let mut k = self
            .rt_case(
                "rt-lcpg-zero-gain",
                "With LCPG 1 the gain starts at 0 on LOOP entry: a control velocity moves nothing until a gain arrives; a motor without LCV stays",
                "12",
                &["LCPG", "LFV", "LFAP"],
            )
            .src("Parameter LCPG");
        k = k.decision("seed-lcpg-gain").decision("bh8-rt-zero-gain");
        let k = k
            .note(format!(
                "Control blocks: motor 1 LCV then LCPG, motor 2 LCPG. The answer to a C block shows the state before \
                 its data. Once a gain arrives motor 1 runs at about LFV {v} (25% tolerance)."
            ))
            .line(&format!("1FSET LCV 1 LCVC {lcvc}"))
            .line("12LOOP")
            .comment(format!("velocity {datum}, gain 0 on motor 1; gain 64 on motor 2, which has no velocity field"))
            .block(&[b'C', datum as u8, 0, 64], Shape::Block(still(self)))
            .pause_ms(100)
            .block(b"A", Shape::Block(still(self)))
            .comment("the same velocity with gain 64: motor 1 runs, motor 2 still has no velocity")
            .block(&[b'C', datum as u8, 64, 64], Shape::Block(still(self)))
            .pause_ms(100)
            .block(b"A", Shape::Block(moving))
            .abort();
        self.add(k);

        // LOOP with no prefix takes the motors whose EN is 1; a prefix names them whatever EN.
        let rest: Vec<FieldRule> = self.at_rest();
        let mut k = self
            .rt_case(
                "rt-loop-en-motors",
                "LOOP with no prefix runs the motors whose EN is 1 (fewer fields); a prefix names its motors whatever EN",
                "",
                &["LFAP"],
            )
            .src("Parameter EN");
        k = k.decision("seed-param-prefix-en").decision("bh8-loop-motors").decision("bh8-param-prefix-en");
        let k = k
            .line("SFSET EN 0")
            .comment("motors 1, 2 and 3: three LFAP fields")
            .line("LOOP")
            .block(b"A", Shape::Block(rest.clone()))
            .abort()
            .comment("the spread alone: one LFAP field")
            .line("4LOOP")
            .block(b"A", Shape::Block(rest))
            .abort();
        self.add(k);

        // SGFLIP turns the LFS byte over as it turns FGET SG over.
        if self.p.decisions.iter().any(|d| d.id == "bh8-lfs-sgflip") {
            let f = self.p.hand.free_strain;
            let (plain, flipped) = ((0, (2 * f).min(255)), ((255 - 2 * f).max(0), 255));
            let k = self
                .rt_case(
                    "rt-lfs-sgflip",
                    "With SGFLIP 1 the LFS byte is 255 minus the strain, as FGET SG reads",
                    "12",
                    &["LFS"],
                )
                .src("Parameter LFS")
                .src("Parameter SGFLIP")
                .decision("bh8-lfs-sgflip")
                .decision("bh8-sgflip-default")
                .note(format!(
                    "A free finger's strain is near {f}: with SGFLIP 0 it reads {}..{}, with SGFLIP 1 {}..{}.",
                    plain.0, plain.1, flipped.0, flipped.1
                ))
                .line("2FSET SGFLIP 1")
                .line_shaped("12FGET SG", Shape::Values(vec![vec![Some(plain), Some(flipped)]]))
                .line("12LOOP")
                .block(
                    b"A",
                    Shape::Block(vec![
                        FieldRule { motor: Some(1), name: "LFS", range: Some(plain) },
                        FieldRule { motor: Some(2), name: "LFS", range: Some(flipped) },
                    ]),
                )
                .abort();
            self.add(k);
        }

        // LCVC, LFVC, LFDPC and LFDPD shape the data but add no field.
        if self.p.decisions.iter().any(|d| d.id == "bh8-rt-coefficients") {
            let k = self
                .rt_case(
                    "rt-coefficients-no-field",
                    "LCVC, LFVC, LFDPC and LFDPD add no field: with LCV and LFAP the blocks stay 2 and 3 bytes",
                    "1",
                    &["LCV", "LFAP"],
                )
                .decision("bh8-rt-coefficients")
                .line("1FSET LCVC 2 LFVC 2 LFDPC 2")
                .line("PSET LFDPD 1")
                .line("1LOOP")
                .block(&[b'C', 0], Shape::Block(self.at_rest()))
                .block(b"A", Shape::Block(self.at_rest()))
                .abort();
            self.add(k);
        }

        // A coefficient of 0 is accepted and divides as 1.
        if self.p.decisions.iter().any(|d| d.id == "bh8-coefficient-range") {
            let mpe = 10;
            let (from, to) = (0i64, 100i64);
            let mut lfdp = vec![(i64::MAX, i64::MIN); 2];
            for p1 in (from - mpe).max(0)..=from + mpe {
                for p2 in (to - mpe).max(0)..=to + mpe {
                    let mut r = p1;
                    for slot in lfdp.iter_mut() {
                        let v = i64::from(lfdp_step(&mut r, p2, 1, false));
                        *slot = (slot.0.min(v), slot.1.max(v));
                    }
                }
            }
            let both = |name: &'static str, r: Option<Range>| -> Vec<FieldRule> {
                (1..=2u8).map(|m| FieldRule { motor: Some(m), name, range: r }).collect()
            };
            let v = self.lfv_at(datum, lcvc, 1);
            let near: [Range; 4] = [(0, mpe); 4];
            let mut k = self
                .rt_case(
                    "rt-coefficients-zero",
                    "LFVC 0 and LFDPC 0 are accepted and act as 1: motor 1 (0) reads as motor 2 (1)",
                    "12",
                    &["LCV", "LFV", "LFDP"],
                )
                .src("Parameter LFVC")
                .src("Parameter LFDPC")
                .decision("bh8-coefficient-range")
                .note(format!(
                    "MPE is {mpe} so that LFDP after the move is narrow; velocities are compared with 25% tolerance."
                ))
                .line("1FSET LFVC 0 LFDPC 0")
                .line("2FSET LFVC 1 LFDPC 1")
                .line(&format!("12FSET LCVC {lcvc} MPE {mpe}"))
                .get("12", &["LFVC", "LFDPC"], None)
                .get("12", &["P"], Some(near))
                .line(&format!("12M {to}"))
                .line("12LOOP");
            for r in &lfdp {
                k = k.block(b"A", Shape::Block(both("LFDP", Some(*r))));
            }
            let mut moving = both("LFV", Some(tol(v)));
            moving.extend(both("LFDP", Some((0, 127))));
            let k = k
                .block(&[b'C', datum as u8, datum as u8], Shape::Block(Vec::new()))
                .pause_ms(50)
                .block(b"A", Shape::Block(moving))
                .abort();
            self.add(k);
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn lfdp_case(&mut self, id: &str, title: &str, coeff: i64, from: i64, to: i64, discard: bool, blocks: usize) {
        let mpe = self.mpe(1);
        // Every position the two moves may end at within MPE, and the LFDP values that follow.
        let mut ranges = vec![(i64::MAX, i64::MIN); blocks];
        for p1 in (from - mpe).max(0)..=from + mpe {
            for p2 in (to - mpe).max(0)..=to + mpe {
                let mut r = p1;
                for slot in ranges.iter_mut() {
                    let v = i64::from(lfdp_step(&mut r, p2, coeff, discard));
                    *slot = (slot.0.min(v), slot.1.max(v));
                }
            }
        }
        let mut k = self.rt_case(id, title, "1", &["LFDP"]).src("Parameter LFDPC");
        if discard {
            k = k.src("Parameter LFDPD");
        }
        k = k.decision("seed-lfdp-state").decision("bh8-lfdp-state").decision("bh8-rt-clipping");
        if discard {
            k = k.line("PSET LFDPD 1");
        }
        k = k
            .note(format!("LFDP ranges cover both moves ending anywhere within MPE ({mpe}) of their goals."))
            .line(&format!("1FSET LFDPC {coeff}"));
        if from > 0 {
            k = k.line(&format!("1M {from}"));
        }
        k = k.get("1", &["P"], Some(self.near([from; 4]))).line(&format!("1M {to}")).line("1LOOP");
        for r in ranges {
            k = k.block(b"A", Shape::Block(vec![FieldRule { motor: Some(1), name: "LFDP", range: Some(r) }]));
        }
        k = k.abort();
        self.add(k);
    }

    // ------------------------------------------------------------------ the seed's examples

    fn examples(&mut self) {
        let mut k = self
            .case(
                "example-realtime-seed",
                "The seed's RealTime example: 124LOOP, 3-byte control blocks, 6-byte feedback blocks",
            )
            .clause("seed: RealTime Control, Example")
            .requires(Requirement::Realtime)
            .level(Level::Must);
        k = k.decision("seed-rt-feedback-order");
        let moving = vec![
            FieldRule { motor: Some(1), name: "LFDP", range: Some((0, 127)) },
            FieldRule { motor: Some(2), name: "LFDP", range: Some((-128, 0)) },
        ];
        let mut k = k.preamble(true);
        if self.p.params.iter().any(|x| x.name == "LFT") {
            k = k.line("PSET LFT 0");
        }
        let k = k
            .line("12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1")
            .line("4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1")
            .line("124LOOP")
            .block(&[0x43, 0x14, 0xFB], Shape::Block(Vec::new()))
            .block(&[0x43, 0x14, 0xFB], Shape::Block(moving.clone()))
            .block(&[0x43, 0x00, 0x00], Shape::Block(moving))
            .abort();
        self.add(k);

        let finger = self.limit(1);
        let moving = vec![
            FieldRule { motor: Some(1), name: "LFAP", range: Some((0, finger)) },
            FieldRule { motor: Some(2), name: "LFAP", range: Some((0, self.mpe(2))) },
            FieldRule { motor: Some(3), name: "LFAP", range: Some((0, self.mpe(3))) },
        ];
        let mut k = self
            .case(
                "example-realtime-program",
                "The seed's RealTime example program: RTSetFlags, 123LOOP, 4-byte C blocks, 7-byte feedback",
            )
            .clause("seed: Example Programs, RealTime Mode Example Program")
            .requires(Requirement::Realtime)
            .level(Level::Must)
            .preamble(true)
            .line("123FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFVC 1 LFS 0 LFAP 1 LFDP 0 LFDPC 1")
            .line("123LOOP");
        for _ in 0..5 {
            k = k.block(&[0x43, 55, 0, 0], Shape::Block(moving.clone()));
        }
        let k = k.abort().line("FGET DP");
        self.add(k);

        let mut k = self
            .case("example-supervisory-program", "The seed's supervisory example program: CR, RESET, HI, 123C, 123O")
            .clause("seed: Example Programs, Supervisory Mode Example Program")
            .decision("framing-empty-line")
            .level(Level::Must)
            .requires(Requirement::Motion)
            .comment("a host's start-up: ^C, a bare CR, RESET")
            .abort()
            .line("")
            .line_shaped("RESET", Shape::Banner)
            .line("FDEF");
        if self.has_cmd("PDEF") {
            k = k.line("PDEF");
        }
        let k = k.line("HI").line("123C").line("123O").get("", &["P"], Some(self.near([0; 4])));
        self.add(k);
    }

    // ------------------------------------------------------------------ firmware families

    /// The tables both BH8-262 firmware profiles share, printed the same way in each, so that
    /// the two goldens of this case differ only where the firmware does (LCT, LFBP, LFAIN).
    fn firmware(&mut self) {
        if !self.p.decisions.iter().any(|d| d.id == "bh8-new-rt-fields-defaults") {
            return;
        }
        let lines: Vec<&str> = ["A?", "ERR", "FLISTA", "PLISTA"].into_iter().filter(|n| self.has_cmd(n)).collect();
        let values: Vec<&str> = ["FLISTAV", "PLISTAV"].into_iter().filter(|n| self.has_cmd(n)).collect();
        let mut k = self.case(
            "firmware-shared-tables",
            "Firmware 4.3x and 4.4x share commands, status texts, parameters and defaults; 4.4x adds LCT, LFBP and LFAIN",
        );
        for n in lines.iter().chain(&values) {
            k = k.src(&format!("Command {n}"));
        }
        k = k
            .decision("bh8-44-same-as-43")
            .decision("bh8-err-format")
            .decision("bh8-help-format")
            .decision("bh8-list-names-format")
            .decision("bh8-list-values-format")
            .level(Level::Info)
            .note(
                "Compare this file across the bh8-262 profiles: only the header, LFT's description (its width) and \
                 the LCT, LFBP and LFAIN lines differ.",
            )
            .preamble(false);
        for n in lines {
            k = k.line(n);
        }
        for n in values {
            k = k.line_shaped(n, Shape::ListValues);
        }
        self.add(k);
    }
}

/// The label of the profile's source in clause strings.
impl Gen {
    /// What host libraries look for after RESET (Barrett's C++ API fails to initialise
    /// without it): `BarrettHand Firmware`, the line ending straight after it, more banner
    /// text, the prompt.
    fn banner(&mut self) {
        // The profile's own banner decision (`seed-banner-text`, `bh8-banner-text`): data, not
        // a branch on the profile's id.
        let Some(decision) = self.p.decisions.iter().map(|d| d.id.clone()).find(|id| id.ends_with("-banner-text"))
        else {
            return;
        };
        let k = self
            .case(
                "banner-lines",
                "After RESET, 'BarrettHand Firmware' ends its line and more banner text follows before the prompt",
            )
            .src("Command RESET")
            .decision(&decision)
            .comment("a host's start-up: ^C, then RESET; it searches the answer for the banner line")
            .abort()
            .comment("the check")
            .line_shaped("RESET", Shape::BannerLines);
        self.add(k);
    }
}

/// The band a feedback velocity of about `v` may read in: 25 %, the tolerance the cases' notes
/// state.
fn tol(v: i64) -> (i64, i64) {
    (((v as f64) * 0.75).floor() as i64, ((v as f64) * 1.25).ceil() as i64)
}

/// Motors 1 and 2 in the loop, both sent `datum`; after a pause their feedback velocities read
/// about `v1` and `v2`.
fn two_motor_velocities(k: CaseB, datum: i64, v1: i64, v2: i64) -> CaseB {
    k.line("12LOOP")
        .block(&[b'C', datum as u8, datum as u8], Shape::Block(Vec::new()))
        .pause_ms(50)
        .block(
            b"A",
            Shape::Block(vec![
                FieldRule { motor: Some(1), name: "LFV", range: Some(tol(v1)) },
                FieldRule { motor: Some(2), name: "LFV", range: Some(tol(v2)) },
            ]),
        )
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
