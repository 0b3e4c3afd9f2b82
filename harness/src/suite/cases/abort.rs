//! ^C: aborting an idle line, a motion, the RealTime loop. The cases are scripts
//! (`harness/suite-cases/abort/`) except `abort-motion`, whose read-back follows the profile's
//! close targets.

use super::*;

impl Gen {
    pub(super) fn abort(&mut self) {
        self.scripts(&["abort-idle"]);

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

        self.scripts(&["abort-motion-discards-queue", "abort-loop"]);
    }
}
