//! `serial:PATH?baud=N`: a serial port (or a pty such as `gcl sim --pty`'s), raw 8N1, no flow
//! control, opened non-exclusively so that a pty can be reopened; stale input is discarded at
//! open.

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

impl SerialLink {
    /// Opens `path` at `baud`, 8N1, no flow control.
    pub fn open(path: &str, baud: u32) -> Result<SerialLink, LinkError> {
        let open_err = |reason: String| LinkError::Open { target: format!("serial:{path}"), reason };
        let mut port = serialport::new(path, baud)
            .data_bits(DataBits::Eight)
            .parity(Parity::None)
            .stop_bits(StopBits::One)
            .flow_control(FlowControl::None)
            .exclusive(false)
            .timeout(Duration::from_millis(100))
            .open_native()
            .map_err(|e| open_err(e.to_string()))?;
        port.set_exclusive(false).map_err(|e| open_err(e.to_string()))?;
        port.clear(ClearBuffer::Input).map_err(|e| open_err(e.to_string()))?;
        Ok(SerialLink {
            port,
            label: format!("serial:{path}?baud={baud}"),
            started: Instant::now(),
            scratch: vec![0; 4096],
        })
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
