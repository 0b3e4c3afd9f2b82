//! ^C: aborting an idle line, a motion, the RealTime loop. Every case is a script
//! (`conformance/suite-cases/abort/`).

use super::*;

impl Gen {
    pub(super) fn abort(&mut self) {
        self.scripts(&["abort-idle", "abort-motion", "abort-motion-discards-queue", "abort-loop"]);
    }
}
