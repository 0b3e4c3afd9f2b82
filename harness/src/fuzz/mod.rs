//! Fuzzers that drive whole programs against the model: `host` puts a misbehaving simulated
//! hand in front of a host program.

pub mod host;
