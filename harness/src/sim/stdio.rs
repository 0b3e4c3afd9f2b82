//! `gcl sim --stdio`: the hand on standard input and output, so that a program can run it as a
//! child (the `exec:` target). End of input ends the simulator (after the output already due
//! is written); a reader that went away ends it too.

use std::io::Write;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd};
use std::time::Instant;

use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags};

use super::wait::{IN, ready, wait};
use super::{Engine, SimError};

/// Serves the hand on stdin/stdout until end of input or until one of `stops` is readable.
pub fn serve_stdio(engine: &mut Engine, stops: &[BorrowedFd<'_>]) -> Result<(), SimError> {
    let stdin = std::io::stdin();
    let mut stdout = std::io::stdout().lock();
    let mut buf = vec![0u8; 8192];
    let mut eof = false;
    loop {
        // Write what is due first: the banner, and everything after each input.
        loop {
            let out = engine.ready_output(Instant::now());
            if out.is_empty() {
                break;
            }
            let n = out.len();
            match stdout.write_all(out).and_then(|_| stdout.flush()) {
                Ok(()) => engine.consumed(n),
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return engine.finish(),
                Err(e) => return Err(SimError::io("writing to stdout", e)),
            }
        }
        if eof && !engine.has_output() {
            break;
        }
        let (input, stop) = {
            let mut fds = Vec::with_capacity(1 + stops.len());
            fds.push(PollFd::new(stdin.as_fd(), if eof { PollFlags::empty() } else { IN }));
            fds.extend(stops.iter().map(|s| PollFd::new(*s, IN)));
            wait(&mut fds, engine.deadline()).map_err(|e| SimError::io("waiting on stdin", e))?;
            (!eof && ready(&fds[0], IN), fds[1..].iter().any(|f| ready(f, IN)))
        };
        if stop {
            break;
        }
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
