//! `gcl sim` behaves like a hand on a cable at the port: a pty opens and closes like a serial
//! port (no banner for a host that opens late, unread answers discarded on close), TCP
//! discards unread output on disconnect and honours half-close, nothing is lost when the host
//! reads late (backpressure), and `--stdio` stops on SIGTERM whatever it is blocked on.

use crate::sim_support;

use std::io::{Read, Write};
use std::net::{Shutdown, TcpStream};
use std::os::fd::AsFd;
use std::os::unix::fs::OpenOptionsExt;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use sim_support::{GCL, SimProcess, Transport, open_port};

/// Everything that arrives within `quiet` of the previous byte, stopping at `limit` overall.
fn read_quiet(f: &mut (impl Read + AsFd), quiet: Duration, limit: Duration) -> Vec<u8> {
    sim_support::read_port(f, &|_| false, Some(quiet), limit)
}

const QUIET: Duration = Duration::from_millis(400);

#[test]
fn a_host_that_opens_the_pty_after_start_up_sees_no_banner_but_sees_a_reset() {
    // The defaults of `gcl sim`: real time, paced at 9600.
    let sim = SimProcess::start_exact(Transport::Pty, &["--profile", "bh8-262"]);
    std::thread::sleep(Duration::from_millis(300));
    let mut port = open_port(&sim.address);
    assert_eq!(read_quiet(&mut port, QUIET, Duration::from_secs(2)), b"", "no banner for a late host");
    port.write_all(b"\r").unwrap();
    assert_eq!(read_quiet(&mut port, QUIET, Duration::from_secs(5)), b"\n\r=> ");
    port.write_all(b"RESET\r").unwrap();
    let got = read_quiet(&mut port, QUIET, Duration::from_secs(10));
    let text = String::from_utf8_lossy(&got);
    assert!(text.starts_with("RESET\n\rBarrettHand Firmware\n\r") && text.ends_with("\n\r=> "), "{text:?}");
}

#[test]
fn an_answer_left_unread_is_gone_after_a_close_and_reopen() {
    let sim = SimProcess::start_exact(Transport::Pty, &["--profile", "bh8-262"]);
    let mut port = open_port(&sim.address);
    port.write_all(b"\r").unwrap();
    assert_eq!(read_quiet(&mut port, QUIET, Duration::from_secs(5)), b"\n\r=> ");
    // A command whose answer the host never reads (like PSET BAUD before a reopen).
    port.write_all(b"FGET DP\r").unwrap();
    std::thread::sleep(Duration::from_millis(300));
    drop(port);
    // A host that changed the rate waits before it reopens (Barrett's API: about a second).
    std::thread::sleep(Duration::from_millis(200));
    let mut port = open_port(&sim.address);
    port.write_all(b"\r").unwrap();
    assert_eq!(read_quiet(&mut port, QUIET, Duration::from_secs(5)), b"\n\r=> ", "exactly one fresh prompt");
}

#[test]
fn tcp_discards_unread_output_on_disconnect() {
    let sim = SimProcess::start_exact(Transport::Tcp, &["--profile", "bh8-262"]);
    let mut s = TcpStream::connect(&sim.address).unwrap();
    s.write_all(b"FGET DP\r").unwrap();
    std::thread::sleep(Duration::from_millis(300));
    drop(s);
    std::thread::sleep(Duration::from_millis(200));
    let mut s = TcpStream::connect(&sim.address).unwrap();
    s.write_all(b"\r").unwrap();
    assert_eq!(read_quiet(&mut s, QUIET, Duration::from_secs(5)), b"\n\r=> ");
}

#[test]
fn a_tcp_client_that_half_closes_still_gets_its_answer() {
    let sim = SimProcess::start_exact(Transport::Tcp, &["--profile", "seed"]);
    for _ in 0..3 {
        let mut s = TcpStream::connect(&sim.address).unwrap();
        s.write_all(b"FGET DP\r").unwrap();
        s.shutdown(Shutdown::Write).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        let mut got = Vec::new();
        // The simulator ends the stream after the answer: read to the end.
        let _ = s.read_to_end(&mut got);
        assert_eq!(got, b"FGET DP\n\r1000 1000 1000 150\n\r=> ");
    }
}

/// 10,000 commands written at once while the host reads late: every answer arrives.
fn pipeline(what: &str, mut write: impl Write + Send + 'static, read: &mut (impl Read + AsFd)) {
    const N: usize = 10_000;
    let answer = b"FGET DP\n\r1000 1000 1000 150\n\r=> ";
    let writer = std::thread::spawn(move || {
        let all = b"FGET DP\r".repeat(N);
        write.write_all(&all).is_ok()
    });
    // Read late, so that the simulator's output queue fills and it has to stop reading.
    std::thread::sleep(Duration::from_millis(500));
    let want = N * answer.len();
    let got = sim_support::read_port(read, &|g| g.len() >= want, Some(Duration::from_secs(5)), Duration::from_secs(30));
    assert_eq!(got.len(), want, "{what}: bytes lost");
    assert!(writer.join().unwrap(), "{what}: the writer was cut off");
    assert!(got.chunks(answer.len()).all(|c| c == answer), "{what}: answers out of shape");
}

#[test]
fn ten_thousand_pipelined_commands_lose_no_byte_over_the_pty_and_tcp() {
    for t in [Transport::Pty, Transport::Tcp] {
        let sim = SimProcess::start(t, &["--profile", "seed", "--unpaced"]);
        match t {
            Transport::Pty => {
                let mut port = open_port(&sim.address);
                // The writer gets a blocking descriptor of its own.
                let w = std::fs::OpenOptions::new()
                    .write(true)
                    .custom_flags(nix::libc::O_NOCTTY)
                    .open(&sim.address)
                    .unwrap();
                pipeline("pty", w, &mut port);
            }
            _ => {
                let mut s = TcpStream::connect(&sim.address).unwrap();
                let w = s.try_clone().unwrap();
                pipeline("tcp", w, &mut s);
            }
        }
    }
}

#[test]
fn stdio_stops_on_sigterm_while_nobody_reads_its_output() {
    let mut child = Command::new(GCL)
        .args(["sim", "--stdio", "--profile", "seed"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let _stdout = child.stdout.take().unwrap(); // held open, never read
    let writer = std::thread::spawn(move || {
        let chunk = b"FGET DP\r".repeat(1000);
        for _ in 0..200 {
            if stdin.write_all(&chunk).is_err() {
                break;
            }
        }
    });
    // Long enough for the pipe to fill and the simulator to stop reading.
    std::thread::sleep(Duration::from_millis(1500));
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).unwrap();
    let end = Instant::now() + Duration::from_secs(10);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if Instant::now() > end {
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    if status.is_none() {
        let _ = child.kill();
        let _ = child.wait();
    }
    drop(_stdout);
    let _ = writer.join();
    let status = status.expect("gcl sim --stdio ignored SIGTERM while its output was not read");
    assert_eq!(status.code(), Some(0));
}

#[test]
fn a_host_at_another_speed_than_the_hand_exchanges_garbage_both_ways() {
    use nix::sys::termios::BaudRate;
    use sim_support::{read_port, set_port_speed};
    let log = tempfile::NamedTempFile::new().unwrap();
    let sim = SimProcess::start_logged(Transport::Pty, &["--profile", "bh8-262"], log.reopen().unwrap());
    let mut port = open_port(&sim.address);
    // The pty starts at the hand's rate: a host that sets no speed talks.
    port.write_all(b"\r").unwrap();
    assert_eq!(read_quiet(&mut port, QUIET, Duration::from_secs(5)), b"\n\r=> ");
    // The host forgets that the hand is at 9600.
    set_port_speed(&port, BaudRate::B38400);
    port.write_all(b"FGET DP\r").unwrap();
    let got = read_quiet(&mut port, QUIET, Duration::from_secs(5));
    assert!(!got.windows(3).any(|w| w == b"=> "), "no prompt makes it through: {got:?}");
    assert!(got.iter().all(|b| *b >= 0x80), "only garbage: {got:?}");
    // Back at the hand's rate, ^C clears what garbage the hand received.
    set_port_speed(&port, BaudRate::B9600);
    port.write_all(b"\x03").unwrap();
    let got = read_port(&mut port, &|b| b.ends_with(b"\n\r=> "), None, Duration::from_secs(5));
    assert!(got.ends_with(b"\n\r=> "), "{got:?}");
    port.write_all(b"FGET DP\r").unwrap();
    assert_eq!(read_quiet(&mut port, QUIET, Duration::from_secs(5)), b"FGET DP\n\r8500 8500 8500 1575\n\r=> ");
    // The simulator said why, once for the one change of speed, however many bytes crossed.
    let said = std::fs::read_to_string(log.path()).unwrap();
    let line = "gcl sim: the host opened the port at 38400 baud; the hand runs at 9600: bytes are garbled as on a \
                real line (--no-speed-check to turn this off)";
    assert_eq!(said.lines().filter(|l| l.contains("baud; the hand runs at")).collect::<Vec<_>>(), vec![line], "{said}");

    // --no-speed-check: the speed is ignored, and nothing is said.
    let log = tempfile::NamedTempFile::new().unwrap();
    let sim =
        SimProcess::start_logged(Transport::Pty, &["--profile", "bh8-262", "--no-speed-check"], log.reopen().unwrap());
    let mut port = open_port(&sim.address);
    set_port_speed(&port, BaudRate::B38400);
    port.write_all(b"\r").unwrap();
    assert_eq!(read_quiet(&mut port, QUIET, Duration::from_secs(5)), b"\n\r=> ");
    assert!(!std::fs::read_to_string(log.path()).unwrap().contains("garbled"));
}

/// Everything a serialport port receives until it has been quiet for its timeout.
fn read_quiet_serial(port: &mut serialport::TTYPort) -> Vec<u8> {
    let mut got = Vec::new();
    let mut buf = [0u8; 256];
    loop {
        match port.read(&mut buf) {
            Ok(0) => return got,
            Ok(n) => got.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => return got,
            Err(e) => panic!("reading the port: {e}"),
        }
    }
}

/// The serialport crate, as Rust host libraries use it, sets every rate as an arbitrary one
/// (termios2, `BOTHER`), which the simulator used to leave unjudged: a Rust host at the wrong
/// speed talked. It is judged like a standard rate; a rate a real UART understands (within
/// 2 % of the hand's) talks.
#[test]
fn a_rust_host_at_the_wrong_speed_is_garbled_too() {
    let log = tempfile::NamedTempFile::new().unwrap();
    let sim = SimProcess::start_logged(Transport::Pty, &["--profile", "bh8-262"], log.reopen().unwrap());
    let mut port = serialport::new(&sim.address, 115_200).timeout(QUIET).open_native().unwrap();
    port.write_all(b"FGET DP\r").unwrap();
    let got = read_quiet_serial(&mut port);
    assert!(got.iter().all(|b| *b >= 0x80), "at 115200 nothing the hand sends is readable: {got:?}");
    // 9650 bit/s: 0.5 % off the hand's 9600, which a UART takes in its stride.
    serialport::SerialPort::set_baud_rate(&mut port, 9650).unwrap();
    port.write_all(b"\x03").unwrap();
    assert!(read_quiet_serial(&mut port).ends_with(b"\n\r=> "));
    port.write_all(b"FGET DP\r").unwrap();
    assert_eq!(read_quiet_serial(&mut port), b"FGET DP\n\r8500 8500 8500 1575\n\r=> ");
    let said = std::fs::read_to_string(log.path()).unwrap();
    assert_eq!(
        said.lines().filter(|l| l.contains("baud; the hand runs at")).collect::<Vec<_>>(),
        vec![
            "gcl sim: the host opened the port at 115200 baud; the hand runs at 9600: bytes are garbled as on a real \
             line (--no-speed-check to turn this off)"
        ],
        "{said}"
    );
}
