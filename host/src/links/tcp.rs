//! `tcp://HOST:PORT`: a hand (or `gcl sim --tcp`) behind a TCP socket. Nagle is off, so that a
//! command goes out at once.

use std::io::{Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use crate::link::{Link, LinkError};

/// A connected socket.
#[derive(Debug)]
pub struct TcpLink {
    stream: TcpStream,
    label: String,
    started: Instant,
    scratch: Vec<u8>,
}

fn is_gone(e: &std::io::Error) -> bool {
    use std::io::ErrorKind::*;
    matches!(e.kind(), BrokenPipe | UnexpectedEof | ConnectionReset | ConnectionAborted | NotConnected)
}

impl TcpLink {
    /// Connects to `addr` (`HOST:PORT`), trying each address it resolves to for at most
    /// `connect_timeout`.
    pub fn connect(addr: &str, connect_timeout: Duration) -> Result<TcpLink, LinkError> {
        let open_err = |reason: String| LinkError::Open { target: format!("tcp://{addr}"), reason };
        let addrs = addr.to_socket_addrs().map_err(|e| open_err(e.to_string()))?;
        let mut last = "resolves to no address".to_string();
        for a in addrs {
            match TcpStream::connect_timeout(&a, connect_timeout) {
                Ok(stream) => {
                    stream.set_nodelay(true).map_err(|e| open_err(e.to_string()))?;
                    stream.set_write_timeout(Some(Duration::from_secs(5))).map_err(|e| open_err(e.to_string()))?;
                    return Ok(TcpLink {
                        stream,
                        label: format!("tcp://{addr}"),
                        started: Instant::now(),
                        scratch: vec![0; 4096],
                    });
                }
                Err(e) => last = e.to_string(),
            }
        }
        Err(open_err(last))
    }
}

impl Link for TcpLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        match self.stream.write_all(bytes) {
            Ok(()) => Ok(()),
            Err(e) if is_gone(&e) => Err(LinkError::Disconnected),
            Err(e) => Err(LinkError::Io(e)),
        }
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        self.stream.set_read_timeout(Some(timeout.max(super::MIN_WAIT))).map_err(LinkError::Io)?;
        let r = self.stream.read(&mut self.scratch);
        super::read_outcome(r, &self.scratch, buf, is_gone)
    }

    fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    fn describe(&self) -> String {
        self.label.clone()
    }
}
