//! Links to hands outside this process: a serial port or pty ([`serial`]), a TCP server
//! ([`tcp`]), a child process on stdin/stdout ([`exec`]). Each honours [`crate::Link::recv`]'s
//! timeout and reports a vanished hand as [`crate::LinkError::Disconnected`].

pub mod exec;
pub mod serial;
pub mod tcp;

pub use exec::{ExecLink, StderrMode};
pub use serial::SerialLink;
pub use tcp::TcpLink;

use std::time::Duration;

/// The smallest wait a link asks the operating system for (a zero timeout means "only what is
/// already there").
pub(crate) const MIN_WAIT: Duration = Duration::from_micros(1);
