//! Deliberate firmware bugs (mutants). The conformance suite proves its worth by failing
//! against each of these; the unmutated device must pass everything.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

macro_rules! faults {
    ($( $(#[doc = $doc:literal])* $variant:ident => $name:literal, )*) => {
        /// A plausible firmware bug the simulated hand can be told to have.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
        #[serde(rename_all = "kebab-case")]
        pub enum Fault {
            $( $(#[doc = $doc])* $variant, )*
        }

        impl Fault {
            /// Every fault, in declaration order.
            pub const ALL: &'static [Fault] = &[$(Fault::$variant,)*];

            /// The fault's command-line name.
            pub fn name(self) -> &'static str {
                match self { $(Fault::$variant => $name,)* }
            }

            /// A one-line description.
            pub fn description(self) -> &'static str {
                match self { $(Fault::$variant => concat!($($doc),*).trim_ascii(),)* }
            }
        }
    };
}

faults! {
    /// Lines end in CR LF instead of LF CR.
    CrLf => "crlf",
    /// Received bytes are not echoed.
    NoEcho => "no-echo",
    /// The prompt lacks its trailing space (`=>`).
    PromptNoSpace => "prompt-no-space",
    /// LFAP is sent little-endian.
    LittleEndianLfap => "lfap-little-endian",
    /// A write to a read-only parameter gives 128 instead of 256.
    ReadOnlyStatus => "read-only-status",
    /// LFDP wraps instead of clipping to one signed byte.
    LfdpNotClipped => "lfdp-not-clipped",
    /// A position move never reports 16, whatever MPE says.
    MpeIgnored => "mpe-ignored",
    /// After a bad RealTime header the hand stays in the loop.
    StayInLoop => "stay-in-loop",
    /// Range checks accept one past the maximum.
    RangeOffByOne => "range-off-by-one",
    /// FDEF does not restore MCV.
    FdefSkipsMcv => "fdef-skips-mcv",
    /// Lower-case command words are refused.
    LowercaseRejected => "lowercase-rejected",
    /// FGET prints the motors in descending order.
    FgetReversed => "fget-reversed",
    /// ^C during motion gives only the prompt, never its status.
    AbortSilent => "abort-silent",
    /// LOOP puts a line break before the `*`.
    LoopAckNewline => "loop-ack-newline",
    /// RESET does not print the banner.
    ResetNoBanner => "reset-no-banner",
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The name is not a known fault.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown fault `{0}`; known faults: {known}", known = Fault::ALL.iter().map(|f| f.name()).collect::<Vec<_>>().join(", "))]
pub struct UnknownFault(pub String);

impl FromStr for Fault {
    type Err = UnknownFault;
    fn from_str(s: &str) -> Result<Fault, UnknownFault> {
        Fault::ALL.iter().copied().find(|f| f.name().eq_ignore_ascii_case(s)).ok_or_else(|| UnknownFault(s.to_string()))
    }
}
