//! `gcl sim --stdio`: the hand on standard input and output, so that a program can run it as a
//! child (the `exec:` target). End of input ends the simulator (after the output already due
//! is written); a reader that went away ends it too.
//!
//! Output is written without blocking (stdout is reopened through `/proc/self/fd/1` as a
//! non-blocking description of its own, so the parent's is left as it is), so a stop request
//! or a signal ends the simulator even while nobody reads its output. While output waits, the
//! simulator stops reading input (backpressure; nothing is dropped).

use std::fs::File;
use std::io::Write;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd};
use std::time::Instant;

use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags};

use super::wait::{IN, ready, wait};
use super::{Engine, SimError};

/// Stdout as a non-blocking file of its own, when the system allows it (a pipe, a FIFO, a
/// terminal or a regular file); `None` otherwise (the inherited descriptor is then used,
/// still polled before each write).
fn nonblocking_stdout() -> Option<File> {
    let f = std::fs::OpenOptions::new().write(true).open("/proc/self/fd/1").ok()?;
    let fd = f.as_raw_fd();
    let flags = nix::fcntl::fcntl(fd, nix::fcntl::FcntlArg::F_GETFL).ok()?;
    let flags = nix::fcntl::OFlag::from_bits_truncate(flags) | nix::fcntl::OFlag::O_NONBLOCK;
    nix::fcntl::fcntl(fd, nix::fcntl::FcntlArg::F_SETFL(flags)).ok()?;
    Some(f)
}

/// Serves the hand on stdin/stdout until end of input or until one of `stops` is readable.
pub fn serve_stdio(engine: &mut Engine, stops: &[BorrowedFd<'_>]) -> Result<(), SimError> {
    let stdin = std::io::stdin();
    let own = nonblocking_stdout();
    let inherited = std::io::stdout();
    let mut buf = vec![0u8; 8192];
    let mut eof = false;
    let mut writable = true;
    loop {
        // Write what is due first: the banner, and everything after each input.
        while writable {
            let out = engine.ready_output(Instant::now());
            if out.is_empty() {
                break;
            }
            // Without a non-blocking description, write no more than a pipe takes at once.
            let r = match &own {
                Some(f) => {
                    let mut w: &File = f;
                    w.write(out)
                }
                None => {
                    let n = out.len().min(512);
                    inherited.lock().write(&out[..n]).and_then(|n| inherited.lock().flush().map(|_| n))
                }
            };
            match r {
                Ok(0) => writable = false,
                Ok(n) => engine.consumed(n),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => writable = false,
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return engine.finish(),
                Err(e) => return Err(SimError::io("writing to stdout", e)),
            }
        }
        if eof && !engine.has_output() && !engine.has_input() {
            break;
        }
        // The deadline before the output check (see the pty loop).
        let deadline = engine.deadline();
        let want_write = !engine.ready_output(Instant::now()).is_empty();
        let read_ok = !eof && engine.wants_input();
        let (input, can_write, stop) = {
            let out_fd = match &own {
                Some(f) => f.as_fd(),
                None => inherited.as_fd(),
            };
            let mut fds = Vec::with_capacity(2 + stops.len());
            fds.push(PollFd::new(stdin.as_fd(), if read_ok { IN } else { PollFlags::empty() }));
            fds.push(PollFd::new(out_fd, if want_write { PollFlags::POLLOUT } else { PollFlags::empty() }));
            fds.extend(stops.iter().map(|s| PollFd::new(*s, IN)));
            wait(&mut fds, deadline).map_err(|e| SimError::io("waiting on stdin", e))?;
            (
                read_ok && ready(&fds[0], IN),
                ready(&fds[1], PollFlags::POLLOUT | PollFlags::POLLERR | PollFlags::POLLHUP),
                fds[2..].iter().any(|f| ready(f, IN)),
            )
        };
        if stop {
            break;
        }
        writable = can_write || !want_write;
        if input {
            match nix::unistd::read(stdin.as_fd().as_raw_fd(), &mut buf) {
                Ok(0) => {
                    eof = true;
                    engine.note("end of input");
                }
                Ok(n) => engine.input(&buf[..n]),
                Err(Errno::EINTR | Errno::EAGAIN) => {}
                Err(e) => return Err(SimError::io("reading stdin", e)),
            }
        }
        engine.wake();
    }
    engine.finish()
}
