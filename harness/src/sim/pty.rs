//! `gcl sim --pty`: the hand behind a pseudo-terminal, which any program that opens a serial
//! port by path (pyserial, termios, the `serial:` target) can use.
//!
//! The slave side is set raw (`cfmakeraw`): no echo by the line discipline, no CR/NL
//! translation, no signals from ^C, so every byte reaches the hand as sent. The simulator keeps
//! its own descriptor of the slave open for its whole life, so a client closing the port never
//! hangs up the master: the next client finds the hand as the last one left it. A client should
//! discard stale input when it opens the port (pyserial and the `serial:` target do), since
//! answers the previous client did not read wait in the slave's buffer.

use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::time::Instant;

use nix::fcntl::{FcntlArg, OFlag, fcntl};
use nix::poll::{PollFd, PollFlags};
use nix::sys::termios::{self, SetArg};

use super::wait::{BACKOFF, IN, ready, wait};
use super::{Engine, SimError};

/// A pseudo-terminal pair held by the simulator.
#[derive(Debug)]
pub struct Pty {
    master: File,
    _slave: OwnedFd,
    path: PathBuf,
    link: Option<PathBuf>,
}

fn pty_err(what: &str, e: impl std::fmt::Display) -> SimError {
    SimError::Pty(format!("{what}: {e}"))
}

impl Pty {
    /// Creates a raw pty; with `link`, also a symbolic link to its slave at that path (an
    /// existing symbolic link there is replaced; any other file is an error). The link is
    /// removed when the `Pty` is dropped.
    pub fn open(link: Option<&Path>) -> Result<Pty, SimError> {
        let pair = nix::pty::openpty(None, None).map_err(|e| pty_err("cannot create a pty", e))?;
        let mut t = termios::tcgetattr(&pair.slave).map_err(|e| pty_err("tcgetattr", e))?;
        termios::cfmakeraw(&mut t);
        termios::tcsetattr(&pair.slave, SetArg::TCSANOW, &t).map_err(|e| pty_err("tcsetattr", e))?;
        let path = nix::unistd::ttyname(&pair.slave).map_err(|e| pty_err("ttyname", e))?;
        fcntl(pair.master.as_raw_fd(), FcntlArg::F_SETFL(OFlag::O_NONBLOCK))
            .map_err(|e| pty_err("cannot make the master non-blocking", e))?;
        let mut pty = Pty { master: File::from(pair.master), _slave: pair.slave, path, link: None };
        if let Some(l) = link {
            make_link(&pty.path, l)?;
            pty.link = Some(l.to_path_buf());
        }
        Ok(pty)
    }

    /// The slave's path (`/dev/pts/N`).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The symbolic link, if one was made.
    pub fn link(&self) -> Option<&Path> {
        self.link.as_deref()
    }

    /// Serves the hand until one of `stops` becomes readable. Returns an error only for a
    /// failure of the pty itself, never for anything a client does.
    pub fn serve(&mut self, engine: &mut Engine, stops: &[BorrowedFd<'_>]) -> Result<(), SimError> {
        let mut buf = vec![0u8; 8192];
        let mut backoff_until: Option<Instant> = None;
        loop {
            let now = Instant::now();
            let readable_ok = backoff_until.is_none_or(|t| now >= t);
            if readable_ok {
                backoff_until = None;
            }
            let want_write = !engine.ready_output(now).is_empty();
            let mut flags = PollFlags::empty();
            if readable_ok {
                flags |= IN;
            }
            if want_write {
                flags |= PollFlags::POLLOUT;
            }
            let mut deadline = engine.deadline();
            if let Some(b) = backoff_until {
                deadline = Some(deadline.map_or(b, |d| d.min(b)));
            }
            let (master_in, stop) = {
                let mut fds = Vec::with_capacity(1 + stops.len());
                fds.push(PollFd::new(self.master.as_fd(), flags));
                fds.extend(stops.iter().map(|s| PollFd::new(*s, IN)));
                wait(&mut fds, deadline).map_err(|e| SimError::io("waiting on the pty", e))?;
                (readable_ok && ready(&fds[0], IN), fds[1..].iter().any(|f| ready(f, IN)))
            };
            if stop {
                break;
            }
            if master_in {
                loop {
                    match self.master.read(&mut buf) {
                        Ok(0) => {
                            backoff_until = Some(Instant::now() + BACKOFF);
                            break;
                        }
                        Ok(n) => engine.input(&buf[..n]),
                        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        // EIO: no process has the slave open. Cannot happen while we hold
                        // it, but a hand does not die of it either.
                        Err(_) => {
                            backoff_until = Some(Instant::now() + BACKOFF);
                            break;
                        }
                    }
                }
            }
            engine.wake();
            loop {
                let out = engine.ready_output(Instant::now());
                if out.is_empty() {
                    break;
                }
                match self.master.write(out) {
                    Ok(n) => engine.consumed(n),
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    // Full (nobody reading) or EIO: try again later.
                    Err(_) => break,
                }
            }
        }
        engine.finish()
    }
}

fn make_link(target: &Path, link: &Path) -> Result<(), SimError> {
    match std::fs::symlink_metadata(link) {
        Ok(m) if !m.file_type().is_symlink() => {
            return Err(SimError::Pty(format!("--link {}: exists and is not a symbolic link", link.display())));
        }
        _ => {}
    }
    let name = link.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = link.with_file_name(format!(".{name}.tmp{}", std::process::id()));
    let _ = std::fs::remove_file(&tmp);
    std::os::unix::fs::symlink(target, &tmp)
        .and_then(|_| std::fs::rename(&tmp, link))
        .map_err(|e| SimError::Pty(format!("--link {}: {e}", link.display())))
}

impl Drop for Pty {
    fn drop(&mut self) {
        if let Some(l) = &self.link {
            // Only our own link: another simulator may have replaced it since.
            if std::fs::read_link(l).is_ok_and(|t| t == self.path) {
                let _ = std::fs::remove_file(l);
            }
        }
        let _ = self.master.flush();
    }
}
