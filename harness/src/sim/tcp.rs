//! `gcl sim --tcp`: the hand behind a TCP listener, one client at a time like a cable.
//!
//! A second connection while one is active is accepted and closed at once with nothing
//! written (the cable is taken); before deciding, the active connection is read to its end, so
//! a client that closes and reconnects at once is not refused. The hand keeps its state from
//! one client to the next; output produced while no client is connected is dropped. pyserial's
//! `socket://HOST:PORT` works as a client.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::os::fd::{AsFd, BorrowedFd};
use std::time::Instant;

use nix::poll::{PollFd, PollFlags};

use super::wait::{IN, ready, wait};
use super::{Engine, SimError};

/// How long a new connection waits for the active client's end before it is refused: a
/// client that closes and reconnects at once must not be turned away.
const RECONNECT_GRACE: std::time::Duration = std::time::Duration::from_millis(100);

/// A bound listener.
#[derive(Debug)]
pub struct TcpServer {
    listener: TcpListener,
    addr: SocketAddr,
}

impl TcpServer {
    /// Binds `addr` (`HOST:PORT`, or a bare `PORT` meaning `127.0.0.1:PORT`; port 0 picks a
    /// free one). A non-loopback address is refused unless `allow_remote`.
    pub fn bind(addr: &str, allow_remote: bool) -> Result<TcpServer, SimError> {
        let bad = |reason: String| SimError::Listen { addr: addr.to_string(), reason };
        let text = if addr.parse::<u16>().is_ok() { format!("127.0.0.1:{addr}") } else { addr.to_string() };
        let addrs: Vec<SocketAddr> =
            text.to_socket_addrs().map_err(|e| bad(format!("not an address (HOST:PORT or PORT): {e}")))?.collect();
        if addrs.is_empty() {
            return Err(bad("the name resolves to no address".into()));
        }
        if !allow_remote && let Some(a) = addrs.iter().find(|a| !a.ip().is_loopback()) {
            return Err(bad(format!(
                "{} is not a loopback address; the simulator has no authentication, pass --allow-remote to serve it \
                 beyond this machine",
                a.ip()
            )));
        }
        let listener = TcpListener::bind(&addrs[..]).map_err(|e| bad(e.to_string()))?;
        listener.set_nonblocking(true).map_err(|e| bad(e.to_string()))?;
        let addr = listener.local_addr().map_err(|e| bad(e.to_string()))?;
        Ok(TcpServer { listener, addr })
    }

    /// The address actually bound.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Serves clients one at a time until one of `stops` becomes readable.
    pub fn serve(&mut self, engine: &mut Engine, stops: &[BorrowedFd<'_>]) -> Result<(), SimError> {
        engine.client_gone("listening, no client yet");
        let mut client: Option<(TcpStream, String)> = None;
        let mut buf = vec![0u8; 8192];
        loop {
            let want_write = !engine.ready_output(Instant::now()).is_empty();
            let (client_in, listen_in, stop) = {
                let mut fds = Vec::with_capacity(2 + stops.len());
                fds.push(PollFd::new(self.listener.as_fd(), IN));
                if let Some((s, _)) = &client {
                    let mut f = IN;
                    if want_write {
                        f |= PollFlags::POLLOUT;
                    }
                    fds.push(PollFd::new(s.as_fd(), f));
                }
                let first_stop = fds.len();
                fds.extend(stops.iter().map(|s| PollFd::new(*s, IN)));
                wait(&mut fds, engine.deadline()).map_err(|e| SimError::io("waiting on the socket", e))?;
                let client_in = client.is_some() && ready(&fds[1], IN);
                (client_in, ready(&fds[0], IN), fds[first_stop..].iter().any(|f| ready(f, IN)))
            };
            if stop {
                break;
            }
            // The active client first, so that its end is seen before a new connection.
            if client_in || listen_in {
                read_client(&mut client, engine, &mut buf);
            }
            if listen_in {
                loop {
                    match self.listener.accept() {
                        Ok((s, peer)) => {
                            // A client accepted in this same round may already have ended, and
                            // one that closed just before this connection may not have been
                            // seen to end yet (a busy machine): give its end a moment to land.
                            read_client(&mut client, engine, &mut buf);
                            if let Some((active, _)) = &client {
                                let mut fds = [PollFd::new(active.as_fd(), IN)];
                                let _ = wait(&mut fds, Some(Instant::now() + RECONNECT_GRACE));
                                read_client(&mut client, engine, &mut buf);
                            }
                            if client.is_some() {
                                engine.note(&format!("refused {peer}: another client is connected"));
                                let _ = s.shutdown(Shutdown::Both);
                            } else if s.set_nonblocking(true).is_ok() {
                                let _ = s.set_nodelay(true);
                                engine.client_connected(&peer.to_string());
                                client = Some((s, peer.to_string()));
                            }
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        // WouldBlock, or a connection that died in the backlog.
                        Err(_) => break,
                    }
                }
            }
            engine.wake();
            if let Some((s, _)) = &mut client {
                let mut gone = None;
                loop {
                    let out = engine.ready_output(Instant::now());
                    if out.is_empty() {
                        break;
                    }
                    match s.write(out) {
                        Ok(n) => engine.consumed(n),
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                        Err(e) => {
                            gone = Some(e.to_string());
                            break;
                        }
                    }
                }
                if let Some(why) = gone {
                    client = None;
                    engine.client_gone(&why);
                }
            }
        }
        engine.finish()
    }
}

/// Reads the active client until it has nothing more; ends it on end of stream or error.
fn read_client(client: &mut Option<(TcpStream, String)>, engine: &mut Engine, buf: &mut [u8]) {
    let Some((s, _)) = client else { return };
    let why = loop {
        match s.read(buf) {
            Ok(0) => break "closed by the client".to_string(),
            Ok(n) => engine.input(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => break e.to_string(),
        }
    };
    *client = None;
    engine.client_gone(&why);
}
