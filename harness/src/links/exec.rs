//! `exec:COMMAND ARGS`: a child process speaking GCL on its stdin/stdout (`gcl sim --stdio`,
//! another simulator, a bridge to a hand). A reader thread feeds a channel so that
//! [`Link::recv`] honours its timeout; the child is killed and reaped when the link drops.

use std::io::{Read, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::link::{Link, LinkError};

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
        let Some(mut stdout) = child.stdout.take() else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(open_err("no stdout pipe".into()));
        };
        let (tx, rx) = std::sync::mpsc::channel();
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
        Ok(ExecLink { child, stdin, rx, stderr: captured, label, started: Instant::now(), closed: false })
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
        match stdin.write_all(bytes).and_then(|_| stdin.flush()) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(LinkError::Disconnected),
            Err(e) => Err(LinkError::Io(e)),
        }
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
        // Whatever else is already there.
        while let Ok(more) = self.rx.try_recv() {
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

impl Drop for ExecLink {
    fn drop(&mut self) {
        self.stdin = None;
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
