//! # gcl-conformance: the suite, its runner and what it reports
//!
//! The conformance side of the harness: the suite of golden transcripts built from the
//! reference model (`suite`, with the host actions its cases and the fuzzer's are built from,
//! `actions`), the vectors written from it (`vectors`), where a failing replay parts from its
//! golden (`align`) and which clause is at fault (`triage`), pre-flight checks, deadlines and
//! the motion-time probe, the runner (`conform`), certificates (`certify`) and every report
//! writer (`report`: JSON, JUnit, the HTML page).
//!
//! It stands on `gcl-line` (the hand on its transports) and the crates below it. It may not
//! depend on the fuzzers (`gcl-fuzzers`) or the command line (`gcl-harness`): a piece both the
//! runner and a fuzzer need lives here or lower.

// The modules of the layer below, under the names they had in one crate (`crate::sim`, ...).
use gcl_line::{digest, outputs, record, replay};

pub mod actions;
pub mod align;
pub mod certify;
pub mod conform;
pub mod deadline;
pub mod identity;
pub mod motion;
pub mod preflight;
pub mod report;
pub mod suite;
pub mod triage;
pub mod vectors;
