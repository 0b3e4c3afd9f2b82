//! Fuzzers that check someone else's implementation of GCL against the reference model.
//!
//! [`device`] drives a hand (any `--target`) with generated host actions and judges every
//! answer by the model. [`host`] puts a misbehaving simulated hand in front of a host program
//! and catches its crashes, hangs and protocol violations. [`shard`] slices a campaign of
//! either over machines and [`merge`] folds the slices' outputs back into one. The fuzzers
//! print nothing and own no CLI.

pub mod device;
pub mod host;
pub mod merge;
pub mod shard;
