//! The closed vocabulary of RealTime (LOOP) blocks that a profile names: the RealTime flags,
//! the type of the field each adds, and the block it adds it to. [`crate::spec`] loads a
//! profile's flags into these; [`crate::realtime`] computes layouts and values from them.

use std::ops::RangeInclusive;

use serde::{Deserialize, Serialize};

/// Which RealTime block a flag adds a field to.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BlockKind {
    /// Host to hand.
    Control,
    /// Hand to host.
    Feedback,
}

/// A RealTime flag: a parameter whose value 1 adds a field to the control or feedback block.
/// The loader maps each parameter with an `rt` table to one of these and refuses other names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum RtFlag {
    /// LCV: control velocity (per motor, control).
    Lcv,
    /// LCPG: control proportional gain (per motor, control).
    Lcpg,
    /// LCT: control torque (per motor, control; bh8-262 4.4).
    Lct,
    /// LFV: feedback velocity (per motor, feedback).
    Lfv,
    /// LFS: feedback strain (per motor, feedback).
    Lfs,
    /// LFAP: feedback absolute position (per motor, feedback).
    Lfap,
    /// LFDP: feedback delta position (per motor, feedback).
    Lfdp,
    /// LFBP: feedback breakaway position (per motor, feedback; bh8-262 4.4).
    Lfbp,
    /// LFAIN: feedback analog input (per motor, feedback; bh8-262 4.4).
    Lfain,
    /// LFT: feedback temperature (hand-wide, feedback; bh8-262).
    Lft,
}

impl RtFlag {
    /// Every flag.
    pub const ALL: [RtFlag; 10] = [
        RtFlag::Lcv,
        RtFlag::Lcpg,
        RtFlag::Lct,
        RtFlag::Lfv,
        RtFlag::Lfs,
        RtFlag::Lfap,
        RtFlag::Lfdp,
        RtFlag::Lfbp,
        RtFlag::Lfain,
        RtFlag::Lft,
    ];

    /// The parameter name.
    pub fn name(self) -> &'static str {
        match self {
            RtFlag::Lcv => "LCV",
            RtFlag::Lcpg => "LCPG",
            RtFlag::Lct => "LCT",
            RtFlag::Lfv => "LFV",
            RtFlag::Lfs => "LFS",
            RtFlag::Lfap => "LFAP",
            RtFlag::Lfdp => "LFDP",
            RtFlag::Lfbp => "LFBP",
            RtFlag::Lfain => "LFAIN",
            RtFlag::Lft => "LFT",
        }
    }

    /// The flag with this parameter name (ASCII case ignored).
    pub fn from_name(name: &str) -> Option<RtFlag> {
        RtFlag::ALL.into_iter().find(|f| f.name().eq_ignore_ascii_case(name))
    }

    /// The block its field goes in.
    pub fn block(self) -> BlockKind {
        match self {
            RtFlag::Lcv | RtFlag::Lcpg | RtFlag::Lct => BlockKind::Control,
            RtFlag::Lfv | RtFlag::Lfs | RtFlag::Lfap | RtFlag::Lfdp | RtFlag::Lfbp | RtFlag::Lfain | RtFlag::Lft => {
                BlockKind::Feedback
            }
        }
    }

    /// Whether the field is hand-wide (once per block) rather than per motor.
    pub fn is_global(self) -> bool {
        self == RtFlag::Lft
    }
}

/// The wire type of a RealTime field. Two-byte types are big-endian.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FieldType {
    /// One unsigned byte.
    U8,
    /// One two's complement byte.
    I8,
    /// Two bytes, unsigned.
    U16,
    /// Two bytes, two's complement.
    I16,
}

impl FieldType {
    /// The type of this width and signedness, if GCL has one (widths 1 and 2).
    pub fn new(size: usize, signed: bool) -> Option<FieldType> {
        match (size, signed) {
            (1, false) => Some(FieldType::U8),
            (1, true) => Some(FieldType::I8),
            (2, false) => Some(FieldType::U16),
            (2, true) => Some(FieldType::I16),
            _ => None,
        }
    }

    /// Width in bytes.
    pub fn size(self) -> usize {
        match self {
            FieldType::U8 | FieldType::I8 => 1,
            FieldType::U16 | FieldType::I16 => 2,
        }
    }

    /// Whether it is two's complement.
    pub fn signed(self) -> bool {
        matches!(self, FieldType::I8 | FieldType::I16)
    }

    /// The values it can carry.
    pub fn range(self) -> RangeInclusive<i64> {
        match self {
            FieldType::U8 => 0..=i64::from(u8::MAX),
            FieldType::I8 => i64::from(i8::MIN)..=i64::from(i8::MAX),
            FieldType::U16 => 0..=i64::from(u16::MAX),
            FieldType::I16 => i64::from(i16::MIN)..=i64::from(i16::MAX),
        }
    }

    /// The short name: `u8`, `i8`, `u16`, `i16`.
    pub fn name(self) -> &'static str {
        match self {
            FieldType::U8 => "u8",
            FieldType::I8 => "i8",
            FieldType::U16 => "u16",
            FieldType::I16 => "i16",
        }
    }

    /// Reads a value from the first [`FieldType::size`] bytes, or `None` when there are fewer.
    pub fn read(self, bytes: &[u8]) -> Option<i64> {
        Some(match self {
            FieldType::U8 => i64::from(*bytes.first()?),
            FieldType::I8 => i64::from(i8::from_be_bytes([*bytes.first()?])),
            FieldType::U16 => i64::from(u16::from_be_bytes([*bytes.first()?, *bytes.get(1)?])),
            FieldType::I16 => i64::from(i16::from_be_bytes([*bytes.first()?, *bytes.get(1)?])),
        })
    }

    /// Writes a value, clamped into [`FieldType::range`], into the first
    /// [`FieldType::size`] bytes; writes nothing when `out` is shorter.
    pub fn write(self, value: i64, out: &mut [u8]) {
        let range = self.range();
        let v = value.clamp(*range.start(), *range.end());
        match self {
            FieldType::U8 | FieldType::I8 => {
                if let Some(b) = out.first_mut() {
                    *b = v as u8;
                }
            }
            FieldType::U16 | FieldType::I16 => {
                if let Some(b) = out.get_mut(..2) {
                    b.copy_from_slice(&(v as u16).to_be_bytes());
                }
            }
        }
    }
}

impl std::fmt::Display for FieldType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
