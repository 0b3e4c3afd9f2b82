//! Motion: where HI, C, O, M, IC and IO leave the motors. Every case is a script
//! (`conformance/suite-cases/motion/`); their lines and bounds name the profile's joint limits,
//! MPE and status codes as `{expressions}`.

use super::*;

impl Gen {
    pub(super) fn motion(&mut self) {
        self.scripts(&[
            "motion-goal-within-mpe",
            "motion-strain-limit",
            "motion-close-stall-no-status",
            "motion-mpe-boundary",
            "motion-hi-stall",
        ]);
    }
}
