//! The simulated grasper on real transports: `gcl sim`.
//!
//! One [`Engine`] owns the reference model and everything around it that is not a transport:
//! simulated or wall-clock time, output pacing at a baud rate, the EEPROM file and the trace.
//! The transports ([`pty`], [`tcp`], [`stdio`]) only move bytes between a file descriptor and
//! the engine, and wait (with `ppoll`) for input, for the engine's next deadline, or for a stop
//! request. Nothing a client sends can take the hand down: bad bytes go to the model, which
//! answers them like a hand would; a client that goes away leaves the hand as it was.
//!
//! The module never reads the terminal, never installs signal handlers and never exits the
//! process; `gcl sim` (in `cli/sim.rs`) does those.
//!
//! The engine runs on one of two clocks: `fast` drives a `SimLink`, `real` follows the wall clock;
//! the pace follows the hand's BAUD, `--baud`, or nothing. Past 64 KiB of output the host has not
//! taken (`OUT_CAP`) it stops taking host bytes and never drops them. Stale EEPROM temporaries are
//! removed at start; the trace is flushed per line. `host_writes` is the crate's one module with
//! `unsafe`, for system calls no safe wrapper we use has (also the pty master's packet mode).

mod eeprom;
mod engine;
pub mod host_writes;
pub mod misbehave;
pub mod pty;
mod scenario;
pub mod stdio;
pub mod tcp;
mod trace;
mod wait;

use std::path::PathBuf;
use std::sync::Arc;

use gcl_model::{Fault, Profile, Scenario};

pub use eeprom::EepromFile;
pub use engine::{Engine, IN_CAP, OUT_CAP};
pub use scenario::{SCENARIO_EXAMPLE, check_scenario, parse_scenario};
pub use trace::{Direction, Trace};
pub use wait::{StopHandle, StopSignal, stop_pair};

/// How simulated time relates to the wall clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TimeMode {
    /// Simulated time advances by the wire time of every byte exchanged (at the hand's BAUD)
    /// and by the duration of each motion, which completes as fast as the CPU allows. The same
    /// bytes always give the same answers, whatever the host's speed.
    #[default]
    Fast,
    /// Simulated time is the wall clock since start: a motion takes as long as on a hand and a
    /// ^C sent mid-motion stops it.
    Real,
}

impl TimeMode {
    /// `fast` or `real`.
    pub fn name(self) -> &'static str {
        match self {
            TimeMode::Fast => "fast",
            TimeMode::Real => "real",
        }
    }
}

/// How fast bytes cross the simulated line (8N1: 10 bits a byte), in both directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pace {
    /// At the hand's BAUD parameter (9600 at the factory), which `PSET BAUD`/`FSET BAUD`
    /// changes after the answer to the command that sets it.
    #[default]
    Hand,
    /// At this rate, whatever the hand's BAUD.
    Fixed(u32),
    /// As fast as the transport goes (an opt-in speed-up; no hand does this).
    Unpaced,
}

impl Pace {
    /// How a start line says it: "paced at the hand's BAUD", "paced at 38400 baud" or
    /// "unpaced".
    pub fn phrase(&self) -> String {
        match self {
            Pace::Unpaced => self.to_string(),
            p => format!("paced at {p}"),
        }
    }
}

impl std::fmt::Display for Pace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Pace::Hand => f.write_str("the hand's BAUD"),
            Pace::Fixed(b) => write!(f, "{b} baud"),
            Pace::Unpaced => f.write_str("unpaced"),
        }
    }
}

/// Everything a simulated hand on a transport is built from.
#[derive(Debug, Clone)]
pub struct SimOptions {
    /// The profile the hand runs.
    pub profile: Arc<Profile>,
    /// Seed of the model's noise.
    pub seed: u64,
    /// The world around the hand.
    pub scenario: Scenario,
    /// Deliberate firmware bugs.
    pub faults: Vec<Fault>,
    /// Fast or real time.
    pub time: TimeMode,
    /// How fast bytes cross the line, in both directions.
    pub pace: Pace,
    /// Where the EEPROM lives between runs (JSON of `NvMemory`).
    pub eeprom: Option<PathBuf>,
    /// Where to log both directions.
    pub trace: Option<PathBuf>,
}

impl SimOptions {
    /// Default options for a profile: seed 0, default scenario, fast time, unpaced, no files
    /// (what a test or an in-process tool wants; `gcl sim --pty`/`--tcp` default to real
    /// time paced at the hand's BAUD).
    pub fn new(profile: Arc<Profile>) -> SimOptions {
        SimOptions {
            profile,
            seed: 0,
            scenario: Scenario::default(),
            faults: Vec::new(),
            time: TimeMode::Fast,
            pace: Pace::Unpaced,
            eeprom: None,
            trace: None,
        }
    }
}

/// Why the simulated hand could not start or had to stop.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The EEPROM file cannot be read, parsed or written.
    #[error("EEPROM file {path}: {reason}")]
    Eeprom {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// The trace file cannot be created or written.
    #[error("trace file {path}: {reason}")]
    Trace {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// The scenario text is not a valid scenario.
    #[error("scenario: {0}")]
    Scenario(String),
    /// A pseudo-terminal could not be created or linked.
    #[error("pty: {0}")]
    Pty(String),
    /// The TCP address is not acceptable or cannot be bound.
    #[error("cannot listen on {addr}: {reason}")]
    Listen {
        /// The address asked for.
        addr: String,
        /// Why not.
        reason: String,
    },
    /// An I/O error on the transport that the hand cannot recover from.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: &'static str,
        /// The error.
        #[source]
        source: std::io::Error,
    },
}

impl SimError {
    fn io(context: &'static str, source: impl Into<std::io::Error>) -> SimError {
        SimError::Io { context, source: source.into() }
    }
}
