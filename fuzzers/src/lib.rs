//! # gcl-fuzzers: fuzz device, fuzz host, and the host check
//!
//! The fuzzers of the harness: `fuzz device` (generated cases against a hand, findings
//! minimized and named by their cause), `fuzz host` (a simulated hand that misbehaves on
//! purpose, host crashes and hangs caught and signed), shards and their merges, and the host
//! check (`host_check`, `host_check_serve`: one graded session of a host), built on the host
//! fuzzer's sessions.
//!
//! It stands on `gcl-conformance` and `gcl-line`. It may not depend on the command line
//! (`gcl-harness`); nothing below it may depend on it.

// The modules of the layers below, under the names they had in one crate (`crate::suite`, ...).
use gcl_conformance::{align, conform, deadline, motion, preflight, report, suite};
use gcl_line::{digest, outputs, replay, sim};

pub mod fuzz;
pub mod host_check;
pub mod host_check_serve;
