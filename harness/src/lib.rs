//! The gcl harness.
