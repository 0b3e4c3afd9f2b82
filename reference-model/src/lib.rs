//! # gcl-model: the executable reference model of the Grasper Control Language
//!
//! GCL is the serial protocol of Barrett's BH8-series robot hands. This crate is its
//! reference: the protocol as data ([`spec`]), the grammar of a command line ([`grammar`]),
//! motor sets ([`motor`]), status bits ([`status`]), conformance levels ([`level`]), the parameter store and EEPROM
//! ([`params`]), RealTime block layouts ([`realtime`]) and a whole simulated grasper as a
//! sans-IO state machine ([`device`]).
//!
//! The crate does no I/O and reads no clock: time and bytes go in as arguments, bytes come
//! out. That keeps it deterministic, fuzzable and fast, and lets one model serve the
//! in-process target, every transport, the fuzzers and the generated vectors.
//!
//! ```
//! use std::time::Duration;
//! use gcl_model::{device::Device, spec::Profile};
//!
//! let mut hand = Device::with_profile(Profile::builtin("seed").unwrap());
//! hand.clear_output(); // the power-up banner
//! hand.handle_input(Duration::ZERO, b"FGET DP\r");
//! assert_eq!(hand.take_output(), b"FGET DP\n\r1000 1000 1000 150\n\r=> ");
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing, clippy::panic))]

pub mod device;
pub mod escape;
pub mod grammar;
pub mod level;
pub mod motor;
pub mod params;
pub mod realtime;
pub mod rtflags;
pub mod spec;
pub mod status;

pub use device::{Device, DeviceConfig, Event, Fault, Mode, Scenario};
pub use grammar::{Args, Command, Line, Rejected, parse_line};
pub use level::Level;
pub use motor::{Motor, MotorSet, PerMotor};
pub use realtime::{BlockLayout, ControlHeader, Field, RtLayout};
pub use spec::Profile;
pub use status::StatusBits;
