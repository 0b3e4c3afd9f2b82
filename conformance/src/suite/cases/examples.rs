//! The seed document's example programs. Every case is a script
//! (`conformance/suite-cases/examples/`).

use super::*;

impl Gen {
    pub(super) fn examples(&mut self) {
        self.scripts(&["example-realtime-seed", "example-realtime-program", "example-supervisory-program"]);
    }
}
