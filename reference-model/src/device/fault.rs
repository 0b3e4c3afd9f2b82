//! Deliberate firmware bugs (mutants). The conformance suite proves its worth by failing
//! against each of these; the unmutated device must pass everything.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::spec::Framing;

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
    /// DP is stored but ignored: M without an argument goes to the factory DP.
    DpIgnored => "dp-ignored",
    /// DS is stored but ignored: IC and IO step by the factory DS.
    DsIgnored => "ds-ignored",
    /// CT is stored but ignored: C closes to the factory CT.
    CtIgnored => "ct-ignored",
    /// OT is stored but ignored: O opens to the factory OT.
    OtIgnored => "ot-ignored",
    /// MCV is stored but ignored: closing runs at the factory MCV.
    McvIgnored => "mcv-ignored",
    /// MOV is stored but ignored: opening runs at the factory MOV.
    MovIgnored => "mov-ignored",
    /// ACCEL is stored but ignored: moves accelerate at the factory ACCEL.
    AccelIgnored => "accel-ignored",
    /// MPE is stored but ignored: the final position is checked against the factory MPE.
    MpeDefault => "mpe-default",
    /// TSTOP is stored but ignored: a stall ends after the factory TSTOP.
    TstopIgnored => "tstop-ignored",
    /// The high strain limit (HSG, or MSG) is stored but ignored.
    HsgIgnored => "hsg-ignored",
    /// LSG is stored but ignored.
    LsgIgnored => "lsg-ignored",
    /// HOLD is stored but ignored: a motor is held (or let go) after a move as its factory
    /// HOLD says.
    HoldIgnored => "hold-ignored",
    /// BS is stored but ignored: a finger whose breakaway is detected closes on as with the
    /// factory BS 0.
    BsIgnored => "bs-ignored",
    /// EN is stored but ignored: commands without a prefix act on every motor.
    EnIgnored => "en-ignored",
    /// SGFLIP is stored but ignored: the strain is never turned over.
    SgflipIgnored => "sgflip-ignored",
    /// OTEMP is stored but ignored: the hand never trips over temperature.
    OtempIgnored => "otemp-ignored",
    /// LCVC is stored but ignored: the control velocity uses the factory LCVC.
    LcvcIgnored => "lcvc-ignored",
    /// LFVC is stored but ignored: LFV is divided by the factory LFVC.
    LfvcIgnored => "lfvc-ignored",
    /// LFDPC is stored but ignored: LFDP is divided by the factory LFDPC.
    LfdpcIgnored => "lfdpc-ignored",
    /// LFDPD is stored but ignored: the clipped rest of LFDP is always carried.
    LfdpdIgnored => "lfdpd-ignored",
    /// The LCV flag is stored but ignored: the control block layout uses the factory LCV.
    LcvIgnored => "lcv-ignored",
    /// The LCPG flag is stored but ignored: the block layout and the gain use the factory LCPG.
    LcpgIgnored => "lcpg-ignored",
    /// The LFV flag is stored but ignored: the feedback layout uses the factory LFV.
    LfvIgnored => "lfv-ignored",
    /// The LFS flag is stored but ignored.
    LfsIgnored => "lfs-ignored",
    /// The LFAP flag is stored but ignored.
    LfapIgnored => "lfap-ignored",
    /// The LFDP flag is stored but ignored.
    LfdpIgnored => "lfdp-ignored",
    /// The LCT flag is stored but ignored.
    LctIgnored => "lct-ignored",
    /// The LFBP flag is stored but ignored.
    LfbpIgnored => "lfbp-ignored",
    /// The LFAIN flag is stored but ignored.
    LfainIgnored => "lfain-ignored",
    /// The LFT flag is stored but ignored.
    LftIgnored => "lft-ignored",
    /// A line with too many arguments (and no other problem) gets the prompt and no status.
    TooManyArgsSilent => "too-many-args-silent",
    /// A prefix on a command that takes none is ignored and the command runs.
    PrefixNotRefused => "prefix-not-refused",
    /// The prefix G names the spread too (1234 instead of 123).
    GIncludesSpread => "g-includes-spread",
    /// RESET keeps the parameters in RAM instead of loading the saved ones.
    ResetKeepsRam => "reset-keeps-ram",
    /// FDEF also writes the factory values to the EEPROM.
    FdefWritesEeprom => "fdef-writes-eeprom",
    /// The LCV datum is read as an unsigned byte: negative velocities become large positive ones.
    LcvUnsigned => "lcv-unsigned",
    /// FGET P does not set the position LFDP is reported against.
    FgetPKeepsReported => "fget-p-keeps-reported",
    /// Motion commands run on motors HI has not initialised, instead of giving 4.
    UninitializedMoves => "uninitialized-moves",
    /// An unknown command word gives 64 (unknown parameter) instead of 32.
    UnknownCommand64 => "unknown-command-64",
    /// An unknown parameter name gives 128 (invalid value) instead of 64.
    UnknownParam128 => "unknown-param-128",
    /// A refused FSET or PSET still applies the pairs that are valid on their own.
    PartialSetApplied => "partial-set-applied",
    /// A tab is not a separator: a line with one is an unknown command.
    TabNotSeparator => "tab-not-separator",
    /// A set whose last name has no value drops it silently instead of giving 128.
    MissingValueIgnored => "missing-value-ignored",
    /// An empty line gives ERR 32 instead of a fresh prompt.
    EmptyLineError => "empty-line-error",
    /// A line past the length limit runs cut short instead of giving its status.
    OverlongLineRuns => "overlong-line-runs",
    /// An empty line gets its prompt twice (the line handler and the main loop each print one):
    /// the second comes after the answer a host expects, so a host that stops reading at the
    /// first prompt meets it before its next answer.
    EmptyLineTwoPrompts => "empty-line-two-prompts",
    /// VERS is not implemented: it is an unknown command (its status, 32) instead of the
    /// version lines, so a host that reads the version at connect reads an error line.
    VersUnknown => "vers-unknown",
}

impl Fault {
    /// Applies the fault to the profile's framing, if it is a fault of framing alone (line
    /// ending, prompt, echo): such a fault is a patch of the profile, and the hand then runs
    /// the patched profile with no further check. Returns whether it was one.
    pub fn patch_framing(self, framing: &mut Framing) -> bool {
        match self {
            Fault::CrLf => framing.line_ending = "\r\n".to_string(),
            Fault::PromptNoSpace => framing.prompt = framing.prompt.trim_end_matches(' ').to_string(),
            Fault::NoEcho => framing.echo = false,
            _ => return false,
        }
        true
    }

    /// The parameters a `*-ignored` fault makes the hand ignore (it behaves as if each had its
    /// factory value, while FGET still reads back what was set), or none.
    pub fn ignored_params(self) -> &'static [&'static str] {
        match self {
            Fault::DpIgnored => &["DP"],
            Fault::DsIgnored => &["DS"],
            Fault::CtIgnored => &["CT"],
            Fault::OtIgnored => &["OT"],
            Fault::McvIgnored => &["MCV"],
            Fault::MovIgnored => &["MOV"],
            Fault::AccelIgnored => &["ACCEL"],
            Fault::MpeDefault => &["MPE"],
            Fault::TstopIgnored => &["TSTOP"],
            Fault::HsgIgnored => &["HSG", "MSG"],
            Fault::LsgIgnored => &["LSG"],
            Fault::HoldIgnored => &["HOLD"],
            Fault::BsIgnored => &["BS"],
            Fault::EnIgnored => &["EN"],
            Fault::SgflipIgnored => &["SGFLIP"],
            Fault::OtempIgnored => &["OTEMP"],
            Fault::LcvcIgnored => &["LCVC"],
            Fault::LfvcIgnored => &["LFVC"],
            Fault::LfdpcIgnored => &["LFDPC"],
            Fault::LfdpdIgnored => &["LFDPD"],
            Fault::LcvIgnored => &["LCV"],
            Fault::LcpgIgnored => &["LCPG"],
            Fault::LfvIgnored => &["LFV"],
            Fault::LfsIgnored => &["LFS"],
            Fault::LfapIgnored => &["LFAP"],
            Fault::LfdpIgnored => &["LFDP"],
            Fault::LctIgnored => &["LCT"],
            Fault::LfbpIgnored => &["LFBP"],
            Fault::LfainIgnored => &["LFAIN"],
            Fault::LftIgnored => &["LFT"],
            _ => &[],
        }
    }
}

/// The faults a hand has, as a set: each is read at the named hook where it bends the
/// hand's behaviour (`Device::has`), in O(1).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct FaultSet(u128);

const _: () = assert!(Fault::ALL.len() <= 128, "FaultSet holds at most 128 faults");

impl FaultSet {
    /// Whether the set holds `f`.
    pub fn contains(self, f: Fault) -> bool {
        self.0 & (1u128 << (f as u32)) != 0
    }

    /// Adds `f`.
    pub fn insert(&mut self, f: Fault) {
        self.0 |= 1u128 << (f as u32);
    }

    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The faults in declaration order (visiting only the faults held: the empty set, every
    /// unmutated hand's, costs nothing).
    pub fn iter(self) -> impl Iterator<Item = Fault> {
        let mut bits = self.0;
        std::iter::from_fn(move || {
            while bits != 0 {
                let i = bits.trailing_zeros();
                bits &= bits - 1;
                if let Some(f) = Fault::ALL.get(i as usize) {
                    return Some(*f);
                }
            }
            None
        })
    }
}

impl FromIterator<Fault> for FaultSet {
    fn from_iter<I: IntoIterator<Item = Fault>>(iter: I) -> FaultSet {
        let mut s = FaultSet::default();
        for f in iter {
            s.insert(f);
        }
        s
    }
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
