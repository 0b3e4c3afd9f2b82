//! Parameters: a generator over the profile's parameter table (each parameter's default,
//! setting, range and access). Cases about one named parameter, the unknown-name cases and the
//! fixed-line effect cases are scripts (`conformance/suite-cases/params/`).

use super::*;

impl Gen {
    pub(super) fn params(&mut self) {
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
        self.scripts(&[
            "param-unknown-name-fget",
            "param-unknown-name-fset",
            "param-unknown-name-pget",
            "param-unknown-name-pset",
        ]);
        self.scripts(&[
            "param-scope-commands",
            "param-temp-global",
            "param-tmp-alias",
            "param-msg-hsg-alias",
            "param-en-narrows-motion",
            "param-spread-finger-defaults",
        ]);

        self.scripts(&["param-44-rt-flags"]);
    }

    /// The source clause of a parameter case, and the decisions that govern it: those about
    /// defaults only for the default case.
    pub(super) fn param_level(&self, mut k: CaseB, x: &ParamSpec, default_case: bool) -> CaseB {
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

    pub(super) fn param_default(&mut self, x: &ParamSpec) {
        let what = if x.live { "reads" } else { "reads its factory default" };
        let k = self.case(format!("param-{}-default", slug(&x.name)), format!("{} {what}", x.name));
        let k = self.param_level(k, x, true).preamble(false).get("", &[&x.name], None);
        self.add(k);
    }

    pub(super) fn param_set(&mut self, x: &ParamSpec) {
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

    pub(super) fn param_range(&mut self, x: &ParamSpec) {
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

    pub(super) fn param_read_only(&mut self, x: &ParamSpec) {
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
}
