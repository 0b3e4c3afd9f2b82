//! Status bits: the codes a hand sends after `ERR`, as a composable bitflags type.
//!
//! The numbers are the protocol's (powers of two, OR'ed on the wire); the texts come from the
//! profile (through [`StatusTexts`]), so this module owns composition and decomposition only.
//! It is a leaf: it imports nothing else from the crate.

use serde::{Deserialize, Serialize};

/// Where the `ERR n` description of each bit comes from (a profile).
pub trait StatusTexts {
    /// The text of one status bit, if defined.
    fn status_text(&self, bit: u32) -> Option<&str>;
}

impl<T: StatusTexts + ?Sized> StatusTexts for std::sync::Arc<T> {
    fn status_text(&self, bit: u32) -> Option<&str> {
        T::status_text(self, bit)
    }
}

bitflags::bitflags! {
    /// A set of GCL status bits. The wire form is the decimal sum.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord, Serialize, Deserialize)]
    #[serde(transparent)]
    pub struct StatusBits: u32 {
        /// 1: no motor board found (also what T says for an uninitialised motor).
        const NO_MOTOR_BOARD = 1;
        /// 2: no motor found.
        const NO_MOTOR = 2;
        /// 4: motor not initialised.
        const NOT_INITIALIZED = 4;
        /// 8: not used.
        const UNUSED_8 = 8;
        /// 16: could not reach position (outside MPE).
        const MISSED_POSITION = 16;
        /// 32: unknown command.
        const UNKNOWN_COMMAND = 32;
        /// 64: unknown parameter name.
        const UNKNOWN_PARAMETER = 64;
        /// 128: invalid value.
        const INVALID_VALUE = 128;
        /// 256: tried to write a read-only parameter.
        const READ_ONLY = 256;
        /// 512: timeout (seed) or not used (bh8-262).
        const TIMEOUT = 512;
        /// 1024: too many arguments.
        const TOO_MANY_ARGUMENTS = 1024;
        /// 2048: invalid RealTime control block header.
        const BAD_HEADER = 2048;
        /// 4096: command can't have a motor prefix.
        const PREFIX_NOT_ALLOWED = 4096;
        /// 8192: overtemperature fault tripped (bh8-262).
        const OVERTEMPERATURE = 8192;
        /// 16384: ^C abort received (bh8-262).
        const ABORTED = 16384;
    }
}

impl StatusBits {
    /// The wire number (0 for no status).
    pub fn code(self) -> u32 {
        self.bits()
    }

    /// Decodes a wire number. Bits the protocol does not define are an error.
    pub fn from_code(code: u32) -> Result<Self, UnknownStatusBits> {
        Self::from_bits(code).ok_or(UnknownStatusBits(code & !Self::all().bits()))
    }

    /// The `ERR n` description lines for each set bit, as the profile words them:
    /// `bit: text`. Bits the profile does not define are skipped.
    pub fn describe<T: StatusTexts + ?Sized>(self, texts: &T) -> Vec<String> {
        self.iter().filter_map(|b| texts.status_text(b.bits()).map(|t| format!("{}: {}", b.bits(), t))).collect()
    }
}

/// A status number carried bits that GCL does not define.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("status carries undefined bits {0:#x}")]
pub struct UnknownStatusBits(pub u32);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn composes_and_decomposes() {
        let s = StatusBits::from_code(3).unwrap();
        assert_eq!(s, StatusBits::NO_MOTOR_BOARD | StatusBits::NO_MOTOR);
        assert_eq!(s.iter().map(|b| b.code()).collect::<Vec<_>>(), vec![1, 2]);
        assert_eq!((StatusBits::PREFIX_NOT_ALLOWED | StatusBits::TOO_MANY_ARGUMENTS).code(), 5120);
        assert_eq!(StatusBits::from_code(32768), Err(UnknownStatusBits(32768)));
    }
}
