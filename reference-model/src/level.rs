//! How strongly a conformance check binds an implementation: MUST, SHOULD, MAY or INFO.
//!
//! A leaf: spec decisions carry a [`Level`] (checked when a profile loads, so a typo is an
//! error, never a silent INFO), and the suite and transcripts grade their cases with it.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// How strongly a case binds an implementation. Ordered strongest first (`Must < Info`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Level {
    /// Required by the protocol's sources; a failure is non-conformance.
    #[default]
    Must,
    /// Expected; a decision of this project with good evidence.
    Should,
    /// Allowed behaviour.
    May,
    /// Informational: the project's choice where no source settles it. Never a failure of
    /// conformance by itself.
    Info,
}

impl Level {
    /// Every level, strongest first.
    pub const ALL: [Level; 4] = [Level::Must, Level::Should, Level::May, Level::Info];

    /// The upper-case name as written in files.
    pub fn as_str(self) -> &'static str {
        match self {
            Level::Must => "MUST",
            Level::Should => "SHOULD",
            Level::May => "MAY",
            Level::Info => "INFO",
        }
    }
}

impl fmt::Display for Level {
    /// The name, padded as the format asks (`{:<6}` lines up a column of levels).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.as_str())
    }
}

/// A level name that is not MUST, SHOULD, MAY or INFO.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown level `{0}` (expected MUST, SHOULD, MAY or INFO)")]
pub struct UnknownLevel(pub String);

impl FromStr for Level {
    type Err = UnknownLevel;
    fn from_str(s: &str) -> Result<Level, UnknownLevel> {
        Level::ALL.into_iter().find(|l| l.as_str().eq_ignore_ascii_case(s)).ok_or_else(|| UnknownLevel(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_order_strongest_first() {
        for l in Level::ALL {
            assert_eq!(l.as_str().parse::<Level>(), Ok(l));
            assert_eq!(l.as_str().to_lowercase().parse::<Level>(), Ok(l));
        }
        assert_eq!("MUTS".parse::<Level>(), Err(UnknownLevel("MUTS".into())));
        assert!(Level::Must < Level::Should && Level::May < Level::Info);
    }
}
