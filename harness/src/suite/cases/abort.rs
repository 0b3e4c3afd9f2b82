//! ^C: aborting an idle line, a motion, the RealTime loop.

use super::*;

impl Gen {
    pub(super) fn abort(&mut self) {
        let k = self
            .case("abort-idle", "^C while idle prints a fresh prompt and no status")
            .decision("framing-abort-idle")
            .preamble(false)
            .abort()
            .abort()
            .line("FGET DP");
        self.add(k);

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

        let k = self
            .case("abort-motion-discards-queue", "^C during motion also discards the lines queued behind the command")
            .src("Command ^C")
            .decision("framing-busy-input")
            .decision("seed-abort")
            .decision("bh8-abort-motion")
            .requires(Requirement::AbortTiming)
            .preamble(true)
            .nowait("GC\rFGET DP")
            .pause_ms(200)
            .abort()
            .line("FGET DS");
        self.add(k);

        let k = self
            .case("abort-loop", "^C in place of a RealTime header ends the loop and prints the prompt")
            .src("RealTime Control")
            .decision("seed-abort")
            .decision("bh8-abort-loop")
            .requires(Requirement::Realtime)
            .preamble(true)
            .line("1LOOP")
            .abort()
            .line("FGET DP");
        self.add(k);
    }
}
