//! `gcl check-host --serve`: a graded simulated hand that serves whoever connects (a test
//! suite's host code, for example the `gcl_hand` pytest fixture) until it is stopped, then
//! grades the whole session as `gcl check-host` grades one host command
//! ([`crate::check_host::grade`]).
//!
//! The hand is the `gcl sim` engine on a pty or a loopback TCP port, in this thread; a tap
//! feeds both directions to the same [`HostChecker`] `gcl check-host` uses, and may shape the
//! answers with a seeded misbehaviour [`Schedule`] (the schedules `gcl fuzz host` draws), so
//! a test body can be run under misbehaviours. Several connections in one session are one
//! session to the checker, as a serial line is one line however often it is opened.

use std::os::fd::{AsFd, BorrowedFd};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use gcl_model::{Device, Fault, Profile};

use crate::fuzz::host::{Dir, Exchange, HostChecker, HostClause, HostEnd, RunError, RunResult, Transport};
use crate::sim::misbehave::{Fired, LineTap, Misbehave, Schedule, Shaped};
use crate::sim::{Engine, Pace, SimOptions, TimeMode, pty::Pty, stop_pair, tcp::TcpServer};

/// What a served hand is.
#[derive(Debug, Clone)]
pub struct ServeOptions {
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
    /// Deliberate firmware bugs of the hand (`gcl sim --fault`).
    pub faults: Vec<Fault>,
    /// Misbehaviours on its answers (empty: a perfect hand).
    pub schedule: Schedule,
}

/// Where the served hand is, told once it is listening.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Served {
    /// The pty's path or `127.0.0.1:N`.
    pub port: String,
    /// The same port as a pyserial URL (the path itself, or `socket://127.0.0.1:N`).
    pub url: String,
}

struct Log {
    misbehave: Misbehave,
    checker: HostChecker,
    exchanges: Vec<Exchange>,
    hung_up: bool,
    hang_up: Option<crate::sim::StopHandle>,
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
        if let Ok(mut log) = self.0.lock() {
            log.checker.host_bytes(device, bytes);
            log.push(Dir::Host, bytes, Vec::new());
        }
    }

    fn hand_bytes(&mut self, device: &Device, bytes: &[u8]) -> Shaped {
        let Ok(mut log) = self.0.lock() else { return Shaped::plain(bytes) };
        let log = &mut *log;
        let state = log.checker.answer_state(device);
        let before = log.misbehave.fired().len();
        let shaped = log.misbehave.shape(device, bytes, &state);
        let new: Vec<Fired> = log.misbehave.fired()[before..].to_vec();
        // Changed in any way (a silence drops every answer after it; a delay holds one), as
        // `gcl fuzz host` judges it: the host's reaction to it is a note, not a violation.
        let misbehaved = !new.is_empty() || shaped.bytes != bytes || shaped.hold.is_some() || shaped.hang_up;
        log.checker.hand_bytes(device, &shaped.bytes, misbehaved);
        if shaped.restart {
            log.checker.restarted();
        }
        let marks = new
            .iter()
            .map(|f| format!("misbehaviour {} at answer {} ({}): {}", f.op, f.answer, f.state, f.what))
            .collect();
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

    fn connection(&mut self, _device: &Device, open: bool) {
        if let Ok(mut log) = self.0.lock() {
            log.checker.connection(open);
        }
    }

    fn host_unread(&mut self, unread: bool) {
        if let Ok(mut log) = self.0.lock() {
            log.checker.host_unread(unread);
        }
    }
}

/// Serves the hand until one of `stops` becomes readable (or a `hang-up` misbehaviour closes
/// the line), telling `ready` where it listens first; returns the session as a run that ended
/// with exit code 0, for [`crate::check_host::grade`].
pub fn serve(
    opts: &ServeOptions,
    stops: &[BorrowedFd<'_>],
    ready: &mut dyn FnMut(&Served),
) -> Result<RunResult, RunError> {
    let started = Instant::now();
    let mut sim = SimOptions::new(opts.profile.clone());
    sim.seed = opts.hand_seed;
    sim.time = opts.time;
    sim.pace = opts.pace;
    sim.faults = opts.faults.clone();
    let mut engine = Engine::new(&sim)?;
    let (hang_up, hang_rx) = stop_pair()?;
    let log = Arc::new(Mutex::new(Log {
        misbehave: Misbehave::new(opts.schedule.clone(), engine.device()),
        checker: HostChecker::new(opts.profile.clone()),
        exchanges: Vec::new(),
        hung_up: false,
        hang_up: Some(hang_up),
    }));
    engine.set_tap(Box::new(Tap(log.clone())));
    let mut all: Vec<BorrowedFd<'_>> = stops.to_vec();
    all.push(hang_rx.as_fd());
    match opts.transport {
        Transport::Pty => {
            let mut pty = Pty::open(None)?;
            pty.match_speed(&engine)?;
            let path = pty.path().display().to_string();
            ready(&Served { port: path.clone(), url: path });
            pty.serve(&mut engine, &all)?;
        }
        Transport::Tcp => {
            let mut server = TcpServer::bind("127.0.0.1:0", false)?;
            let addr = server.local_addr().to_string();
            ready(&Served { port: addr.clone(), url: format!("socket://{addr}") });
            server.serve(&mut engine, &all)?;
        }
    }
    let mut log = log.lock().map_err(|_| std::io::Error::other("the hand's tap panicked"))?;
    if !log.hung_up {
        log.checker.finish();
    }
    let mut violations = log.checker.violations().to_vec();
    // After a hang-up the host cannot leave cleanly.
    if log.hung_up {
        violations.retain(|v| v.clause != HostClause::LeavesCleanly);
    }
    Ok(RunResult {
        end: HostEnd::Exit(0),
        stack: None,
        leftovers: Vec::new(),
        gave_up_after: None,
        stderr: String::new(),
        observations: 0,
        wrong_values: Vec::new(),
        exchanges: std::mem::take(&mut log.exchanges),
        fired: log.misbehave.fired().to_vec(),
        violations,
        commands: log.checker.commands().to_vec(),
        reactions: Vec::new(),
        answers: log.misbehave.answers(),
        elapsed: started.elapsed(),
    })
}
