//! Fuzz entry points for gcl. Each takes arbitrary bytes and must never panic.
