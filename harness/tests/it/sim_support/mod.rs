//! Shared by the `sim_*` and `client_*` integration tests: start `gcl sim` as a child process
//! on a pty, TCP or stdio, and open a [`Hand`] on it. Children are killed and reaped on drop.

#![allow(dead_code)] // each test file uses a part

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use gcl_host::client::{Hand, Timeouts};
use gcl_host::links::{ExecLink, StderrMode};
use gcl_host::target::OpenOptions;

/// The `gcl` binary under test.
pub const GCL: &str = env!("CARGO_BIN_EXE_gcl");

/// A transport `gcl sim` serves on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transport {
    Pty,
    Tcp,
    Stdio,
}

pub const ALL: [Transport; 3] = [Transport::Pty, Transport::Tcp, Transport::Stdio];

/// A `gcl sim --pty` or `--tcp` child.
pub struct SimProcess {
    child: Child,
    /// The first line of its stdout: the pty path or the bound address.
    pub address: String,
    pub transport: Transport,
}

impl SimProcess {
    /// Starts `gcl sim <transport flag> <args>` and reads the address it prints. Unless `args`
    /// choose a time mode, the child runs in fast time (unpaced), the opt-in speed-up: most
    /// tests check answers, not timing.
    pub fn start(transport: Transport, args: &[&str]) -> SimProcess {
        let fast: &[&str] = if args.contains(&"--time") { &[] } else { &["--time", "fast"] };
        SimProcess::start_exact(transport, &[args, fast].concat())
    }

    /// Starts `gcl sim <transport flag> <args>` with exactly these arguments (the defaults of
    /// `gcl sim` otherwise: real time, paced at the hand's BAUD).
    pub fn start_exact(transport: Transport, args: &[&str]) -> SimProcess {
        SimProcess::start_logged(transport, args, Stdio::null())
    }

    /// [`SimProcess::start_exact`] with its stderr going to `stderr`.
    pub fn start_logged(transport: Transport, args: &[&str], stderr: impl Into<Stdio>) -> SimProcess {
        let flag: &[&str] = match transport {
            Transport::Pty => &["--pty"],
            Transport::Tcp => &["--tcp", "127.0.0.1:0"],
            Transport::Stdio => panic!("stdio children are started by the exec link"),
        };
        let mut child = Command::new(GCL)
            .arg("sim")
            .args(flag)
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(stderr)
            .spawn()
            .expect("spawn gcl sim");
        let stdout = child.stdout.take().expect("stdout");
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut line = String::new();
            let _ = BufReader::new(stdout).read_line(&mut line);
            let _ = tx.send(line);
        });
        let line = match rx.recv_timeout(Duration::from_secs(30)) {
            Ok(l) => l,
            Err(_) => {
                let _ = child.kill();
                let _ = child.wait();
                panic!("gcl sim printed no address");
            }
        };
        let address = line.trim().to_string();
        assert!(!address.is_empty(), "gcl sim exited without an address");
        SimProcess { child, address, transport }
    }

    /// The `--target` text for this simulator.
    pub fn target(&self) -> String {
        match self.transport {
            Transport::Pty => format!("serial:{}", self.address),
            _ => format!("tcp://{}", self.address),
        }
    }

    /// A new client (a new open of the pty, a new TCP connection). A pty this process just
    /// closed may still be held for a moment by a child another test is starting (until it
    /// execs, it holds a copy of every descriptor, and with it the port's lock; every test
    /// file shares this process, issue 41): a port that is busy is opened again, for 10 s.
    pub fn hand(&self, profile: &str) -> Hand {
        let opts = OpenOptions { profile: Some(profile.into()), ..Default::default() };
        let target = self.target().parse().unwrap();
        let until = Instant::now() + Duration::from_secs(10);
        let mut h = loop {
            match Hand::open(&target, &opts) {
                Err(e) if format!("{e:?}").contains("is in use by another program") && Instant::now() < until => {
                    std::thread::sleep(Duration::from_millis(20));
                }
                r => break r.expect("open the simulator"),
            }
        };
        h.set_timeouts(test_timeouts());
        h
    }

    /// SIGTERM, then the exit status.
    pub fn terminate(&mut self) -> ExitStatus {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
        let end = Instant::now() + Duration::from_secs(20);
        loop {
            if let Ok(Some(s)) = self.child.try_wait() {
                return s;
            }
            assert!(Instant::now() < end, "gcl sim ignored SIGTERM");
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Whether it is still running.
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// SIGKILL, as a crash would.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub fn test_timeouts() -> Timeouts {
    Timeouts { sync: Duration::from_millis(300), ..Timeouts::default() }
}

/// The argv of a `gcl sim --stdio` child.
pub fn stdio_argv(args: &[&str]) -> Vec<String> {
    let mut v = vec![GCL.to_string(), "sim".into(), "--stdio".into()];
    v.extend(args.iter().map(|s| s.to_string()));
    v
}

/// A hand on a `gcl sim --stdio` child.
pub fn stdio_hand(profile: &str, args: &[&str]) -> Hand {
    let mut all = vec!["--profile", profile];
    all.extend_from_slice(args);
    let link = ExecLink::spawn(&stdio_argv(&all), StderrMode::Null).expect("spawn gcl sim --stdio");
    let mut h = Hand::new(Box::new(link), gcl_host::profiles::load(profile).unwrap());
    h.set_timeouts(test_timeouts());
    h
}

/// A simulator (none for stdio, whose child belongs to the hand's link) and a hand on it.
pub fn start(transport: Transport, profile: &str, args: &[&str]) -> (Option<SimProcess>, Hand) {
    if transport == Transport::Stdio {
        return (None, stdio_hand(profile, args));
    }
    let mut all = vec!["--profile", profile];
    all.extend_from_slice(args);
    let sim = SimProcess::start(transport, &all);
    let hand = sim.hand(profile);
    (Some(sim), hand)
}

/// Deterministic noise (no dependency on a random crate): a 64-bit LCG.
pub fn noise(seed: u64, len: usize) -> Vec<u8> {
    let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    (0..len)
        .map(|_| {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 56) as u8
        })
        .collect()
}

/// A pty opened as a host program opens a serial port (no controlling tty, non-blocking, no
/// discard of stale input: the test sees exactly what the port holds).
pub fn open_port(path: &str) -> std::fs::File {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(nix::libc::O_NOCTTY | nix::libc::O_NONBLOCK)
        .open(path)
        .expect("open the pty")
}

/// Reads from a non-blocking port until `done(bytes)` or `limit` passes, or, with `quiet`,
/// until nothing came for that long. Returns what arrived.
pub fn read_port(
    port: &mut (impl std::io::Read + std::os::fd::AsFd),
    done: &dyn Fn(&[u8]) -> bool,
    quiet: Option<Duration>,
    limit: Duration,
) -> Vec<u8> {
    use nix::poll::{PollFd, PollFlags, PollTimeout};
    use std::os::fd::AsFd;
    let end = Instant::now() + limit;
    let mut got = Vec::new();
    let mut buf = [0u8; 4096];
    while !done(&got) {
        let mut wait = end.saturating_duration_since(Instant::now());
        if let Some(q) = quiet {
            wait = wait.min(q);
        }
        if wait.is_zero() {
            break;
        }
        let mut fds = [PollFd::new(port.as_fd(), PollFlags::POLLIN)];
        let ms = PollTimeout::try_from(wait.as_millis().min(60_000) as i32).unwrap_or(PollTimeout::MAX);
        if !nix::poll::poll(&mut fds, ms).is_ok_and(|n| n > 0) {
            break;
        }
        match port.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => got.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(_) => break,
        }
    }
    got
}

/// Sets the speed of a port as a host program does (`cfsetspeed`, `tcsetattr`).
pub fn set_port_speed(port: &std::fs::File, speed: nix::sys::termios::BaudRate) {
    use nix::sys::termios;
    let mut t = termios::tcgetattr(port).unwrap();
    termios::cfsetspeed(&mut t, speed).unwrap();
    termios::tcsetattr(port, termios::SetArg::TCSANOW, &t).unwrap();
}
