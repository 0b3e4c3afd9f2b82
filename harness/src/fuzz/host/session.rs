//! One run: a fresh simulated hand on a fresh pty (or loopback TCP port), a misbehaviour
//! schedule on its answers, the host command run to its end, and what came of it.
//!
//! The hand is the `gcl sim` engine and transport, in threads of this process; the host is a
//! child process in its own process group (so a hang is ended with the whole group). A hang
//! is the host neither sending nor exiting for the hang timeout after the hand's last answer
//! (held-back output counts as an answer still coming), or the run outliving its budget.

use std::io::Read;
use std::os::fd::AsFd;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};

use gcl_model::{Device, Profile};
use serde::{Deserialize, Serialize};

use super::check::{HostChecker, HostViolation};
use crate::sim::misbehave::{Fired, LineTap, Misbehave, Schedule, Shaped};
use crate::sim::{Engine, Pace, SimError, SimOptions, StopHandle, TimeMode, pty::Pty, stop_pair, tcp::TcpServer};

/// How the host reaches the hand.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Transport {
    /// A pseudo-terminal; the port is its slave's path.
    #[default]
    Pty,
    /// A loopback TCP port; the port is `127.0.0.1:N`.
    Tcp,
}

/// Everything one run is made of, but the schedule.
#[derive(Debug, Clone)]
pub struct HostRun {
    /// The host command and its arguments; `{port}` is replaced by the port (also in
    /// `GCL_PORT`), `{url}` by a pyserial URL for it.
    pub command: Vec<String>,
    /// Pty or TCP.
    pub transport: Transport,
    /// The hand's profile.
    pub profile: Arc<Profile>,
    /// Fast or real time.
    pub time: TimeMode,
    /// Line pacing.
    pub pace: Pace,
    /// The seed of the hand's noise.
    pub hand_seed: u64,
    /// Silence after the hand's last answer that makes a hang.
    pub timeout_hang: Duration,
    /// The longest a run may take.
    pub budget: Duration,
}

/// Which way bytes went.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dir {
    /// Host to hand.
    Host,
    /// Hand to host.
    Hand,
}

/// Bytes that crossed, in order.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Exchange {
    /// Which way.
    pub dir: Dir,
    /// The bytes (as they went: after misbehaviours).
    pub bytes: Vec<u8>,
    /// The misbehaviours that shaped them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub marks: Vec<String>,
}

/// How the host ended.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HostEnd {
    /// It exited with this code.
    Exit(i32),
    /// A signal killed it.
    Signal(i32),
    /// It went silent for the hang timeout; it was killed. The protocol state it hung in.
    Hung(String),
    /// It ran past the run budget; it was killed. The protocol state it was in.
    OverBudget(String),
}

/// What one run gave.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// How the host ended.
    pub end: HostEnd,
    /// Its stderr (the first 256 KiB).
    pub stderr: String,
    /// Bytes both ways.
    pub exchanges: Vec<Exchange>,
    /// The misbehaviours that fired.
    pub fired: Vec<Fired>,
    /// The host's protocol violations.
    pub violations: Vec<HostViolation>,
    /// Command words the host sent.
    pub commands: Vec<String>,
    /// Each fired misbehaviour with the command the host sent next (`-` if none): the paths
    /// guidance looks for.
    pub reactions: Vec<(String, String, String)>,
    /// Answers the hand gave.
    pub answers: u32,
    /// Wall time of the run.
    pub elapsed: Duration,
}

/// Why a run could not be made (not a finding: infrastructure).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The simulated hand could not start.
    #[error("simulated hand: {0}")]
    Sim(#[from] SimError),
    /// The host command could not be started.
    #[error("cannot start host command `{command}`: {source}")]
    Spawn {
        /// The program.
        command: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The command is empty.
    #[error("no host command given (put it after --)")]
    NoCommand,
    /// A thread or pipe could not be made.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The run was called off (the campaign is stopping); the host was killed.
    #[error("the run was called off")]
    Cancelled,
}

/// Shared between the tap (in the hand's thread) and the run.
struct Log {
    misbehave: Misbehave,
    checker: HostChecker,
    exchanges: Vec<Exchange>,
    last_activity: Instant,
    hang_up: Option<StopHandle>,
    hung_up: bool,
    reactions: Vec<(String, String, String)>,
    /// Reactions still waiting for the host's next command: (index into reactions, commands seen).
    awaiting: Vec<(usize, usize)>,
}

impl Log {
    fn push(&mut self, dir: Dir, bytes: &[u8], marks: Vec<String>) {
        match self.exchanges.last_mut() {
            Some(e) if e.dir == dir && marks.is_empty() && e.bytes.len() < 1 << 20 => e.bytes.extend_from_slice(bytes),
            _ => self.exchanges.push(Exchange { dir, bytes: bytes.to_vec(), marks }),
        }
    }
}

struct Tap(Arc<Mutex<Log>>);

impl LineTap for Tap {
    fn host_bytes(&mut self, device: &Device, bytes: &[u8]) {
        let Ok(mut log) = self.0.lock() else { return };
        let log = &mut *log;
        log.last_activity = Instant::now();
        log.checker.host_bytes(device, bytes);
        // A reaction is the first command sent after its misbehaviour.
        let commands = log.checker.commands();
        log.awaiting.retain(|&(i, seen)| match commands.get(seen) {
            Some(c) => {
                log.reactions[i].2 = c.clone();
                false
            }
            None => true,
        });
        log.push(Dir::Host, bytes, Vec::new());
    }

    fn hand_bytes(&mut self, device: &Device, bytes: &[u8]) -> Shaped {
        let Ok(mut log) = self.0.lock() else { return Shaped::plain(bytes) };
        let log = &mut *log;
        let state = log.checker.answer_state(device);
        let before = log.misbehave.fired().len();
        let shaped = log.misbehave.shape(device, bytes, &state);
        let new: Vec<Fired> = log.misbehave.fired()[before..].to_vec();
        log.checker.hand_bytes(device, &shaped.bytes, !new.is_empty());
        let seen = log.checker.commands().len();
        for f in &new {
            log.reactions.push((f.op.name().to_string(), f.state.clone(), "-".to_string()));
            log.awaiting.push((log.reactions.len() - 1, seen));
        }
        let marks = new
            .iter()
            .map(|f| format!("misbehaviour {} at answer {} ({}): {}", f.op, f.answer, f.state, f.what))
            .collect();
        let mut quiet = Instant::now();
        if let Some((_, d)) = shaped.hold {
            quiet += d;
        }
        log.last_activity = log.last_activity.max(quiet);
        log.push(Dir::Hand, &shaped.bytes, marks);
        if shaped.hang_up {
            log.hung_up = true;
            if let Some(mut h) = log.hang_up.take() {
                h.stop();
            }
        }
        shaped
    }

    fn delivered(&mut self, _device: &Device) {
        if let Ok(mut log) = self.0.lock() {
            log.checker.delivered();
        }
    }

    fn discarded(&mut self, _device: &Device) {
        if let Ok(mut log) = self.0.lock() {
            log.checker.discarded();
        }
    }
}

/// Longest stderr kept.
const STDERR_CAP: usize = 256 * 1024;

/// Runs the host once against a hand that follows `schedule`.
pub fn run_once(spec: &HostRun, schedule: &Schedule) -> Result<RunResult, RunError> {
    run_once_until(spec, schedule, &AtomicBool::new(false))
}

/// [`run_once`], called off ([`RunError::Cancelled`], the host killed) once `cancel` is set.
pub fn run_once_until(spec: &HostRun, schedule: &Schedule, cancel: &AtomicBool) -> Result<RunResult, RunError> {
    let program = spec.command.first().ok_or(RunError::NoCommand)?;
    let started = Instant::now();
    let mut opts = SimOptions::new(spec.profile.clone());
    opts.seed = spec.hand_seed;
    opts.time = spec.time;
    opts.pace = spec.pace;
    let mut engine = Engine::new(&opts)?;
    let (mut stop, stop_rx) = stop_pair()?;
    let (hang_up, hang_rx) = stop_pair()?;
    let log = Arc::new(Mutex::new(Log {
        misbehave: Misbehave::new(schedule.clone(), engine.device()),
        checker: HostChecker::new(spec.profile.clone()),
        exchanges: Vec::new(),
        last_activity: started,
        hang_up: Some(hang_up),
        hung_up: false,
        reactions: Vec::new(),
        awaiting: Vec::new(),
    }));
    engine.set_tap(Box::new(Tap(log.clone())));

    // The hand: its transport in a thread; the line closes (hangs up) when the thread ends.
    let (port, url, hand) = match spec.transport {
        Transport::Pty => {
            let mut pty = Pty::open(None)?;
            pty.match_speed(&engine)?;
            let path = pty.path().display().to_string();
            let h = std::thread::spawn(move || pty.serve(&mut engine, &[stop_rx.as_fd(), hang_rx.as_fd()]));
            (path.clone(), path, h)
        }
        Transport::Tcp => {
            let mut server = TcpServer::bind("127.0.0.1:0", false)?;
            let addr = server.local_addr().to_string();
            let h = std::thread::spawn(move || server.serve(&mut engine, &[stop_rx.as_fd(), hang_rx.as_fd()]));
            (addr.clone(), format!("socket://{addr}"), h)
        }
    };

    let args: Vec<String> =
        spec.command[1..].iter().map(|a| a.replace("{port}", &port).replace("{url}", &url)).collect();
    let mut child = Command::new(program)
        .args(&args)
        .env("GCL_PORT", &port)
        .env("GCL_PORT_URL", &url)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .process_group(0)
        .spawn()
        .map_err(|source| RunError::Spawn { command: program.clone(), source })?;
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    let mut err_pipe = child.stderr.take();
    let err_reader = std::thread::spawn(move || {
        let mut kept = Vec::new();
        if let Some(p) = &mut err_pipe {
            let mut buf = [0u8; 8192];
            while let Ok(n) = p.read(&mut buf) {
                if n == 0 {
                    break;
                }
                if kept.len() < STDERR_CAP {
                    kept.extend_from_slice(&buf[..n.min(STDERR_CAP - kept.len())]);
                }
            }
        }
        String::from_utf8_lossy(&kept).into_owned()
    });
    let (tx, rx) = mpsc::channel();
    let waiter = std::thread::spawn(move || {
        let _ = tx.send(child.wait());
    });

    let state = |log: &Arc<Mutex<Log>>| log.lock().map(|l| l.checker.state()).unwrap_or_default();
    let mut cancelled = false;
    let end = loop {
        match rx.recv_timeout(Duration::from_millis(5)) {
            Ok(Ok(status)) => {
                break match (status.code(), status.signal()) {
                    (Some(c), _) => HostEnd::Exit(c),
                    (None, Some(s)) => HostEnd::Signal(s),
                    (None, None) => HostEnd::Exit(-1),
                };
            }
            Ok(Err(e)) => return Err(RunError::Io(e)),
            Err(mpsc::RecvTimeoutError::Disconnected) => break HostEnd::Exit(-1),
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        let now = Instant::now();
        let quiet_since = log.lock().map(|l| l.last_activity).unwrap_or(started);
        cancelled = cancel.load(Ordering::Relaxed);
        let verdict = if cancelled {
            Some(HostEnd::Exit(-1))
        } else if now.duration_since(started) > spec.budget {
            Some(HostEnd::OverBudget(state(&log)))
        } else if now > quiet_since && now.duration_since(quiet_since) > spec.timeout_hang {
            Some(HostEnd::Hung(state(&log)))
        } else {
            None
        };
        if let Some(v) = verdict {
            let _ = nix::sys::signal::killpg(pid, nix::sys::signal::Signal::SIGKILL);
            let _ = rx.recv_timeout(Duration::from_secs(5));
            break v;
        }
    };
    // Whatever the host left behind in its group goes with it.
    let _ = nix::sys::signal::killpg(pid, nix::sys::signal::Signal::SIGKILL);
    let _ = waiter.join();
    let stderr = err_reader.join().unwrap_or_default();
    stop.stop();
    let served = hand.join();
    if let Ok(Err(e)) = served {
        return Err(RunError::Sim(e));
    }
    if cancelled {
        return Err(RunError::Cancelled);
    }
    let mut log = log.lock().map_err(|_| std::io::Error::other("the hand's thread panicked"))?;
    if !log.hung_up {
        log.checker.finish();
    }
    let mut violations = log.checker.violations().to_vec();
    // After a hang-up the host cannot leave cleanly; and a host killed for hanging did not leave.
    if log.hung_up || matches!(end, HostEnd::Hung(_) | HostEnd::OverBudget(_)) {
        violations.retain(|v| v.clause != super::check::HostClause::LeavesCleanly);
    }
    Ok(RunResult {
        end,
        stderr,
        exchanges: std::mem::take(&mut log.exchanges),
        fired: log.misbehave.fired().to_vec(),
        violations,
        commands: log.checker.commands().to_vec(),
        reactions: log.reactions.clone(),
        answers: log.misbehave.answers(),
        elapsed: started.elapsed(),
    })
}
