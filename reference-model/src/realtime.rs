//! RealTime (LOOP) blocks: layouts computed from the flags, checked encode and decode, and
//! the LFDP delta-position arithmetic.
//!
//! A layout is a list of named byte ranges, like a wire header in smoltcp, except that it is
//! computed at LOOP entry from the RealTime flags of the motors in the loop. Two-byte fields
//! are big-endian. This module owns no state of the hand.

use serde::Serialize;

use crate::motor::MotorSet;
use crate::params::ParamStore;
use crate::spec::{BlockKind, Profile, Scope};

/// The feedback header byte: `*`.
pub const FEEDBACK_HEADER: u8 = b'*';

/// A control block header byte from the host.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ControlHeader {
    /// `C`: control data follows; answer with a feedback block.
    DataFeedback,
    /// `c`: control data follows; answer with `*`.
    DataAck,
    /// `A`: no data; answer with a feedback block.
    Feedback,
    /// `a`: no data; answer with `*`.
    Ack,
    /// ^C: leave the loop.
    Abort,
}

impl ControlHeader {
    /// Classifies a header byte; `None` is an invalid header (2048).
    pub fn from_byte(b: u8) -> Option<ControlHeader> {
        match b {
            b'C' => Some(Self::DataFeedback),
            b'c' => Some(Self::DataAck),
            b'A' => Some(Self::Feedback),
            b'a' => Some(Self::Ack),
            3 => Some(Self::Abort),
            _ => None,
        }
    }

    /// The byte.
    pub fn byte(self) -> u8 {
        match self {
            Self::DataFeedback => b'C',
            Self::DataAck => b'c',
            Self::Feedback => b'A',
            Self::Ack => b'a',
            Self::Abort => 3,
        }
    }

    /// Whether control data follows the header.
    pub fn has_data(self) -> bool {
        matches!(self, Self::DataFeedback | Self::DataAck)
    }

    /// Whether the hand answers with a full feedback block (else `*` alone).
    pub fn wants_feedback(self) -> bool {
        matches!(self, Self::DataFeedback | Self::Feedback)
    }
}

/// One named field of a block.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Field {
    /// The motor, 1..=4, or `None` for a hand-wide field (LFT).
    pub motor: Option<u8>,
    /// The flag's name: LCV, LCPG, LCT, LFV, LFS, LFAP, LFDP, LFBP, LFAIN, LFT.
    pub name: String,
    /// Offset from the start of the block; the header is at 0.
    pub offset: usize,
    /// Width in bytes.
    pub size: usize,
    /// Two's complement or unsigned.
    pub signed: bool,
}

impl Field {
    /// Lowest value the field can carry.
    pub fn min(&self) -> i64 {
        if self.signed { -(1i64 << (self.size * 8 - 1)) } else { 0 }
    }

    /// Highest value the field can carry.
    pub fn max(&self) -> i64 {
        if self.signed { (1i64 << (self.size * 8 - 1)) - 1 } else { (1i64 << (self.size * 8)) - 1 }
    }

    /// Reads the field from a whole block (big-endian). The caller has checked the length.
    fn read(&self, block: &[u8]) -> i64 {
        let b = &block[self.offset..self.offset + self.size];
        match (self.size, self.signed) {
            (1, true) => i64::from(b[0] as i8),
            (1, false) => i64::from(b[0]),
            (_, true) => i64::from(i16::from_be_bytes([b[0], b[1]])),
            (_, false) => i64::from(u16::from_be_bytes([b[0], b[1]])),
        }
    }

    /// Writes a value, clamped to what the field can carry.
    fn write(&self, block: &mut [u8], value: i64) {
        let v = value.clamp(self.min(), self.max());
        let b = &mut block[self.offset..self.offset + self.size];
        if self.size == 1 {
            b[0] = v as u8;
        } else {
            b.copy_from_slice(&(v as u16).to_be_bytes());
        }
    }
}

/// The layout of one kind of block for one loop.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct BlockLayout {
    /// Control or feedback.
    pub kind: BlockKind,
    /// Whole block size in bytes, header included.
    pub size: usize,
    /// The fields after the header, in wire order.
    pub fields: Vec<Field>,
}

/// Why bytes are not a block of a layout.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BlockError {
    /// Fewer or more bytes than the layout's size.
    #[error("block is {got} bytes, layout needs {want}")]
    Length {
        /// Bytes given.
        got: usize,
        /// Bytes the layout needs.
        want: usize,
    },
    /// The first byte is not a valid header for this kind of block.
    #[error("bad header byte {0:#04x}")]
    Header(u8),
    /// A value does not fit its field.
    #[error("value {value} does not fit field {name} ({min}..={max})")]
    Range {
        /// The field.
        name: String,
        /// The value.
        value: i64,
        /// Lowest allowed.
        min: i64,
        /// Highest allowed.
        max: i64,
    },
    /// The number of values is not the number of fields.
    #[error("{got} values for {want} fields")]
    Arity {
        /// Values given.
        got: usize,
        /// Fields in the layout.
        want: usize,
    },
}

impl BlockLayout {
    fn build(profile: &Profile, store: &ParamStore, motors: MotorSet, kind: BlockKind) -> BlockLayout {
        let mut fields = Vec::new();
        let mut offset = 1;
        let mut flags: Vec<_> = profile
            .param_ids()
            .filter_map(|id| {
                let p = profile.param(id);
                let rt = p.rt.as_ref()?;
                (rt.block == kind).then_some((id, p, *rt))
            })
            .collect();
        flags.sort_by_key(|(_, _, rt)| rt.order);
        for m in motors.iter() {
            for (id, p, rt) in flags.iter().filter(|(_, p, _)| p.scope == Scope::Motor) {
                if store.get(profile, *id, m) != 0 {
                    fields.push(Field {
                        motor: Some(m),
                        name: p.name.clone(),
                        offset,
                        size: rt.size,
                        signed: rt.signed,
                    });
                    offset += rt.size;
                }
            }
        }
        for (id, p, rt) in flags.iter().filter(|(_, p, _)| p.scope == Scope::Global) {
            if store.get(profile, *id, 1) != 0 {
                fields.push(Field { motor: None, name: p.name.clone(), offset, size: rt.size, signed: rt.signed });
                offset += rt.size;
            }
        }
        BlockLayout { kind, size: offset, fields }
    }

    /// The index of a field by motor and flag name.
    pub fn position(&self, motor: Option<u8>, name: &str) -> Option<usize> {
        self.fields.iter().position(|f| f.motor == motor && f.name == name)
    }

    /// The value of a field in decoded values, by motor and flag name.
    pub fn value_of(&self, values: &[i64], motor: Option<u8>, name: &str) -> Option<i64> {
        self.position(motor, name).and_then(|i| values.get(i).copied())
    }

    /// Size of the data after the header.
    pub fn data_len(&self) -> usize {
        self.size - 1
    }

    /// Encodes a block: the header, then each value in field order. Values must fit.
    pub fn encode(&self, header: u8, values: &[i64], out: &mut Vec<u8>) -> Result<(), BlockError> {
        if values.len() != self.fields.len() {
            return Err(BlockError::Arity { got: values.len(), want: self.fields.len() });
        }
        for (f, v) in self.fields.iter().zip(values) {
            if !(f.min()..=f.max()).contains(v) {
                return Err(BlockError::Range { name: f.name.clone(), value: *v, min: f.min(), max: f.max() });
            }
        }
        self.encode_clamped(header, values, out);
        Ok(())
    }

    /// Encodes a block, clamping each value into its field (what the hand does).
    pub fn encode_clamped(&self, header: u8, values: &[i64], out: &mut Vec<u8>) {
        let start = out.len();
        out.resize(start + self.size, 0);
        let block = &mut out[start..];
        block[0] = header;
        for (f, v) in self.fields.iter().zip(values) {
            f.write(block, *v);
        }
    }

    /// Decodes a whole block, checking its length (and, for feedback, its `*` header).
    /// Returns the header byte and one value per field.
    pub fn decode(&self, block: &[u8]) -> Result<(u8, Vec<i64>), BlockError> {
        let mut values = vec![0; self.fields.len()];
        let h = self.decode_into(block, &mut values)?;
        Ok((h, values))
    }

    /// Decodes into a caller's buffer (no allocation). `values` must hold one slot per field.
    pub fn decode_into(&self, block: &[u8], values: &mut [i64]) -> Result<u8, BlockError> {
        if block.len() != self.size {
            return Err(BlockError::Length { got: block.len(), want: self.size });
        }
        if values.len() != self.fields.len() {
            return Err(BlockError::Arity { got: values.len(), want: self.fields.len() });
        }
        let h = block[0];
        let ok = match self.kind {
            BlockKind::Feedback => h == FEEDBACK_HEADER,
            BlockKind::Control => ControlHeader::from_byte(h).is_some_and(|c| c.has_data()),
        };
        if !ok {
            return Err(BlockError::Header(h));
        }
        for (f, v) in self.fields.iter().zip(values.iter_mut()) {
            *v = f.read(block);
        }
        Ok(h)
    }
}

/// Both layouts of a loop.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RtLayout {
    /// The motors in the loop.
    pub motors: MotorSet,
    /// Host to hand, after a `C` or `c` header.
    pub control: BlockLayout,
    /// Hand to host, after a `C` or `A` header.
    pub feedback: BlockLayout,
}

impl RtLayout {
    /// Computes the layouts from the flags in `store` for the motors in the loop.
    pub fn compute(profile: &Profile, store: &ParamStore, motors: MotorSet) -> RtLayout {
        RtLayout {
            motors,
            control: BlockLayout::build(profile, store, motors, BlockKind::Control),
            feedback: BlockLayout::build(profile, store, motors, BlockKind::Feedback),
        }
    }
}

/// One LFDP step for one motor: the value to send, updating the last reported position.
///
/// `coeff` is LFDPC (0 counts as 1). Division truncates toward zero and the result is
/// clipped to one signed byte. Without `discard` (LFDPD 0) the reported position advances by
/// the sent value × LFDPC, so the clipped rest is carried into later blocks; with `discard`
/// it advances by the unclipped quotient, dropping the rest.
pub fn lfdp_step(reported: &mut i64, present: i64, coeff: i64, discard: bool) -> i8 {
    let c = coeff.max(1);
    let q_raw = (present - *reported) / c;
    let q = q_raw.clamp(-128, 127);
    *reported += if discard { q_raw * c } else { q * c };
    q as i8
}

/// Decodes an LCV datum into a control velocity: the datum × LCVC, scaled by the profile's
/// fraction bits (4.4 fixed point in 4.3x).
pub fn control_velocity(datum: i64, lcvc: i64, fraction_bits: u32) -> f64 {
    (datum * lcvc) as f64 / f64::from(1u32 << fraction_bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The worked example: LFDPC 2, last reported 1500, position jumps to 2000.
    #[test]
    fn lfdp_worked_example_carries() {
        let mut r = 1500;
        let sent: Vec<i8> = (0..3).map(|_| lfdp_step(&mut r, 2000, 2, false)).collect();
        assert_eq!(sent, vec![127, 123, 0]);
        assert_eq!(r, 2000);
        // As bytes on the wire:
        assert_eq!(sent.iter().map(|v| *v as u8).collect::<Vec<_>>(), vec![0x7F, 0x7B, 0x00]);
    }

    #[test]
    fn lfdp_worked_example_discards() {
        let mut r = 1500;
        let sent: Vec<i8> = (0..3).map(|_| lfdp_step(&mut r, 2000, 2, true)).collect();
        assert_eq!(sent, vec![127, 0, 0]);
        // The host that adds sent × LFDPC is stuck at 1754.
        assert_eq!(1500 + sent.iter().map(|v| i64::from(*v) * 2).sum::<i64>(), 1754);
    }

    #[test]
    fn lfdp_negative_and_zero_coefficient() {
        let mut r = 1000;
        assert_eq!(lfdp_step(&mut r, 0, 1, false), -128);
        assert_eq!(r, 872);
        let mut r = 10;
        assert_eq!(lfdp_step(&mut r, 13, 0, false), 3);
    }

    #[test]
    fn lcv_fixed_point() {
        assert_eq!(control_velocity(20, 1, 4), 1.25);
        assert_eq!(control_velocity(-5, 1, 4), -0.3125);
        assert_eq!(control_velocity(55, 2, 0), 110.0);
    }
}
