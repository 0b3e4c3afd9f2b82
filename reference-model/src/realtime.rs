//! RealTime (LOOP) blocks: the closed set of RealTime flags and field types (from
//! [`crate::rtflags`], which the profile loader stands on), layouts computed from the flags, typed control and feedback values ([`Control`], [`Feedback`]) with checked
//! `parse` and `emit`, and the LFDP delta-position arithmetic.
//!
//! A layout is a list of named byte ranges, like a wire header in smoltcp, except that it is
//! computed at LOOP entry from the RealTime flags of the motors in the loop. Two-byte fields
//! are big-endian. Layouts are built only by [`RtLayout::compute`], so every field lies inside
//! its block and decoding cannot go out of bounds. This module owns no state of the hand.

use serde::Serialize;

use crate::motor::{Motor, MotorSet};
use crate::params::ParamStore;
use crate::rtflags::BlockKind;
pub use crate::rtflags::{FieldType, RtFlag};
use crate::spec::Profile;

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

/// One field of a block: a flag of one motor (or of the hand), at an offset, of a type.
/// Built only by the layout computation, so it always lies inside its block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    motor: Option<u8>,
    flag: RtFlag,
    offset: usize,
    ty: FieldType,
}

impl Field {
    /// The motor, 1..=4, or `None` for a hand-wide field (LFT).
    pub fn motor(&self) -> Option<u8> {
        self.motor
    }

    /// The flag that adds this field.
    pub fn flag(&self) -> RtFlag {
        self.flag
    }

    /// The flag's name: LCV, LCPG, LCT, LFV, LFS, LFAP, LFDP, LFBP, LFAIN, LFT.
    pub fn name(&self) -> &'static str {
        self.flag.name()
    }

    /// Offset from the start of the block; the header is at 0.
    pub fn offset(&self) -> usize {
        self.offset
    }

    /// The wire type.
    pub fn ty(&self) -> FieldType {
        self.ty
    }

    /// Width in bytes.
    pub fn size(&self) -> usize {
        self.ty.size()
    }

    /// Two's complement or unsigned.
    pub fn signed(&self) -> bool {
        self.ty.signed()
    }

    /// Lowest value the field can carry.
    pub fn min(&self) -> i64 {
        *self.ty.range().start()
    }

    /// Highest value the field can carry.
    pub fn max(&self) -> i64 {
        *self.ty.range().end()
    }

    /// Reads the field from a whole block (big-endian); 0 if the block is too short, which a
    /// length-checked block never is.
    fn read(&self, block: &[u8]) -> i64 {
        block.get(self.offset..).and_then(|b| self.ty.read(b)).unwrap_or(0)
    }

    /// Writes a value, clamped to what the field can carry.
    fn write(&self, block: &mut [u8], value: i64) {
        if let Some(b) = block.get_mut(self.offset..) {
            self.ty.write(value, b);
        }
    }
}

impl Serialize for Field {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("Field", 5)?;
        st.serialize_field("motor", &self.motor)?;
        st.serialize_field("name", self.name())?;
        st.serialize_field("offset", &self.offset)?;
        st.serialize_field("size", &self.size())?;
        st.serialize_field("signed", &self.signed())?;
        st.end()
    }
}

/// The layout of one kind of block for one loop.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct BlockLayout {
    kind: BlockKind,
    size: usize,
    fields: Vec<Field>,
}

/// Why bytes or values are not a block of a layout.
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
    /// A typed block lacks the value of a field the layout has.
    #[error("no value for field {name} of motor {motor:?}")]
    Missing {
        /// The field.
        name: &'static str,
        /// Its motor (`None`: hand-wide).
        motor: Option<u8>,
    },
    /// A typed block of one kind was given the layout of the other.
    #[error("a {got:?} block does not fit a {want:?} layout")]
    Kind {
        /// The block's kind.
        got: BlockKind,
        /// The layout's kind.
        want: BlockKind,
    },
}

impl BlockLayout {
    fn build(profile: &Profile, store: &ParamStore, motors: MotorSet, kind: BlockKind) -> BlockLayout {
        let mut fields = Vec::new();
        let mut offset = 1;
        let slots = || profile.rt_slots().iter().filter(|s| s.flag.block() == kind);
        for m in motors.iter() {
            for s in slots().filter(|s| !s.flag.is_global()) {
                if store.get(profile, s.param, m) != 0 {
                    fields.push(Field { motor: Some(m), flag: s.flag, offset, ty: s.ty });
                    offset += s.ty.size();
                }
            }
        }
        for s in slots().filter(|s| s.flag.is_global()) {
            if store.get(profile, s.param, 1) != 0 {
                fields.push(Field { motor: None, flag: s.flag, offset, ty: s.ty });
                offset += s.ty.size();
            }
        }
        BlockLayout { kind, size: offset, fields }
    }

    /// Control or feedback.
    pub fn kind(&self) -> BlockKind {
        self.kind
    }

    /// Whole block size in bytes, header included.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The fields after the header, in wire order.
    pub fn fields(&self) -> &[Field] {
        &self.fields
    }

    /// The index of a field by motor and flag name.
    pub fn position(&self, motor: Option<u8>, name: &str) -> Option<usize> {
        self.fields.iter().position(|f| f.motor == motor && f.name() == name)
    }

    /// The index of a field by motor and flag.
    pub fn position_of(&self, motor: Option<u8>, flag: RtFlag) -> Option<usize> {
        self.fields.iter().position(|f| f.motor == motor && f.flag == flag)
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
            if !f.ty.range().contains(v) {
                return Err(BlockError::Range { name: f.name().to_string(), value: *v, min: f.min(), max: f.max() });
            }
        }
        self.encode_clamped(header, values, out);
        Ok(())
    }

    /// Encodes a block, clamping each value into its field (what the hand does).
    pub fn encode_clamped(&self, header: u8, values: &[i64], out: &mut Vec<u8>) {
        let start = out.len();
        out.resize(start + self.size, 0);
        let block = out.get_mut(start..).unwrap_or_default();
        if let Some(h) = block.first_mut() {
            *h = header;
        }
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

    /// Checks a whole block's length, then its header; returns the header byte.
    fn check(&self, block: &[u8]) -> Result<u8, BlockError> {
        if block.len() != self.size {
            return Err(BlockError::Length { got: block.len(), want: self.size });
        }
        self.check_header(block.first().copied().unwrap_or_default())
    }

    fn check_header(&self, h: u8) -> Result<u8, BlockError> {
        let ok = match self.kind {
            BlockKind::Feedback => h == FEEDBACK_HEADER,
            BlockKind::Control => ControlHeader::from_byte(h).is_some_and(|c| c.has_data()),
        };
        if ok { Ok(h) } else { Err(BlockError::Header(h)) }
    }

    /// Decodes into a caller's buffer (no allocation). `values` must hold one slot per field.
    pub fn decode_into(&self, block: &[u8], values: &mut [i64]) -> Result<u8, BlockError> {
        if block.len() != self.size {
            return Err(BlockError::Length { got: block.len(), want: self.size });
        }
        if values.len() != self.fields.len() {
            return Err(BlockError::Arity { got: values.len(), want: self.fields.len() });
        }
        let h = self.check_header(block.first().copied().unwrap_or_default())?;
        for (f, v) in self.fields.iter().zip(values.iter_mut()) {
            *v = f.read(block);
        }
        Ok(h)
    }
}

/// Both layouts of a loop. Built only by [`RtLayout::compute`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RtLayout {
    motors: MotorSet,
    control: BlockLayout,
    feedback: BlockLayout,
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

    /// The motors in the loop.
    pub fn motors(&self) -> MotorSet {
        self.motors
    }

    /// Host to hand, after a `C` or `c` header.
    pub fn control(&self) -> &BlockLayout {
        &self.control
    }

    /// Hand to host, after a `C` or `A` header.
    pub fn feedback(&self) -> &BlockLayout {
        &self.feedback
    }
}

/// The control values for one motor; `None` where the layout has no such field.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MotorControl {
    /// LCV: the velocity datum.
    pub velocity: Option<i64>,
    /// LCPG: the proportional gain.
    pub gain: Option<i64>,
    /// LCT: the torque datum.
    pub torque: Option<i64>,
}

/// The feedback values for one motor; `None` where the layout has no such field.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MotorFeedback {
    /// LFV: velocity.
    pub velocity: Option<i64>,
    /// LFS: strain.
    pub strain: Option<i64>,
    /// LFAP: absolute position.
    pub absolute_position: Option<i64>,
    /// LFDP: delta position since the last report.
    pub delta_position: Option<i64>,
    /// LFBP: breakaway position.
    pub breakaway_position: Option<i64>,
    /// LFAIN: analog input.
    pub analog_input: Option<i64>,
}

/// A typed control block (host to hand): its header and the values of each motor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Control {
    /// `C` or `c` (the headers that carry data).
    pub header: ControlHeader,
    motors: [MotorControl; 4],
}

/// A typed feedback block (hand to host): the values of each motor and of the hand.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Feedback {
    motors: [MotorFeedback; 4],
    /// LFT: the hand's temperature.
    pub temperature: Option<i64>,
}

/// The values of a typed block by field: shared by [`Control`] and [`Feedback`].
trait Repr {
    const KIND: BlockKind;
    fn slot(&mut self, motor: Option<u8>, flag: RtFlag) -> Option<&mut Option<i64>>;
    fn peek(&self, motor: Option<u8>, flag: RtFlag) -> Option<i64>;

    fn value(&self, f: &Field) -> Option<i64> {
        self.peek(f.motor, f.flag)
    }

    fn fill(&mut self, layout: &BlockLayout, block: &[u8]) -> Result<u8, BlockError> {
        if layout.kind != Self::KIND {
            return Err(BlockError::Kind { got: Self::KIND, want: layout.kind });
        }
        let h = layout.check(block)?;
        for f in &layout.fields {
            if let Some(v) = self.slot(f.motor, f.flag) {
                *v = Some(f.read(block));
            }
        }
        Ok(h)
    }

    /// Checked: every field has a value that fits.
    fn emit_checked(&self, layout: &BlockLayout, header: u8, out: &mut Vec<u8>) -> Result<(), BlockError> {
        if layout.kind != Self::KIND {
            return Err(BlockError::Kind { got: Self::KIND, want: layout.kind });
        }
        layout.check_header(header)?;
        let start = out.len();
        out.resize(start + layout.size, 0);
        let block = out.get_mut(start..).unwrap_or_default();
        if let Some(b) = block.first_mut() {
            *b = header;
        }
        for f in &layout.fields {
            let v = self.value(f);
            let err = match v {
                None => Some(BlockError::Missing { name: f.name(), motor: f.motor }),
                Some(v) if !f.ty.range().contains(&v) => {
                    Some(BlockError::Range { name: f.name().to_string(), value: v, min: f.min(), max: f.max() })
                }
                Some(v) => {
                    f.write(block, v);
                    None
                }
            };
            if let Some(e) = err {
                out.truncate(start);
                return Err(e);
            }
        }
        Ok(())
    }
}

impl Repr for Control {
    const KIND: BlockKind = BlockKind::Control;
    fn slot(&mut self, motor: Option<u8>, flag: RtFlag) -> Option<&mut Option<i64>> {
        let m = self.motor_mut(motor?)?;
        match flag {
            RtFlag::Lcv => Some(&mut m.velocity),
            RtFlag::Lcpg => Some(&mut m.gain),
            RtFlag::Lct => Some(&mut m.torque),
            RtFlag::Lfv | RtFlag::Lfs | RtFlag::Lfap | RtFlag::Lfdp | RtFlag::Lfbp | RtFlag::Lfain | RtFlag::Lft => {
                None
            }
        }
    }
    fn peek(&self, motor: Option<u8>, flag: RtFlag) -> Option<i64> {
        let m = Motor::new(motor?)?.pick(&self.motors);
        match flag {
            RtFlag::Lcv => m.velocity,
            RtFlag::Lcpg => m.gain,
            RtFlag::Lct => m.torque,
            RtFlag::Lfv | RtFlag::Lfs | RtFlag::Lfap | RtFlag::Lfdp | RtFlag::Lfbp | RtFlag::Lfain | RtFlag::Lft => {
                None
            }
        }
    }
}

impl Repr for Feedback {
    const KIND: BlockKind = BlockKind::Feedback;
    fn slot(&mut self, motor: Option<u8>, flag: RtFlag) -> Option<&mut Option<i64>> {
        if flag == RtFlag::Lft {
            return motor.is_none().then_some(&mut self.temperature);
        }
        let m = self.motor_mut(motor?)?;
        match flag {
            RtFlag::Lfv => Some(&mut m.velocity),
            RtFlag::Lfs => Some(&mut m.strain),
            RtFlag::Lfap => Some(&mut m.absolute_position),
            RtFlag::Lfdp => Some(&mut m.delta_position),
            RtFlag::Lfbp => Some(&mut m.breakaway_position),
            RtFlag::Lfain => Some(&mut m.analog_input),
            RtFlag::Lcv | RtFlag::Lcpg | RtFlag::Lct | RtFlag::Lft => None,
        }
    }
    fn peek(&self, motor: Option<u8>, flag: RtFlag) -> Option<i64> {
        if flag == RtFlag::Lft {
            return if motor.is_none() { self.temperature } else { None };
        }
        let m = Motor::new(motor?)?.pick(&self.motors);
        match flag {
            RtFlag::Lfv => m.velocity,
            RtFlag::Lfs => m.strain,
            RtFlag::Lfap => m.absolute_position,
            RtFlag::Lfdp => m.delta_position,
            RtFlag::Lfbp => m.breakaway_position,
            RtFlag::Lfain => m.analog_input,
            RtFlag::Lcv | RtFlag::Lcpg | RtFlag::Lct | RtFlag::Lft => None,
        }
    }
}

impl Control {
    /// A block with this header and no values yet.
    pub fn new(header: ControlHeader) -> Control {
        Control { header, motors: [MotorControl::default(); 4] }
    }

    /// A block with this header and every field of `layout` set to 0: what a host sends
    /// before it has values of its own.
    pub fn zeroed(header: ControlHeader, layout: &BlockLayout) -> Control {
        let mut control = Control::new(header);
        for f in layout.fields() {
            control.set(f, 0);
        }
        control
    }

    /// Parses a whole control block of `layout` (length and header checked).
    pub fn parse(layout: &BlockLayout, block: &[u8]) -> Result<Control, BlockError> {
        let mut c = Control::new(ControlHeader::DataFeedback);
        let h = c.fill(layout, block)?;
        c.header = ControlHeader::from_byte(h).ok_or(BlockError::Header(h))?;
        Ok(c)
    }

    /// The values of motor `m` (1..=4; none for another number).
    pub fn motor(&self, m: u8) -> MotorControl {
        Motor::new(m).map(|m| *m.pick(&self.motors)).unwrap_or_default()
    }

    /// The values of motor `m` to fill in, or `None` outside 1..=4.
    pub fn motor_mut(&mut self, m: u8) -> Option<&mut MotorControl> {
        Motor::new(m).map(|m| m.pick_mut(&mut self.motors))
    }

    /// The value of one field of a layout, if this block has it.
    pub fn get(&self, field: &Field) -> Option<i64> {
        self.value(field)
    }

    /// Sets the value of one field of a layout (a feedback field is ignored).
    pub fn set(&mut self, field: &Field, value: i64) {
        if let Some(v) = self.slot(field.motor, field.flag) {
            *v = Some(value);
        }
    }

    /// Appends the block: the header, then every field of `layout`, which must each have a
    /// value that fits.
    pub fn emit(&self, layout: &BlockLayout, out: &mut Vec<u8>) -> Result<(), BlockError> {
        self.emit_checked(layout, self.header.byte(), out)
    }
}

impl Feedback {
    /// Parses a whole feedback block of `layout` (length and `*` header checked).
    pub fn parse(layout: &BlockLayout, block: &[u8]) -> Result<Feedback, BlockError> {
        let mut f = Feedback::default();
        f.fill(layout, block)?;
        Ok(f)
    }

    /// The values of motor `m` (1..=4; none for another number).
    pub fn motor(&self, m: u8) -> MotorFeedback {
        Motor::new(m).map(|m| *m.pick(&self.motors)).unwrap_or_default()
    }

    /// The values of motor `m` to fill in, or `None` outside 1..=4.
    pub fn motor_mut(&mut self, m: u8) -> Option<&mut MotorFeedback> {
        Motor::new(m).map(|m| m.pick_mut(&mut self.motors))
    }

    /// The value of one field of a layout, if this block has it.
    pub fn get(&self, field: &Field) -> Option<i64> {
        self.value(field)
    }

    /// The values in the wire order of `layout` (0 for a field this block lacks).
    pub fn values(&self, layout: &BlockLayout) -> Vec<i64> {
        layout.fields.iter().map(|f| self.value(f).unwrap_or(0)).collect()
    }

    /// Sets the value of one field of a layout (a control field is ignored).
    pub fn set(&mut self, field: &Field, value: i64) {
        if let Some(v) = self.slot(field.motor, field.flag) {
            *v = Some(value);
        }
    }

    /// Appends the block: `*`, then every field of `layout`, which must each have a value
    /// that fits.
    pub fn emit(&self, layout: &BlockLayout, out: &mut Vec<u8>) -> Result<(), BlockError> {
        self.emit_checked(layout, FEEDBACK_HEADER, out)
    }

    /// Appends the block as a hand sends it: each value clamped into its field, a missing
    /// value sent as 0.
    pub fn emit_clamped(&self, layout: &BlockLayout, out: &mut Vec<u8>) {
        let start = out.len();
        out.resize(start + layout.size, 0);
        let block = out.get_mut(start..).unwrap_or_default();
        if let Some(b) = block.first_mut() {
            *b = FEEDBACK_HEADER;
        }
        for f in &layout.fields {
            f.write(block, self.value(f).unwrap_or(0));
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

    /// bh8-262 with LCV and LCPG, LFS and LFAP on for F1 and F2, and LFT on.
    fn layout() -> RtLayout {
        let p = Profile::builtin("bh8-262").unwrap();
        let mut store = ParamStore::defaults(&p);
        for name in ["LCV", "LCPG", "LFS", "LFAP", "LFV", "LFDP", "LFT"] {
            let on = i64::from(["LCV", "LCPG", "LFS", "LFAP", "LFT"].contains(&name));
            store.set_unchecked(&p, p.param_id(name).unwrap(), MotorSet::ALL, on);
        }
        RtLayout::compute(&p, &store, MotorSet::from_motors([1, 2]))
    }

    #[test]
    fn field_types_read_write_and_clamp_big_endian() {
        let mut b = [0u8; 2];
        FieldType::I16.write(-2, &mut b);
        assert_eq!(b, [0xFF, 0xFE]);
        assert_eq!(FieldType::I16.read(&b), Some(-2));
        assert_eq!(FieldType::U16.read(&b), Some(65534));
        FieldType::U8.write(300, &mut b);
        assert_eq!(b[0], 255);
        FieldType::I8.write(-300, &mut b);
        assert_eq!(FieldType::I8.read(&b), Some(-128));
        assert_eq!(FieldType::U16.read(&[1]), None, "one byte is not a u16");
        assert_eq!(FieldType::new(3, false), None);
        assert_eq!(FieldType::I8.range(), -128..=127);
    }

    #[test]
    fn feedback_parses_and_emits_per_motor() {
        let l = layout();
        // Per motor LFS (u8) then LFAP (u16), then LFT (i8 in 4.4).
        assert_eq!(l.feedback().size(), 1 + 2 * 3 + 1);
        let bytes = [b'*', 40, 0x13, 0x88, 41, 0x00, 0x10, 0xFD];
        let fb = Feedback::parse(l.feedback(), &bytes).unwrap();
        assert_eq!(fb.motor(1).strain, Some(40));
        assert_eq!(fb.motor(1).absolute_position, Some(5000));
        assert_eq!(fb.motor(2).absolute_position, Some(16));
        assert_eq!(fb.motor(2).velocity, None, "LFV is off");
        assert_eq!(fb.motor(3), MotorFeedback::default(), "F3 is not in the loop");
        assert_eq!(fb.motor(9), MotorFeedback::default());
        assert_eq!(fb.temperature, Some(-3));
        let mut out = Vec::new();
        fb.emit(l.feedback(), &mut out).unwrap();
        assert_eq!(out, bytes);
        assert_eq!(Feedback::parse(l.feedback(), &bytes[..7]), Err(BlockError::Length { got: 7, want: 8 }));
        let mut bad = bytes;
        bad[0] = b'C';
        assert_eq!(Feedback::parse(l.feedback(), &bad), Err(BlockError::Header(b'C')));
        assert_eq!(
            Feedback::parse(l.control(), &bytes),
            Err(BlockError::Kind { got: BlockKind::Feedback, want: BlockKind::Control })
        );
    }

    #[test]
    fn feedback_emit_checks_what_the_hand_clamps() {
        let l = layout();
        let mut fb = Feedback::parse(l.feedback(), &[b'*', 0, 0, 0, 0, 0, 0, 0]).unwrap();
        if let Some(m) = fb.motor_mut(1) {
            m.strain = Some(256);
        }
        let mut out = vec![7];
        assert!(matches!(fb.emit(l.feedback(), &mut out), Err(BlockError::Range { value: 256, .. })));
        assert_eq!(out, [7], "a refused block leaves the buffer as it was");
        fb.emit_clamped(l.feedback(), &mut out);
        assert_eq!(out, [7, b'*', 255, 0, 0, 0, 0, 0, 0]);
        if let Some(m) = fb.motor_mut(1) {
            m.strain = Some(0);
        }
        if let Some(m) = fb.motor_mut(2) {
            m.strain = None;
        }
        assert_eq!(fb.emit(l.feedback(), &mut Vec::new()), Err(BlockError::Missing { name: "LFS", motor: Some(2) }));
    }

    #[test]
    fn control_parses_its_header_and_values() {
        let l = layout();
        let bytes = [b'c', 0xF8, 10, 8, 0];
        let c = Control::parse(l.control(), &bytes).unwrap();
        assert_eq!(c.header, ControlHeader::DataAck);
        assert_eq!(c.motor(1), MotorControl { velocity: Some(-8), gain: Some(10), torque: None });
        assert_eq!(c.motor(2).velocity, Some(8));
        let mut out = Vec::new();
        c.emit(l.control(), &mut out).unwrap();
        assert_eq!(out, bytes);
        assert_eq!(Control::parse(l.control(), &[b'A', 0, 0, 0, 0]), Err(BlockError::Header(b'A')));
        let mut no_data = c;
        no_data.header = ControlHeader::Feedback;
        assert_eq!(no_data.emit(l.control(), &mut Vec::new()), Err(BlockError::Header(b'A')));
    }

    #[test]
    fn a_zeroed_control_fills_every_field_of_its_layout() {
        let l = layout();
        let mut out = Vec::new();
        Control::zeroed(ControlHeader::DataAck, l.control()).emit(l.control(), &mut out).unwrap();
        assert_eq!(out, [b'c', 0, 0, 0, 0]);
        // A bare `new` has no values, so it does not make a block of that layout.
        assert!(Control::new(ControlHeader::DataAck).emit(l.control(), &mut Vec::new()).is_err());
    }

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
