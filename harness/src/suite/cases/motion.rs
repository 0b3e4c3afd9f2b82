//! Motion: where HI, C, O, M, IC and IO leave the motors. `motion-goal-within-mpe` is a
//! script (`harness/suite-cases/motion/`); the others compute their lines and bounds from the
//! profile's joint limits and status codes.

use super::*;

impl Gen {
    pub(super) fn motion(&mut self) {
        self.scripts(&["motion-goal-within-mpe"]);

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
}
