//! `gcl sim --tcp`: the hand behind a TCP listener, one client at a time like a cable.
//!
//! A second connection while one is active is accepted and closed at once with nothing
//! written (the cable is taken); before deciding, the active connection is read to its end, so
//! a client that closes and reconnects at once is not refused. The hand keeps its state from
//! one client to the next; when a client goes, what it had not read is discarded, and output
//! produced while no client is connected is lost. A client that shuts down its sending side
//! (half-close) still gets every answer; the simulator then ends the stream. While the client
//! does not read, the simulator stops reading it (backpressure; nothing is dropped). pyserial's
//! `socket://HOST:PORT` works as a client.
//!
//! On a tapped line the transport learns which of the host's bytes the host wrote with output
//! unread: from `host_writes` when the host is a child of ours, so the order of its read and write
//! decides, not who runs first; otherwise by a look in `/proc/net/tcp` before it takes the host's
//! next bytes.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::os::fd::{AsFd, BorrowedFd};
use std::time::Instant;

use nix::poll::{PollFd, PollFlags};

use super::host_writes::Marks;
use super::wait::{IN, precise_timers, ready, wait};
use super::{Engine, SimError};

/// How long a new connection waits for the active client's end before it is refused: a
/// client that closes and reconnects at once must not be turned away.
const RECONNECT_GRACE: std::time::Duration = std::time::Duration::from_millis(100);

/// A bound listener.
#[derive(Debug)]
pub struct TcpServer {
    listener: TcpListener,
    addr: SocketAddr,
    /// Where the host's writes are seen as it makes them ([`super::host_writes`]).
    marks: Option<Marks>,
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
        Ok(TcpServer { listener, addr, marks: None })
    }

    /// The address actually bound.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Takes, for a tapped line, which of the client's bytes it wrote with output unread
    /// from `marks` (seen at its writes) rather than by looking when they arrive.
    pub fn watch_host_writes(&mut self, marks: Marks) {
        self.marks = Some(marks);
    }

    /// Serves clients one at a time until one of `stops` becomes readable.
    pub fn serve(&mut self, engine: &mut Engine, stops: &[BorrowedFd<'_>]) -> Result<(), SimError> {
        precise_timers();
        let marks = self.marks.clone();
        let marks = marks.as_ref();
        engine.client_gone("listening, no client yet");
        let mut client: Option<Client> = None;
        let mut buf = vec![0u8; 8192];
        loop {
            // The deadline before the output check: a byte that falls due in between is
            // then either a deadline or ready to write, never neither.
            let deadline = engine.deadline();
            let want_write = !engine.ready_output(Instant::now()).is_empty();
            let (client_in, client_err, listen_in, stop) = {
                let mut fds = Vec::with_capacity(2 + stops.len());
                fds.push(PollFd::new(self.listener.as_fd(), IN));
                if let Some(c) = &client {
                    let mut f = PollFlags::empty();
                    if !c.read_closed && engine.wants_input() {
                        f |= IN;
                    }
                    if want_write {
                        f |= PollFlags::POLLOUT;
                    }
                    fds.push(PollFd::new(c.stream.as_fd(), f));
                }
                let first_stop = fds.len();
                fds.extend(stops.iter().map(|s| PollFd::new(*s, IN)));
                wait(&mut fds, deadline).map_err(|e| SimError::io("waiting on the socket", e))?;
                let client_in = client.is_some() && ready(&fds[1], IN);
                let client_err = client.is_some() && ready(&fds[1], PollFlags::POLLHUP | PollFlags::POLLERR);
                (client_in, client_err, ready(&fds[0], IN), fds[first_stop..].iter().any(|f| ready(f, IN)))
            };
            // A half-closed client whose connection broke cannot take its answers any more.
            if client_err && client.as_ref().is_some_and(|c| c.read_closed) {
                end_client(&mut client, engine, "the half-closed client's connection ended");
            }
            // The active client first, so that its end is seen before a new connection.
            if client_in || listen_in {
                read_client(&mut client, engine, &mut buf, marks);
            }
            if listen_in {
                loop {
                    match self.listener.accept() {
                        Ok((s, peer)) => {
                            // A client accepted in this same round may already have ended, and
                            // one that closed just before this connection may not have been
                            // seen to end yet (a busy machine): give its end a moment to land.
                            read_client(&mut client, engine, &mut buf, marks);
                            if let Some(c) = &client
                                && !c.read_closed
                            {
                                let mut fds = [PollFd::new(c.stream.as_fd(), IN)];
                                let _ = wait(&mut fds, Some(Instant::now() + RECONNECT_GRACE));
                                read_client(&mut client, engine, &mut buf, marks);
                            }
                            // A client that has finished sending (half-closed) gives way.
                            if client.as_ref().is_some_and(|c| c.read_closed) {
                                end_client(&mut client, engine, "half-closed client replaced by a new connection");
                            }
                            if client.is_some() {
                                engine.note(&format!("refused {peer}: another client is connected"));
                                let _ = s.shutdown(Shutdown::Both);
                            } else if s.set_nonblocking(true).is_ok() {
                                let _ = s.set_nodelay(true);
                                engine.client_connected(&peer.to_string());
                                client = Some(Client {
                                    stream: s,
                                    read_closed: false,
                                    wrote: false,
                                    received: 0,
                                    sent: 0,
                                    port: peer.port(),
                                });
                            }
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        // WouldBlock, or a connection that died in the backlog.
                        Err(_) => break,
                    }
                }
            }
            // Stopped: after what the host did before the stop (its connection, its bytes) is
            // taken in, so that a host that connected, wrote and went just before it counts.
            if stop {
                break;
            }
            engine.wake();
            if let Some(c) = &mut client {
                let mut gone = None;
                loop {
                    let out = engine.ready_output(Instant::now());
                    if out.is_empty() {
                        break;
                    }
                    match c.stream.write(out) {
                        Ok(n) => {
                            c.wrote |= n > 0;
                            c.sent += n as u64;
                            engine.consumed(n)
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                        Err(e) => {
                            gone = Some(e.to_string());
                            break;
                        }
                    }
                }
                // A half-closed client gets every answer to what it sent, then the end of the
                // stream: once nothing is queued either way and the hand is idle.
                if gone.is_none()
                    && c.read_closed
                    && !engine.has_output()
                    && !engine.has_input()
                    && !engine.device().is_busy()
                {
                    let _ = c.stream.shutdown(Shutdown::Write);
                    gone = Some("closed by the client after its last answer".to_string());
                }
                if let Some(why) = gone {
                    end_client(&mut client, engine, &why);
                }
            }
        }
        engine.finish()
    }
}

/// The connected client.
#[derive(Debug)]
struct Client {
    stream: TcpStream,
    /// The client shut down its sending side (or closed): its answers are still delivered.
    read_closed: bool,
    /// Output went to it that it may not have read yet.
    wrote: bool,
    /// Bytes read from it so far (where the next one is in its stream).
    received: u64,
    /// Bytes written to it so far.
    sent: u64,
    /// Its port (which connection of the host's it is).
    port: u16,
}

impl Client {
    /// Whether the client has not read all the output sent to it (for a tapped line whose
    /// client's writes are not watched as they are made, [`super::host_writes`], before the
    /// bytes it sent next are judged): bytes still in this side's send queue, or in the
    /// client socket's receive queue (`/proc/net/tcp`: the connection is on this machine).
    /// A client that writes and then reads within the moment it takes to look may be missed;
    /// one that read everything is never taken for one that did not.
    fn has_unread(&mut self) -> bool {
        if !self.wrote {
            return false;
        }
        let unread = unread_bytes(&self.stream).is_some_and(|n| n > 0);
        self.wrote = unread;
        unread
    }
}

/// Bytes written to `stream` that the other end has not read: in this side's send queue, and
/// in the other end's receive queue when it is a socket of this machine (`/proc/net/tcp`, or
/// `tcp6`: each socket's `tx_queue:rx_queue`).
fn unread_bytes(stream: &TcpStream) -> Option<u64> {
    let (ours, theirs) = (stream.local_addr().ok()?, stream.peer_addr().ok()?);
    let hex = |a: &SocketAddr| -> String {
        let ip: String = match a.ip() {
            std::net::IpAddr::V4(v4) => format!("{:08X}", u32::from_ne_bytes(v4.octets())),
            std::net::IpAddr::V6(v6) => {
                v6.octets().chunks(4).map(|c| format!("{:08X}", u32::from_ne_bytes([c[0], c[1], c[2], c[3]]))).collect()
            }
        };
        format!("{ip}:{:04X}", a.port())
    };
    let (ours, theirs) = (hex(&ours), hex(&theirs));
    let table = if stream.peer_addr().ok()?.is_ipv4() { "/proc/net/tcp" } else { "/proc/net/tcp6" };
    let text = std::fs::read_to_string(table).ok()?;
    let mut found = None;
    for l in text.lines().skip(1) {
        let f: Vec<&str> = l.split_whitespace().collect();
        let (Some(local), Some(remote), Some(queues)) = (f.get(1), f.get(2), f.get(4)) else { continue };
        let Some((tx, rx)) = queues.split_once(':') else { continue };
        let n = if *local == ours && *remote == theirs {
            u64::from_str_radix(tx, 16).ok()
        } else if *local == theirs && *remote == ours {
            u64::from_str_radix(rx, 16).ok()
        } else {
            continue;
        };
        found = Some(found.unwrap_or(0) + n.unwrap_or(0));
    }
    found
}

fn end_client(client: &mut Option<Client>, engine: &mut Engine, why: &str) {
    *client = None;
    engine.client_gone(why);
}

/// Reads the active client until it has nothing more (or the engine wants no more for now).
/// End of stream only marks it half-closed; an error ends it.
fn read_client(client: &mut Option<Client>, engine: &mut Engine, buf: &mut [u8], marks: Option<&Marks>) {
    let Some(c) = client else { return };
    if c.read_closed {
        return;
    }
    let why = loop {
        if !engine.wants_input() {
            return;
        }
        match c.stream.read(buf) {
            Ok(0) => {
                c.read_closed = true;
                engine.note("the client finished sending (half-close)");
                return;
            }
            Ok(n) => {
                let from = c.received;
                c.received += n as u64;
                match marks.filter(|m| engine.tapped() && m.watched() && m.seen(c.port)) {
                    // Each write begins a part of its own, judged by what the host had read
                    // when it made it against all the output sent to it before its bytes
                    // are taken (what it had not even received, it had not read either).
                    Some(m) => {
                        let mut at = 0;
                        let mut unread = false;
                        for (cut, read) in m.take(c.port, from, from + n as u64) {
                            let cut = (cut - from) as usize;
                            if cut > at {
                                engine.host_unread(unread);
                                engine.input(&buf[at..cut]);
                                at = cut;
                            }
                            // Output had gone to it that it had not read when it wrote.
                            unread = c.sent > read;
                        }
                        engine.host_unread(unread);
                        engine.input(&buf[at..n])
                    }
                    None => {
                        if engine.tapped() {
                            let unread = c.has_unread();
                            engine.host_unread(unread);
                        }
                        engine.input(&buf[..n])
                    }
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => break e.to_string(),
        }
    };
    end_client(client, engine, &why);
}
