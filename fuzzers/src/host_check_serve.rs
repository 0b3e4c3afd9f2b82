//! `gcl check-host --serve`: a graded simulated hand that serves whoever connects (a test
//! suite's host code, for example the `gcl_hand` pytest fixture) until it is stopped, then
//! grades the whole session as `gcl check-host` grades one host command
//! ([`crate::host_check::grade`]).
//!
//! The hand is the `gcl sim` engine on a pty or a loopback TCP port, in this thread; the tap
//! of `gcl fuzz host` and `gcl check-host` feeds both directions to the same
//! [`crate::fuzz::host::HostChecker`], and may shape the
//! answers with a seeded misbehaviour [`Schedule`] (the schedules `gcl fuzz host` draws), so
//! a test body can be run under misbehaviours. Several connections in one session are one
//! session to the checker, as a serial line is one line however often it is opened.
//!
//! With `--misbehave SEED:I`, a `Misbehave` plays that run's schedule. The session is graded by
//! `host_check::grade_served` (`host_check::grade` is the body of `check_host`). Nothing judged is
//! never a pass: a session in which the host never opened the port or sent no byte
//! (`fuzz::host::unreached`) is an ERROR case `host-session` (`report::SESSION_CASE`) with every
//! clause SKIP ("not exercised"), and a clause no byte of the host exercised is SKIP too
//! (`host_check::not_exercised`); `RunReport::judged` says how much a host report judged, and every
//! writer shows it.

use std::os::fd::{AsFd, BorrowedFd};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use gcl_model::{Fault, Profile};

use crate::fuzz::host::session::{Log, Tap};
use crate::fuzz::host::{HostEnd, RunError, RunResult, Transport};
use crate::sim::misbehave::Schedule;
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

/// Serves the hand until one of `stops` becomes readable (or a `hang-up` misbehaviour closes
/// the line), telling `ready` where it listens first; returns the session as a run that no
/// host process made ([`HostEnd::Served`]), for [`crate::host_check::grade_served`].
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
    let log = Arc::new(Mutex::new(Log::new(&opts.schedule, engine.device(), opts.profile.clone(), hang_up)));
    engine.set_tap(Box::new(Tap(log.clone())));
    let mut all: Vec<BorrowedFd<'_>> = stops.to_vec();
    all.push(hang_rx.as_fd());
    match opts.transport {
        Transport::Pty => {
            let mut pty = Pty::open(None, engine.line_baud())?;
            crate::fuzz::host::session::tell_garbling(&mut pty, &log);
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
    let ended_in = log.checker.state();
    // After a hang-up the host cannot leave cleanly.
    if !log.hung_up {
        log.checker.finish(true);
    }
    let violations = log.checker.violations().to_vec();
    Ok(RunResult {
        end: HostEnd::Served,
        stack: None,
        leftovers: Vec::new(),
        gave_up_after: None,
        waits: Vec::new(),
        stderr: String::new(),
        observations: 0,
        wrong_values: Vec::new(),
        exchanges: log.take_exchanges(),
        fired: log.misbehave.fired().to_vec(),
        violations,
        commands: log.checker.commands().to_vec(),
        reactions: Vec::new(),
        ended_in,
        answers: log.misbehave.answers(),
        answer_kinds: log.misbehave.kinds().to_vec(),
        elapsed: started.elapsed(),
        talking_at_end: false,
        port_opened: log.opened,
        edges: None,
    })
}
