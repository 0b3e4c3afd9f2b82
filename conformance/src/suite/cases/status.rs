//! Status bits: which answer sets which bit, and how `ERR n` reads. The cases are scripts
//! (`conformance/suite-cases/status/`; an id that holds a status code names it as `{code:...}`)
//! except `status-N-text-only`, one per status the profile defines but never sends.

use super::*;

impl Gen {
    pub(super) fn status(&mut self) {
        self.scripts(&[
            "status-terminate-before-hi",
            "status-not-initialized",
            "status-32-unknown-command",
            "status-64-unknown-parameter",
            "status-128-invalid-value",
            "status-256-read-only",
            "status-1024-too-many-arguments",
            "status-4096-prefix-not-allowed",
        ]);

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

        self.scripts(&[
            "status-combined-prefix-and-arguments",
            "status-combined-unknown-and-invalid",
            "status-combined-unknown-and-read-only",
            "status-combined-invalid-and-read-only",
            "status-combined-grammar-and-not-initialized",
            "status-missed-position",
            "status-bad-header",
            "status-overtemperature",
            "status-abort",
        ]);
    }
}
