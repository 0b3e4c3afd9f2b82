//! Motor sets: which of the four motors (F1, F2, F3, spread) a command names.

use std::fmt;

use serde::{Deserialize, Serialize};

/// A set of motors, 1..=4. Bit `n-1` is motor `n`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct MotorSet(u8);

impl MotorSet {
    /// No motor.
    pub const EMPTY: MotorSet = MotorSet(0);
    /// All four motors.
    pub const ALL: MotorSet = MotorSet(0b1111);
    /// The fingers, F1..F3 (the `G` prefix).
    pub const FINGERS: MotorSet = MotorSet(0b0111);
    /// The spread (the `S` prefix, motor 4).
    pub const SPREAD: MotorSet = MotorSet(0b1000);

    /// The set holding one motor; `None` outside 1..=4.
    pub fn single(motor: u8) -> Option<MotorSet> {
        (1..=4).contains(&motor).then(|| MotorSet(1 << (motor - 1)))
    }

    /// Builds a set from motor numbers, ignoring numbers outside 1..=4.
    pub fn from_motors(motors: impl IntoIterator<Item = u8>) -> MotorSet {
        motors.into_iter().filter_map(MotorSet::single).fold(MotorSet::EMPTY, |a, b| a | b)
    }

    /// From the low four bits.
    pub fn from_bits(bits: u8) -> MotorSet {
        MotorSet(bits & 0b1111)
    }

    /// The low four bits.
    pub fn bits(self) -> u8 {
        self.0
    }

    /// Whether motor `m` is in the set.
    pub fn contains(self, motor: u8) -> bool {
        (1..=4).contains(&motor) && self.0 & (1 << (motor - 1)) != 0
    }

    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Number of motors.
    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// Motor numbers in ascending order.
    pub fn iter(self) -> impl Iterator<Item = u8> {
        (1..=4u8).filter(move |m| self.contains(*m))
    }
}

impl std::ops::BitOr for MotorSet {
    type Output = MotorSet;
    fn bitor(self, rhs: MotorSet) -> MotorSet {
        MotorSet(self.0 | rhs.0)
    }
}

impl std::ops::BitAnd for MotorSet {
    type Output = MotorSet;
    fn bitand(self, rhs: MotorSet) -> MotorSet {
        MotorSet(self.0 & rhs.0)
    }
}

/// Prints the canonical prefix: the motor digits in ascending order (`124`).
impl fmt::Display for MotorSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for m in self.iter() {
            write!(f, "{m}")?;
        }
        Ok(())
    }
}

impl fmt::Debug for MotorSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MotorSet({self})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets() {
        let s = MotorSet::from_motors([4, 1, 2, 9]);
        assert_eq!(s.to_string(), "124");
        assert_eq!(s.len(), 3);
        assert!(s.contains(4) && !s.contains(3) && !s.contains(0));
        assert_eq!(MotorSet::FINGERS | MotorSet::SPREAD, MotorSet::ALL);
    }
}
