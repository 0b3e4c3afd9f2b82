//! Persistence: the saved sets, FDEF/FLOAD/FSAVE and their P forms, RESET.

use super::*;

impl Gen {
    pub(super) fn persistence(&mut self) {
        self.scripts(&["persist-fdef"]);

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

        self.scripts(&["persist-fload"]);

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

        self.scripts(&["persist-pdef"]);
        if self.has_cmd("PSAVE") && self.has_param("OTEMP") {
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
        }
        self.scripts(&["persist-pload"]);
    }
}
