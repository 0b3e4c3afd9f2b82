//! Status bits: which answer sets which bit, and how `ERR n` reads.

use super::*;

impl Gen {
    pub(super) fn status(&mut self) {
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
}
