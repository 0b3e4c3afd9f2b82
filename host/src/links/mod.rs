//! Links to hands outside this process: a serial port or pty ([`serial`]), a TCP server
//! ([`tcp`]), a child process on stdin/stdout ([`exec`]). Each honours [`crate::Link::recv`]'s
//! timeout and reports a vanished hand as [`crate::LinkError::Disconnected`].
//!
//! `SerialLink` uses the serialport crate and holds the port exclusively with `flock` and
//! `TIOCEXCL`.

pub mod exec;
pub mod follow;
pub mod serial;
pub mod tcp;

pub use exec::{ExecLink, StderrMode};
pub use follow::RateFollowingLink;
pub use serial::SerialLink;
pub use tcp::TcpLink;

use std::time::Duration;

/// The smallest wait a link asks the operating system for (a zero timeout means "only what is
/// already there").
pub(crate) const MIN_WAIT: Duration = Duration::from_micros(1);

/// Turns one read's result into what [`Link::recv`](crate::Link::recv) returns: the bytes
/// appended to `buf`; 0 when the wait timed out or was interrupted; `Disconnected` at end of
/// stream or when `gone` says the device went away.
pub(crate) fn read_outcome(
    r: std::io::Result<usize>,
    scratch: &[u8],
    buf: &mut Vec<u8>,
    gone: fn(&std::io::Error) -> bool,
) -> Result<usize, crate::LinkError> {
    use std::io::ErrorKind::{Interrupted, TimedOut, WouldBlock};
    match r {
        Ok(0) => Err(crate::LinkError::Disconnected),
        Ok(n) => {
            buf.extend_from_slice(&scratch[..n]);
            Ok(n)
        }
        Err(e) if matches!(e.kind(), WouldBlock | TimedOut | Interrupted) => Ok(0),
        Err(e) if gone(&e) => Err(crate::LinkError::Disconnected),
        Err(e) => Err(crate::LinkError::Io(e)),
    }
}
