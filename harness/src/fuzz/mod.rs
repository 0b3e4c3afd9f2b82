//! Fuzzers that check someone else's implementation of GCL against the reference model.
//!
//! [`device`] drives a hand (any `--target`) with generated host actions and judges every
//! answer by the model. The fuzzers never judge by anything but the model and the invariants
//! the replayer already enforces (deadlines, ceilings); they print nothing and own no CLI.

pub mod device;
