//! Commands: a generator over the profile's command table: each command's prefix and argument
//! rules, before-HI and over-temperature answers, and what a run of it prints. No case here is
//! written by hand (those are scripts, `harness/suite-cases/`).

use super::*;

impl Gen {
    pub(super) fn commands(&mut self) {
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
    pub(super) fn valid_args(&self, c: &CommandSpec) -> String {
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
    pub(super) fn writable_for(&self, setter: &str) -> Vec<ParamSpec> {
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

    pub(super) fn command_prefix(&mut self, c: &CommandSpec) {
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
    pub(super) fn prefixed_run(&self, k: CaseB, c: &CommandSpec) -> CaseB {
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
    pub(super) fn motion_recipe(&self, kind: CommandKind, prefix: &str) -> (Vec<String>, [Range; 4]) {
        let sel = super::super::depends::prefix_motors(&self.p, prefix);
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

    pub(super) fn command_args(&mut self, c: &CommandSpec) {
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

    pub(super) fn command_before_hi(&mut self, c: &CommandSpec) {
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

    pub(super) fn command_overtemp(&mut self, c: &CommandSpec) {
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

    pub(super) fn command_run(&mut self, c: &CommandSpec) {
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
                // What VERS says is the profile's text decision: some lines, none a status.
                let k = k.decision("seed-vers-text").decision("bh8-vers-text");
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
    pub(super) fn listing_order(&self, k: CaseB, kind: CommandKind) -> CaseB {
        let k = k.decision("bh8-listing-order");
        match kind {
            CommandKind::MotorList
            | CommandKind::MotorListAll
            | CommandKind::MotorListValues
            | CommandKind::MotorListAllValues => k.decision("bh8-44-listing-order"),
            _ => k,
        }
    }
}
