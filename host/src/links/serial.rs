//! `serial:PATH?baud=N`: a serial port (or a pty such as `gcl sim --pty`'s), raw 8N1, no flow
//! control; stale input is discarded at open.
//!
//! The port is held exclusively, twice over (the serialport crate's exclusive mode): an
//! advisory `flock` on the device, which every `gcl` honours, root or not, and TIOCEXCL,
//! which makes the kernel refuse other opens by programs without privilege. A port already
//! held is one clear error, [`busy`]. TIOCEXCL is cleared again when the link closes, so a
//! pty whose other end stays open can be reopened.

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use serialport::{ClearBuffer, DataBits, FlowControl, Parity, SerialPort, StopBits};

use crate::link::{Link, LinkError};

/// An open serial port.
pub struct SerialLink {
    port: serialport::TTYPort,
    label: String,
    started: Instant,
    scratch: Vec<u8>,
}

impl std::fmt::Debug for SerialLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SerialLink").field("label", &self.label).finish_non_exhaustive()
    }
}

fn is_gone(e: &std::io::Error) -> bool {
    use std::io::ErrorKind::*;
    matches!(e.kind(), BrokenPipe | UnexpectedEof | ConnectionReset | ConnectionAborted | NotConnected)
        || e.raw_os_error() == Some(nix::libc::EIO)
        || e.to_string().contains("I/O error")
}

/// The reason given when another program holds the port.
pub fn busy(path: &str) -> String {
    format!("{path} is in use by another program (another gcl run or a terminal); close it and try again")
}

impl SerialLink {
    /// Opens `path` at `baud`, 8N1, no flow control, exclusively.
    pub fn open(path: &str, baud: u32) -> Result<SerialLink, LinkError> {
        let open_err = |reason: String| LinkError::Open { target: format!("serial:{path}"), reason };
        // Exclusive: serialport sets TIOCEXCL and takes an exclusive flock, and clears
        // TIOCEXCL again when the port closes.
        let port = serialport::new(path, baud)
            .data_bits(DataBits::Eight)
            .parity(Parity::None)
            .stop_bits(StopBits::One)
            .flow_control(FlowControl::None)
            .exclusive(true)
            .timeout(Duration::from_millis(100))
            .open_native()
            .map_err(|e| {
                let text = e.to_string();
                // EBUSY from TIOCEXCL, or the flock another opener holds.
                if text.contains("busy") || text.contains("exclusive lock") {
                    open_err(busy(path))
                } else {
                    open_err(text)
                }
            })?;
        port.clear(ClearBuffer::Input).map_err(|e| open_err(e.to_string()))?;
        Ok(SerialLink {
            port,
            label: format!("serial:{path}?baud={baud}"),
            started: Instant::now(),
            scratch: vec![0; 4096],
        })
    }
}

impl SerialLink {
    /// Sets the port's rate (bit/s) from now on.
    pub fn set_rate(&mut self, baud: u32) -> Result<(), LinkError> {
        self.port.set_baud_rate(baud).map_err(|e| LinkError::Io(e.into()))
    }

    /// [`Link::recv`], taking at most `max` bytes from the port (what follows stays there).
    pub fn recv_at_most(&mut self, buf: &mut Vec<u8>, timeout: Duration, max: usize) -> Result<usize, LinkError> {
        if max == 0 {
            return Ok(0);
        }
        self.port.set_timeout(timeout.max(super::MIN_WAIT)).map_err(|e| LinkError::Io(e.into()))?;
        let end = max.min(self.scratch.len());
        let r = self.port.read(&mut self.scratch[..end]);
        super::read_outcome(r, &self.scratch, buf, is_gone)
    }
}

impl Link for SerialLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.port.set_timeout(Duration::from_secs(5)).map_err(|e| LinkError::Io(e.into()))?;
        match self.port.write_all(bytes) {
            Ok(()) => Ok(()),
            Err(e) if is_gone(&e) => Err(LinkError::Disconnected),
            Err(e) => Err(LinkError::Io(e)),
        }
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        self.port.set_timeout(timeout.max(super::MIN_WAIT)).map_err(|e| LinkError::Io(e.into()))?;
        let r = self.port.read(&mut self.scratch);
        super::read_outcome(r, &self.scratch, buf, is_gone)
    }

    fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    fn describe(&self) -> String {
        self.label.clone()
    }
}
