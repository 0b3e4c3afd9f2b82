//! Persistence: the saved sets, FDEF/FLOAD/FSAVE and their P forms, RESET. The cases are
//! scripts (`conformance/suite-cases/persistence/`) except `persist-saved-set`, whose lines are
//! computed from the profile's saved set.

use super::*;

impl Gen {
    pub(super) fn persistence(&mut self) {
        self.scripts(&[
            "persist-fdef",
            "persist-fdef-ram-only",
            "persist-fsave-reset",
            "persist-fload",
            "persist-reset-discards-ram",
        ]);

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

        self.scripts(&["persist-pdef", "persist-psave-reset", "persist-pload"]);
    }
}
