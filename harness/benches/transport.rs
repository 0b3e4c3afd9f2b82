//! Transport figures of `gcl sim`: round-trip latency and pacing accuracy.
//!
//! Run with `cargo bench -p gcl-harness --bench transport`. The simulator runs in-process on
//! a thread (the same `gcl_harness::sim` code `gcl sim` runs), in fast time; the host side is
//! the host library over the `serial:` (pty) and `tcp:` links, as a user's program would be.
//!
//! Figures:
//! - `FGET P` round trip (echo, one output line, prompt), unpaced, profile bh8-262: median
//!   and p99 over the pty and over TCP. Aim: p99 under 200 µs.
//! - RealTime `A` exchange with 4-motor feedback (bh8-262 default flags: LFV, LFS, LFAP and
//!   LFDP on motors 1-4, a 21-byte block), unpaced: median and p99 over the pty and TCP.
//!   Aim: p99 under 200 µs.
//! - Pacing at `--baud 9600`: the `?` listing (about 1.6 kB) over the pty, bytes per second
//!   from the first byte to the last, against 960. Aim: within 2 %.
//!
//! - RealTime cycles per second over the pty with the line paced at the hand's BAUD (9600, then
//!   38400 after `FSET BAUD 384`), the seed's example blocks (3 bytes out, 6 back), divided
//!   by the series limit of the line (baud / 90). Aim: between 0.95 and 1.00.
//!
//! Also the median cycle against the line's 9 byte times, which load spikes on a shared machine
//! do not move. `-- --bench realtime` (or `pacing`, `round-trip`) runs only those figures.
//!
//! Without `--bench` (as under `cargo test --all-targets`) it runs a few iterations of each as
//! a smoke test and prints nothing but a line per figure.

use std::os::fd::AsFd;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use gcl_harness::sim::{Engine, Pace, SimOptions, StopHandle, pty::Pty, stop_pair, tcp::TcpServer};
use gcl_host::client::Hand;
use gcl_host::links::{SerialLink, TcpLink};
use gcl_host::{Link, LinkError};
use gcl_model::Profile;

struct Server {
    stop: StopHandle,
    thread: Option<JoinHandle<()>>,
    target: String,
}

impl Drop for Server {
    fn drop(&mut self) {
        self.stop.stop();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn options(pace: Pace) -> SimOptions {
    let mut o = SimOptions::new(Profile::builtin("bh8-262").unwrap());
    o.pace = pace;
    o
}

fn pty_server(pace: Pace) -> Server {
    let (stop, signal) = stop_pair().unwrap();
    let mut engine = Engine::new(&options(pace)).unwrap();
    let mut pty = Pty::open(None, engine.line_baud()).unwrap();
    let target = pty.path().display().to_string();
    let thread = std::thread::spawn(move || {
        pty.serve(&mut engine, &[signal.as_fd()]).unwrap();
    });
    Server { stop, thread: Some(thread), target }
}

fn tcp_server() -> Server {
    let (stop, signal) = stop_pair().unwrap();
    let mut server = TcpServer::bind("127.0.0.1:0", false).unwrap();
    let target = server.local_addr().to_string();
    let mut engine = Engine::new(&options(Pace::Unpaced)).unwrap();
    let thread = std::thread::spawn(move || {
        server.serve(&mut engine, &[signal.as_fd()]).unwrap();
    });
    Server { stop, thread: Some(thread), target }
}

fn link(kind: &str, server: &Server) -> Box<dyn Link> {
    match kind {
        "pty" => Box::new(SerialLink::open(&server.target, 9600).unwrap()),
        _ => Box::new(TcpLink::connect(&server.target, Duration::from_secs(5)).unwrap()),
    }
}

struct Stats {
    median: Duration,
    p99: Duration,
    n: usize,
}

fn stats(mut v: Vec<Duration>) -> Stats {
    v.sort();
    let n = v.len();
    Stats { median: v[n / 2], p99: v[(n * 99 / 100).min(n - 1)], n }
}

fn print(name: &str, s: &Stats) {
    let aim = if s.p99 < Duration::from_micros(200) { "met" } else { "MISSED" };
    println!(
        "{name:<34} median {:>7.1} µs   p99 {:>7.1} µs   ({} samples; aim p99 < 200 µs: {aim})",
        s.median.as_secs_f64() * 1e6,
        s.p99.as_secs_f64() * 1e6,
        s.n
    );
}

fn round_trips(kind: &str, server: &Server, n: usize) {
    let mut hand = Hand::new(link(kind, server), Profile::builtin("bh8-262").unwrap());
    hand.initialize().unwrap();
    for _ in 0..n / 10 + 1 {
        hand.command("FGET P").unwrap();
    }
    let mut v = Vec::with_capacity(n);
    for _ in 0..n {
        let t = Instant::now();
        hand.command("FGET P").unwrap();
        v.push(t.elapsed());
    }
    print(&format!("FGET P round trip, {kind}"), &stats(v));

    hand.rt_start("1234").unwrap();
    assert_eq!(hand.rt_layout().unwrap().feedback().size(), 21);
    for _ in 0..n / 10 + 1 {
        hand.rt_update_with(false, true).unwrap();
    }
    let mut v = Vec::with_capacity(n);
    for _ in 0..n {
        let t = Instant::now();
        hand.rt_update_with(false, true).unwrap();
        v.push(t.elapsed());
    }
    hand.rt_abort().unwrap();
    print(&format!("RealTime A, 4-motor feedback, {kind}"), &stats(v));
}

fn pacing(rounds: usize) -> Result<(), LinkError> {
    let server = pty_server(Pace::Fixed(9600));
    let mut l = SerialLink::open(&server.target, 9600)?;
    let mut total = 0usize;
    let mut time = Duration::ZERO;
    for _ in 0..rounds {
        // Everything pending first (the banner), then a quiet line.
        let mut sink = Vec::new();
        l.send(b"\r")?;
        while l.recv(&mut sink, Duration::from_millis(300))? > 0 {}
        l.send(b"?\r")?;
        let mut buf = Vec::new();
        let mut first: Option<(Instant, usize)> = None;
        let mut last = Instant::now();
        while !buf.ends_with(b"\n\r=> ") {
            let n = l.recv(&mut buf, Duration::from_secs(10))?;
            if n == 0 {
                break;
            }
            let now = Instant::now();
            if first.is_none() {
                first = Some((now, n));
            }
            last = now;
        }
        if let Some((t0, n0)) = first {
            // Bytes after the first read, over the time they took.
            total += buf.len() - n0;
            time += last - t0;
        }
    }
    let rate = total as f64 / time.as_secs_f64();
    let err = (rate - 960.0) / 960.0 * 100.0;
    println!(
        "{:<34} {rate:>7.1} B/s against 960 ({err:+.2} %; {total} bytes; aim within 2 %: {})",
        "pacing at --baud 9600, pty",
        if err.abs() <= 2.0 { "met" } else { "MISSED" }
    );
    Ok(())
}

/// The seed's RealTime example over the pty, paced at the hand's BAUD: `C v1 v2` out (3 bytes),
/// `* s1 d1 s2 d2 d4` back (6 bytes), one block at a time as a control loop does. Prints cycles
/// per second against the series limit of the line (baud / 10 / 9).
fn realtime_cycles(baud: u32, cycles: usize) -> Result<(), LinkError> {
    let (stop, signal) = stop_pair().unwrap();
    let mut o = SimOptions::new(Profile::builtin("seed").unwrap());
    // Fast time so that HI completes at once; the line is paced at the hand's BAUD all the same.
    o.pace = Pace::Hand;
    let mut engine = Engine::new(&o).unwrap();
    let mut pty = Pty::open(None, engine.line_baud()).unwrap();
    let target = pty.path().display().to_string();
    let thread = std::thread::spawn(move || {
        pty.serve(&mut engine, &[signal.as_fd()]).unwrap();
    });
    let _server = Server { stop, thread: Some(thread), target: target.clone() };
    let prompt = |b: &[u8]| b.ends_with(b"\n\r=> ");
    let mut l = SerialLink::open(&target, 9600)?;
    let mut buf = Vec::new();
    let line = |l: &mut SerialLink, text: &str| -> Result<(), LinkError> {
        let mut buf = Vec::new();
        l.send(format!("{text}\r").as_bytes())?;
        l.recv_until(&mut buf, Duration::from_secs(30), &prompt)?;
        Ok(())
    };
    line(&mut l, "")?;
    if baud != 9600 {
        // The hand changes its rate after the answer; the host then follows and reopens.
        line(&mut l, &format!("FSET BAUD {}", baud / 100))?;
        drop(l);
        l = SerialLink::open(&target, baud)?;
        line(&mut l, "")?;
    }
    for cmd in [
        "HI",
        "12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1",
        "4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1",
    ] {
        line(&mut l, cmd)?;
    }
    l.send(b"124LOOP\r")?;
    l.recv_until(&mut buf, Duration::from_secs(5), &|b: &[u8]| b.ends_with(b"*"))?;
    let mut each = Vec::with_capacity(cycles);
    let mut run = |n: usize, each: &mut Vec<Duration>| -> Result<Duration, LinkError> {
        let t = Instant::now();
        for _ in 0..n {
            let c = Instant::now();
            let mut fb = Vec::new();
            l.send(&[b'C', 0, 0])?;
            l.recv_until(&mut fb, Duration::from_secs(5), &|b: &[u8]| b.len() >= 6)?;
            assert_eq!(fb.len(), 6, "a 6-byte feedback block");
            each.push(c.elapsed());
        }
        Ok(t.elapsed())
    };
    run(5, &mut Vec::new())?;
    let took = run(cycles, &mut each)?;
    let rate = cycles as f64 / took.as_secs_f64();
    let limit = f64::from(baud) / 10.0 / 9.0;
    let ratio = rate / limit;
    println!(
        "{:<34} {rate:>7.1} cycles/s against a line limit of {limit:.1} (ratio {ratio:.3}; aim 0.95-1.00: {})",
        format!("RealTime 3+6 bytes, pty, {baud}"),
        if (0.95..=1.0).contains(&ratio) { "met" } else { "MISSED" }
    );
    // The typical cycle, which a loaded machine's stalls do not move: the line's 9 byte times
    // plus what the simulator, the pty and the host add.
    let s = stats(each);
    let line = 90.0 / f64::from(baud);
    println!(
        "{:<34} median cycle {:>7.1} µs against the line's {:.1} µs (ratio {:.3}); p99 {:.1} µs",
        format!("RealTime 3+6 bytes, pty, {baud}"),
        s.median.as_secs_f64() * 1e6,
        line * 1e6,
        line / s.median.as_secs_f64(),
        s.p99.as_secs_f64() * 1e6
    );
    let _ = l.send(&[3]);
    Ok(())
}

fn main() {
    let bench = std::env::args().any(|a| a == "--bench");
    // A word that is not an option picks figures: `round-trip`, `pacing` or `realtime`.
    let only: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with('-')).collect();
    let wanted = |figure: &str| only.is_empty() || only.iter().any(|o| figure.contains(o.as_str()));
    let n = if bench { 20_000 } else { 50 };
    if wanted("round-trip") {
        for kind in ["pty", "tcp"] {
            let server = if kind == "pty" { pty_server(Pace::Unpaced) } else { tcp_server() };
            round_trips(kind, &server, n);
        }
    }
    if wanted("pacing") {
        pacing(if bench { 3 } else { 1 }).unwrap();
    }
    if wanted("realtime") {
        for baud in [9600, 38400] {
            realtime_cycles(baud, if bench { baud as usize / 90 * 5 } else { 20 }).unwrap();
        }
    }
}
