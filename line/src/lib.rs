//! # gcl-line: the hand on its transports
//!
//! The lowest layer of the harness: the simulator server (the reference model on a pty, a TCP
//! socket or stdin/stdout, paced at its baud, misbehaving on request), output files written
//! atomically and their digests, recording a session into a transcript, and replaying a
//! transcript against any link. Time, bytes, files and processes live here; the reference
//! model (`gcl-model`) stays pure.
//!
//! It stands on the model, the transcript format and the host library only. It may not
//! depend on the conformance side (`gcl-conformance`), the fuzzers (`gcl-fuzzers`) or the
//! command line (`gcl-harness`): the compiler holds that line, since none of them is a
//! dependency of this crate.

pub mod digest;
pub mod outputs;
pub mod record;
pub mod replay;
pub mod sim;
