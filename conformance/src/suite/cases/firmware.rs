//! Firmware families, and the RESET banner host libraries look for. Both cases are scripts
//! (`conformance/suite-cases/firmware/`).

use super::*;

impl Gen {
    /// The tables both BH8-262 firmware profiles share: a script,
    /// `conformance/suite-cases/firmware/firmware-shared-tables.gcls`.
    pub(super) fn firmware(&mut self) {
        self.scripts(&["firmware-shared-tables"]);
    }
}

impl Gen {
    /// What host libraries look for after RESET (Barrett's C++ API fails to initialise
    /// without it): a script, `conformance/suite-cases/firmware/banner-lines.gcls`.
    pub(super) fn banner(&mut self) {
        self.scripts(&["banner-lines"]);
    }
}
