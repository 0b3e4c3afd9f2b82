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
    /// without it): `BarrettHand Firmware`, the line ending straight after it, more banner
    /// text, the prompt.
    pub(super) fn banner(&mut self) {
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
