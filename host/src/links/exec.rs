//! `exec:COMMAND ARGS`: a child process speaking GCL on its stdin/stdout (`gcl sim --stdio`,
//! another simulator, a bridge to a hand). A reader thread feeds a bounded channel so that
//! [`Link::recv`] honours its timeout and a child that floods its stdout waits for us (the
//! pipe's own backpressure) instead of filling our memory. Writes to the child's stdin are
//! non-blocking with a deadline ([`WRITE_STALL`]), so a child that stops reading fails the
//! write instead of hanging it. The child is killed and reaped when the link drops.

use std::io::{Read, Write};
use std::os::fd::{AsFd, AsRawFd};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use nix::fcntl::{FcntlArg, OFlag, fcntl};
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use crate::link::{Link, LinkError};

/// How long a write to the child may go without the child taking a single byte before it
/// fails (`TimedOut`): a child that stops reading its stdin ends the step, not the run.
pub const WRITE_STALL: Duration = Duration::from_secs(5);

/// Chunks of the child's output held between the reader thread and [`Link::recv`] (4 KiB
/// each); when they are full the reader stops reading and the pipe holds the child back.
const CHANNEL_CHUNKS: usize = 64;

/// The most bytes one [`Link::recv`] returns.
const RECV_MAX: usize = 64 * 1024;

/// What happens to the child's stderr.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StderrMode {
    /// Shared with this process.
    #[default]
    Inherit,
    /// Discarded.
    Null,
    /// Collected; read it with [`ExecLink::stderr_output`].
    Capture,
}

/// A child process.
pub struct ExecLink {
    child: Child,
    stdin: Option<ChildStdin>,
    rx: Receiver<Vec<u8>>,
    stderr: Arc<Mutex<Vec<u8>>>,
    label: String,
    started: Instant,
    closed: bool,
    write_stall: Duration,
}

impl std::fmt::Debug for ExecLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExecLink").field("label", &self.label).field("pid", &self.child.id()).finish_non_exhaustive()
    }
}

impl ExecLink {
    /// Starts `argv[0]` with the rest as arguments.
    pub fn spawn(argv: &[String], stderr: StderrMode) -> Result<ExecLink, LinkError> {
        let label = format!("exec:{}", argv.join(" "));
        let open_err = |reason: String| LinkError::Open { target: label.clone(), reason };
        let (program, args) = argv.split_first().ok_or_else(|| open_err("empty command".into()))?;
        let mut child = Command::new(program)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(match stderr {
                StderrMode::Inherit => Stdio::inherit(),
                StderrMode::Null => Stdio::null(),
                StderrMode::Capture => Stdio::piped(),
            })
            .spawn()
            .map_err(|e| open_err(e.to_string()))?;
        let stdin = child.stdin.take();
        if let Some(i) = &stdin
            && let Err(e) = set_nonblocking(i)
        {
            let _ = child.kill();
            let _ = child.wait();
            return Err(open_err(format!("cannot make stdin non-blocking: {e}")));
        }
        let Some(mut stdout) = child.stdout.take() else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(open_err("no stdout pipe".into()));
        };
        let (tx, rx) = std::sync::mpsc::sync_channel(CHANNEL_CHUNKS);
        std::thread::Builder::new()
            .name("gcl-exec-reader".into())
            .spawn(move || {
                let mut buf = vec![0u8; 4096];
                loop {
                    match stdout.read(&mut buf) {
                        Ok(0) => break,
                        Ok(n) => {
                            if tx.send(buf[..n].to_vec()).is_err() {
                                break;
                            }
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        Err(_) => break,
                    }
                }
            })
            .map_err(|e| open_err(e.to_string()))?;
        let captured = Arc::new(Mutex::new(Vec::new()));
        if let Some(mut err) = child.stderr.take() {
            let sink = captured.clone();
            let _ = std::thread::Builder::new().name("gcl-exec-stderr".into()).spawn(move || {
                let mut buf = vec![0u8; 4096];
                while let Ok(n) = err.read(&mut buf) {
                    if n == 0 {
                        break;
                    }
                    if let Ok(mut s) = sink.lock() {
                        s.extend_from_slice(&buf[..n]);
                    }
                }
            });
        }
        Ok(ExecLink {
            child,
            stdin,
            rx,
            stderr: captured,
            label,
            started: Instant::now(),
            closed: false,
            write_stall: WRITE_STALL,
        })
    }

    /// Changes how long a write may go without progress (default [`WRITE_STALL`]).
    pub fn set_write_stall(&mut self, d: Duration) {
        self.write_stall = d;
    }

    /// What the child wrote on stderr so far ([`StderrMode::Capture`]).
    pub fn stderr_output(&self) -> String {
        self.stderr.lock().map(|s| String::from_utf8_lossy(&s).into_owned()).unwrap_or_default()
    }

    /// The child's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Closes the child's stdin (a `gcl sim --stdio` child then exits).
    pub fn close_input(&mut self) {
        self.stdin = None;
    }

    /// Waits at most `timeout` for the child to exit by itself; returns its exit code if it did.
    pub fn wait_exit(&mut self, timeout: Duration) -> Option<i32> {
        let end = Instant::now() + timeout;
        loop {
            if let Ok(Some(status)) = self.child.try_wait() {
                return Some(status.code().unwrap_or(-1));
            }
            if Instant::now() >= end {
                return None;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

impl Link for ExecLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let Some(stdin) = &mut self.stdin else { return Err(LinkError::Disconnected) };
        write_with_deadline(stdin, bytes, self.write_stall)
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        if self.closed {
            return Err(LinkError::Disconnected);
        }
        let first = if timeout.is_zero() {
            match self.rx.try_recv() {
                Ok(b) => b,
                Err(TryRecvError::Empty) => return Ok(0),
                Err(TryRecvError::Disconnected) => {
                    self.closed = true;
                    return Err(LinkError::Disconnected);
                }
            }
        } else {
            match self.rx.recv_timeout(timeout) {
                Ok(b) => b,
                Err(RecvTimeoutError::Timeout) => return Ok(0),
                Err(RecvTimeoutError::Disconnected) => {
                    self.closed = true;
                    return Err(LinkError::Disconnected);
                }
            }
        };
        let mut n = first.len();
        buf.extend_from_slice(&first);
        // Whatever else is already there, up to a bound.
        while n < RECV_MAX
            && let Ok(more) = self.rx.try_recv()
        {
            n += more.len();
            buf.extend_from_slice(&more);
        }
        Ok(n)
    }

    fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    fn describe(&self) -> String {
        self.label.clone()
    }
}

fn set_nonblocking(stdin: &ChildStdin) -> nix::Result<()> {
    let fd = stdin.as_raw_fd();
    let flags = OFlag::from_bits_truncate(fcntl(fd, FcntlArg::F_GETFL)?);
    fcntl(fd, FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK))?;
    Ok(())
}

/// Writes all of `bytes` to a non-blocking pipe, waiting for room at most `stall` at a time.
fn write_with_deadline(stdin: &mut ChildStdin, mut bytes: &[u8], stall: Duration) -> Result<(), LinkError> {
    use std::io::ErrorKind::{BrokenPipe, Interrupted, WouldBlock};
    while !bytes.is_empty() {
        match stdin.write(bytes) {
            Ok(0) => return Err(LinkError::Disconnected),
            Ok(n) => bytes = &bytes[n..],
            Err(e) if e.kind() == Interrupted => {}
            Err(e) if e.kind() == WouldBlock => {
                let end = Instant::now() + stall;
                loop {
                    let left = end.saturating_duration_since(Instant::now());
                    if left.is_zero() {
                        return Err(LinkError::Io(std::io::Error::new(
                            std::io::ErrorKind::TimedOut,
                            format!("the hand took none of {} pending bytes within {stall:?}", bytes.len()),
                        )));
                    }
                    let ms = PollTimeout::from(left.as_millis().clamp(1, 60_000) as u16);
                    let mut fds = [PollFd::new(stdin.as_fd(), PollFlags::POLLOUT)];
                    match poll(&mut fds, ms) {
                        Ok(0) | Err(nix::errno::Errno::EINTR) => continue,
                        Ok(_) => {
                            let r = fds[0].revents().unwrap_or(PollFlags::empty());
                            if r.intersects(PollFlags::POLLERR | PollFlags::POLLHUP) {
                                return Err(LinkError::Disconnected);
                            }
                            break;
                        }
                        Err(e) => return Err(LinkError::Io(e.into())),
                    }
                }
            }
            Err(e) if e.kind() == BrokenPipe => return Err(LinkError::Disconnected),
            Err(e) => return Err(LinkError::Io(e)),
        }
    }
    Ok(())
}

impl Drop for ExecLink {
    fn drop(&mut self) {
        self.stdin = None;
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_write_to_a_child_that_does_not_read_fails_at_its_deadline() {
        // `sleep` never reads its stdin: the pipe fills and the write must give up.
        let argv = ["sleep".to_string(), "30".to_string()];
        let mut l = ExecLink::spawn(&argv, StderrMode::Null).unwrap();
        l.set_write_stall(Duration::from_millis(200));
        let err = l.send(&vec![b'x'; 1 << 20]).unwrap_err();
        let LinkError::Io(e) = &err else { panic!("{err:?}") };
        assert_eq!(e.kind(), std::io::ErrorKind::TimedOut, "{e}");
        assert!(e.to_string().contains("pending bytes"), "{e}");
    }

    #[test]
    fn a_flooding_child_is_read_in_bounded_pieces() {
        let argv = ["sh".to_string(), "-c".to_string(), "exec cat /dev/zero".to_string()];
        let mut l = ExecLink::spawn(&argv, StderrMode::Null).unwrap();
        let mut buf = Vec::new();
        for _ in 0..50 {
            buf.clear();
            let n = l.recv(&mut buf, Duration::from_millis(100)).unwrap();
            assert!(n <= RECV_MAX + 8192, "one recv returned {n} bytes");
        }
    }
}
