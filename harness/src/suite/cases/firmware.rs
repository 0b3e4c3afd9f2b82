//! Firmware families, and the RESET banner host libraries look for.

use super::*;

impl Gen {
    /// The tables both BH8-262 firmware profiles share, printed the same way in each, so that
    /// the two goldens of this case differ only where the firmware does (LCT, LFBP, LFAIN).
    pub(super) fn firmware(&mut self) {
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

impl Gen {
    /// What host libraries look for after RESET (Barrett's C++ API fails to initialise
    /// without it): a script, `harness/suite-cases/firmware/banner-lines.gcls`.
    pub(super) fn banner(&mut self) {
        self.scripts(&["banner-lines"]);
    }
}
