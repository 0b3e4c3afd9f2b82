//! Fuzzers that check someone else's implementation of GCL against the reference model.
//!
//! [`device`] drives a hand (any `--target`) with generated host actions and judges every
//! answer by the model. [`host`] puts a misbehaving simulated hand in front of a host program
//! and catches its crashes, hangs and protocol violations. The fuzzers print nothing and own no
//! CLI.

pub mod device;
pub mod host;
