//! Motors and motor sets: one of the four motors (F1, F2, F3, spread), which of them a
//! command names, and values kept per motor.

use std::fmt;
use std::ops::{Index, IndexMut};

/// One motor of the hand: 1..=3 the fingers F1..F3, 4 the spread. Built only from a number
/// in 1..=4 ([`Motor::new`]), so indexing per-motor values by it cannot go out of bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(transparent)]
pub struct Motor(u8);

impl Motor {
    /// Finger 1.
    pub const F1: Motor = Motor(1);
    /// Finger 2.
    pub const F2: Motor = Motor(2);
    /// Finger 3.
    pub const F3: Motor = Motor(3);
    /// The spread.
    pub const SPREAD: Motor = Motor(4);
    /// The four motors in order.
    pub const ALL: [Motor; 4] = [Motor::F1, Motor::F2, Motor::F3, Motor::SPREAD];

    /// The motor with this number; `None` outside 1..=4.
    pub fn new(number: u8) -> Option<Motor> {
        (1..=4).contains(&number).then_some(Motor(number))
    }

    /// Its number, 1..=4.
    pub fn number(self) -> u8 {
        self.0
    }

    /// This motor's element of a per-motor array.
    pub fn pick<T>(self, values: &[T; 4]) -> &T {
        let [a, b, c, d] = values;
        match self.0 {
            1 => a,
            2 => b,
            3 => c,
            _ => d,
        }
    }

    /// This motor's element of a per-motor array, mutably.
    pub fn pick_mut<T>(self, values: &mut [T; 4]) -> &mut T {
        let [a, b, c, d] = values;
        match self.0 {
            1 => a,
            2 => b,
            3 => c,
            _ => d,
        }
    }
}

impl fmt::Display for Motor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// One value for each of the four motors, indexed by [`Motor`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct PerMotor<T>(pub [T; 4]);

impl<T> PerMotor<T> {
    /// The values with their motors, in motor order.
    pub fn iter(&self) -> impl Iterator<Item = (Motor, &T)> {
        Motor::ALL.into_iter().zip(self.0.iter())
    }

    /// The values, mutably, in motor order.
    pub fn values_mut(&mut self) -> impl Iterator<Item = &mut T> {
        self.0.iter_mut()
    }
}

impl<T> Index<Motor> for PerMotor<T> {
    type Output = T;
    fn index(&self, m: Motor) -> &T {
        m.pick(&self.0)
    }
}

impl<T> IndexMut<Motor> for PerMotor<T> {
    fn index_mut(&mut self, m: Motor) -> &mut T {
        m.pick_mut(&mut self.0)
    }
}

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

    /// The motors in ascending order.
    pub fn motors(self) -> impl Iterator<Item = Motor> {
        Motor::ALL.into_iter().filter(move |m| self.contains(m.0))
    }
}

impl From<Motor> for MotorSet {
    fn from(m: Motor) -> MotorSet {
        MotorSet(1 << (m.0 - 1))
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
        assert_eq!(s.motors().map(Motor::number).collect::<Vec<_>>(), vec![1, 2, 4]);
    }

    #[test]
    fn motors_exist_only_in_one_to_four() {
        assert_eq!(Motor::new(0), None);
        assert_eq!(Motor::new(5), None);
        assert_eq!(Motor::new(4), Some(Motor::SPREAD));
        let mut v = PerMotor([10, 20, 30, 40]);
        v[Motor::F2] += 1;
        assert_eq!(Motor::ALL.map(|m| v[m]), [10, 21, 30, 40]);
    }
}
