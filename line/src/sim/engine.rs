//! The engine: the model, its clock, line timing in both directions, EEPROM persistence and
//! the trace, with no transport. A transport hands it what the host wrote
//! ([`Engine::input`], only while [`Engine::wants_input`]), wakes it at [`Engine::deadline`],
//! and writes what [`Engine::ready_output`] offers.
//!
//! Line timing: under pacing every byte costs its wire time (10 bits at the rate) in each
//! direction. A byte the host wrote reaches the model one byte time after the previous one
//! did (or after it was read, if the line was idle); a byte the hand wrote is offered to the
//! host one byte time after the previous one was. So no request/answer cycle beats the line.
//! [`Pace::Hand`] follows the hand's BAUD parameter: an answer goes out at the rate in force
//! when its command arrived, so the answer to the command that changes BAUD still goes at
//! the old rate, as on a hand.
//!
//! Nothing is dropped while a host listens: when output the host has not taken reaches
//! [`OUT_CAP`], the engine stops passing host bytes to the model and [`Engine::wants_input`]
//! turns false, so the transport stops reading the host (flow control by backpressure).
//! While no host listens (a pty nobody has open, no TCP client), what the hand sends is lost,
//! as on a serial line with nobody at the other end.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use gcl_model::params::NvMemory;
use gcl_model::{Device, DeviceConfig};

use super::misbehave::{LineTap, Shaped};
use super::trace::Direction;
use super::{EepromFile, Pace, SimError, SimOptions, TimeMode, Trace};
use gcl_host::link::{Link, SimLink, byte_time};

/// Output the host has not taken, beyond which the engine stops passing the host's bytes to
/// the model (one command's answer may go past it; nothing is ever dropped).
pub const OUT_CAP: usize = 64 * 1024;

/// Host bytes waiting for their wire time, beyond which the transport stops reading the host.
pub const IN_CAP: usize = 4096;

/// In fast time, a motion that has not finished after this much simulated time is left
/// running (a ^C still stops it).
const FAST_MOTION_LIMIT: Duration = Duration::from_secs(3600);

/// A simulated hand with its clock, line timing, EEPROM file and trace.
pub struct Engine {
    link: SimLink,
    time: TimeMode,
    pace: Pace,
    started: Instant,
    eeprom: Option<EepromFile>,
    eeprom_warned: bool,
    trace: Option<Trace>,
    /// Output not yet taken by the transport, with the byte time of each run of it.
    out: VecDeque<u8>,
    out_rates: VecDeque<(usize, Duration)>,
    /// When the output line is free to start the head byte of `out`.
    out_free_at: Instant,
    /// Host bytes not yet passed to the model.
    inq: VecDeque<u8>,
    /// When the head byte of `inq` has crossed the line.
    in_due: Instant,
    /// When the last byte passed to the model had crossed the line.
    in_last: Instant,
    listening: bool,
    /// What sees and shapes the traffic (`gcl fuzz host`, `gcl check-host`), if anything.
    tap: Option<Box<dyn LineTap>>,
    /// Output from this many bytes of `out` on is held back until then (a misbehaviour).
    hold: Option<(usize, Instant)>,
    /// Where each answer queued for a tapped line ends, counted from the start of `out`: the
    /// tap hears when the transport takes an answer's last byte ([`LineTap::delivered`]).
    answer_ends: VecDeque<usize>,
    /// What the model was powered up with (a restart powers it up again, EEPROM kept).
    config: DeviceConfig,
}

impl std::fmt::Debug for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Engine")
            .field("link", &self.link.describe())
            .field("time", &self.time)
            .field("pace", &self.pace)
            .field("queued_out", &self.out.len())
            .field("queued_in", &self.inq.len())
            .finish_non_exhaustive()
    }
}

impl Engine {
    /// Powers up the hand: loads the EEPROM file, opens the trace, and queues the power-up
    /// banner (which only a host already listening receives).
    pub fn new(opts: &SimOptions) -> Result<Engine, SimError> {
        let (eeprom, nv) = match &opts.eeprom {
            Some(p) => {
                let (f, nv) = EepromFile::open(p)?;
                (Some(f), nv)
            }
            None => (None, NvMemory::default()),
        };
        let header = format!(
            "profile {}, time {}, seed {}, pace {}, faults [{}]",
            opts.profile.id,
            opts.time.name(),
            opts.seed,
            opts.pace,
            opts.faults.iter().map(|f| f.name()).collect::<Vec<_>>().join(", ")
        );
        let trace = opts.trace.as_deref().map(|p| Trace::create(p, &header)).transpose()?;
        let config = DeviceConfig {
            seed: opts.seed,
            scenario: opts.scenario.clone(),
            nv,
            faults: opts.faults.clone(),
            ..Default::default()
        };
        let link = SimLink::new(opts.profile.clone(), config.clone());
        let now = Instant::now();
        let mut e = Engine {
            link,
            time: opts.time,
            pace: opts.pace,
            started: now,
            eeprom,
            eeprom_warned: false,
            trace,
            out: VecDeque::new(),
            out_rates: VecDeque::new(),
            out_free_at: now,
            inq: VecDeque::new(),
            in_due: now,
            in_last: now,
            listening: true,
            tap: None,
            hold: None,
            answer_ends: VecDeque::new(),
            config,
        };
        let mut banner = Vec::new();
        let _ = e.link.recv(&mut banner, Duration::ZERO);
        let bt = e.byte_time();
        e.emit(&banner, bt);
        Ok(e)
    }

    /// Installs a tap that sees the host's bytes and sees and shapes the hand's answers from
    /// now on (the power-up banner has been queued already).
    pub fn set_tap(&mut self, tap: Box<dyn LineTap>) {
        self.tap = Some(tap);
    }

    /// Whether a tap watches the line (what only it needs is then worth a transport's work).
    pub fn tapped(&self) -> bool {
        self.tap.is_some()
    }

    /// The model.
    pub fn device(&self) -> &Device {
        self.link.device()
    }

    /// The time mode.
    pub fn time_mode(&self) -> TimeMode {
        self.time
    }

    /// The rate the line runs at now (bit/s), or `None` when unpaced.
    pub fn line_baud(&self) -> Option<u32> {
        match self.pace {
            Pace::Unpaced => None,
            Pace::Fixed(b) => Some(b),
            Pace::Hand => Some(self.link.device().baud()),
        }
    }

    fn byte_time(&self) -> Duration {
        self.line_baud().map_or(Duration::ZERO, byte_time)
    }

    /// Whether the transport should read the host now: false while host bytes wait for their
    /// wire time beyond [`IN_CAP`], or output the host has not taken is at [`OUT_CAP`].
    pub fn wants_input(&self) -> bool {
        self.inq.len() < IN_CAP && self.out.len() < OUT_CAP
    }

    /// Before [`Engine::input`]: whether the host's side of the line still holds output the
    /// host has not read (a transport that can see it says so; the tap hears of it).
    pub fn host_unread(&mut self, unread: bool) {
        if let Some(tap) = &mut self.tap {
            tap.host_unread(unread);
        }
    }

    /// Bytes the host wrote, read from the transport now. They reach the model at their wire
    /// time (at once when unpaced), on the next [`Engine::wake`] that finds them due.
    pub fn input(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        if let Some(tap) = &mut self.tap {
            tap.host_bytes(self.link.device(), bytes);
        }
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.bytes(sim, Direction::In, bytes);
        }
        if self.inq.is_empty() {
            self.in_due = self.in_last.max(Instant::now()) + self.byte_time();
        }
        self.inq.extend(bytes);
        self.wake();
    }

    /// Lets time pass: passes the host bytes that are due to the model (while the output
    /// queue has room), and runs the model up to the wall clock in real time.
    pub fn wake(&mut self) {
        let now = Instant::now();
        while !self.inq.is_empty() && self.in_due <= now && self.out.len() < OUT_CAP {
            let bt = self.byte_time();
            let due = if bt.is_zero() {
                self.inq.len()
            } else {
                let n = (now - self.in_due).as_nanos() / bt.as_nanos() + 1;
                n.min(self.inq.len() as u128) as usize
            };
            // One line at a time, so that the output check above runs between lines.
            let (a, b) = self.inq.as_slices();
            let framing = &self.link.device().profile().framing;
            let (term, abort) = (framing.terminator, framing.abort);
            let end = a.iter().chain(b).take(due).position(|&c| c == term || c == abort).map_or(due, |i| i + 1);
            let chunk: Vec<u8> = self.inq.drain(..end).collect();
            let last_due = self.in_due + bt * (end as u32 - 1);
            self.in_last = last_due;
            self.in_due = last_due + bt;
            self.deliver(&chunk, bt, last_due);
        }
        if self.time == TimeMode::Real && self.link.device().poll_timeout().is_some() {
            let now = self.started.elapsed();
            let d = self.link.device_mut();
            d.handle_timeout(now);
            let out = d.take_output();
            let bt = self.byte_time();
            self.emit(&out, bt);
            self.trace_device_events();
            if !self.link.device().is_busy() {
                self.persist();
            }
        }
    }

    /// Passes host bytes to the model; the answer goes out at `bt`, the rate in force when
    /// they arrived (a BAUD change applies after its own answer).
    fn deliver(&mut self, bytes: &[u8], bt: Duration, arrived: Instant) {
        let mut out = Vec::new();
        match self.time {
            TimeMode::Fast => {
                // SimLink is the one implementation of simulated time: every byte takes its
                // wire time at the hand's BAUD, output too, and a motion runs to its end.
                let _ = self.link.send(bytes);
                let _ = self.link.recv(&mut out, Duration::ZERO);
                let start = self.link.elapsed();
                while self.link.device().is_busy() && self.link.elapsed().saturating_sub(start) < FAST_MOTION_LIMIT {
                    let _ = self.link.recv(&mut out, Duration::from_secs(60));
                }
            }
            TimeMode::Real => {
                let now = self.started.elapsed().max(self.link.device().now());
                let d = self.link.device_mut();
                d.handle_input(now, bytes);
                out = d.take_output();
            }
        }
        self.emit_at(&out, bt, arrived);
        self.trace_device_events();
        self.persist();
    }

    /// Writes what the hand reported since the last call into the trace.
    fn trace_device_events(&mut self) {
        let sim = self.link.elapsed();
        let Some(t) = &mut self.trace else { return };
        while let Some(e) = self.link.device_mut().poll_event() {
            t.device_event(sim, e);
        }
    }

    /// When [`Engine::wake`] or a paced write is next due, if ever. A paced byte that is due
    /// already is not a deadline: the transport waits for its descriptor to be writable.
    pub fn deadline(&self) -> Option<Instant> {
        let now = Instant::now();
        let model = match self.time {
            TimeMode::Real => self.link.device().poll_timeout().map(|t| self.started + t),
            TimeMode::Fast => None,
        };
        let input = (!self.inq.is_empty() && self.out.len() < OUT_CAP).then_some(self.in_due);
        let output = self.out_rates.front().map(|&(_, bt)| self.out_free_at + bt).filter(|t| *t > now);
        let held = self.hold.map(|(_, t)| t).filter(|t| *t > now);
        [model, input, output, held].into_iter().flatten().min()
    }

    /// Whether output is waiting to be written (now or later).
    pub fn has_output(&self) -> bool {
        !self.out.is_empty()
    }

    /// Whether host bytes are waiting for their wire time.
    pub fn has_input(&self) -> bool {
        !self.inq.is_empty()
    }

    /// The output that may be written now: every byte whose wire time has passed by `now`.
    pub fn ready_output(&mut self, now: Instant) -> &[u8] {
        let mut n = 0;
        let mut t = self.out_free_at;
        for &(count, bt) in &self.out_rates {
            if bt.is_zero() {
                n += count;
                continue;
            }
            if t + bt > now {
                break;
            }
            let k = ((now - t).as_nanos() / bt.as_nanos()).min(count as u128) as usize;
            n += k;
            t += bt * k as u32;
            if k < count {
                break;
            }
        }
        if let Some((k, until)) = self.hold {
            if now < until {
                n = n.min(k);
            } else {
                self.hold = None;
            }
        }
        let all = self.out.make_contiguous();
        &all[..n]
    }

    /// The first run of queued output sent at one rate: its length, and the rate (bit/s;
    /// `None` when unpaced). A transport that checks the host's speed writes one run at a time.
    pub fn head_run(&self) -> Option<(usize, Option<u32>)> {
        self.out_rates.front().map(|&(count, bt)| {
            let baud = (!bt.is_zero()).then(|| rate_of(bt));
            (count, baud)
        })
    }

    /// Records that the transport wrote `n` bytes of [`Engine::ready_output`].
    pub fn consumed(&mut self, n: usize) {
        let mut n = n.min(self.out.len());
        if let Some((k, _)) = &mut self.hold {
            *k = k.saturating_sub(n);
        }
        self.out.drain(..n);
        for end in self.answer_ends.iter_mut() {
            *end = end.saturating_sub(n);
        }
        while self.answer_ends.front() == Some(&0) {
            self.answer_ends.pop_front();
            if let Some(tap) = &mut self.tap {
                tap.delivered(self.link.device());
            }
        }
        while n > 0 {
            let Some((count, bt)) = self.out_rates.front_mut() else { break };
            let k = n.min(*count);
            self.out_free_at += *bt * k as u32;
            *count -= k;
            n -= k;
            if *count == 0 {
                self.out_rates.pop_front();
            }
        }
    }

    /// A host opened the port or connected: output is delivered again.
    pub fn client_connected(&mut self, who: &str) {
        self.listening = true;
        if let Some(tap) = &mut self.tap {
            tap.connection(self.link.device(), true);
        }
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.event(sim, &format!("host connected: {who}"));
        }
    }

    /// The host closed the port or went away: the output it has not taken is discarded, and
    /// output is lost until the next host, as on a serial line. The hand itself carries on as
    /// it was (mid-motion, mid-RealTime); bytes already on the wire still reach it.
    pub fn client_gone(&mut self, why: &str) {
        self.listening = false;
        let discarded = self.out.len();
        self.out.clear();
        self.out_rates.clear();
        self.hold = None;
        if !std::mem::take(&mut self.answer_ends).is_empty()
            && let Some(tap) = &mut self.tap
        {
            tap.discarded(self.link.device());
        }
        if let Some(tap) = &mut self.tap {
            tap.connection(self.link.device(), false);
        }
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.event(sim, &format!("host gone: {why}; {discarded} bytes not taken discarded"));
        }
        self.persist();
    }

    /// Whether a host is there to receive output.
    pub fn is_listening(&self) -> bool {
        self.listening
    }

    /// Logs an event in the trace.
    pub fn note(&mut self, what: &str) {
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.event(sim, what);
        }
    }

    /// Saves the EEPROM one last time.
    pub fn finish(&mut self) -> Result<(), SimError> {
        self.note("stopped");
        let nv = self.link.device().nv().clone();
        match &mut self.eeprom {
            Some(f) => f.flush(&nv),
            None => Ok(()),
        }
    }

    fn emit(&mut self, bytes: &[u8], bt: Duration) {
        self.emit_at(bytes, bt, Instant::now());
    }

    /// Queues output the hand started sending at `at` (for an answer, when the last byte of
    /// its command was on the hand's side of the line, however late the engine woke for it).
    fn emit_at(&mut self, bytes: &[u8], bt: Duration, at: Instant) {
        if bytes.is_empty() {
            return;
        }
        let shaped = match &mut self.tap {
            Some(tap) if self.listening => tap.hand_bytes(self.link.device(), bytes),
            _ => Shaped::plain(bytes),
        };
        if shaped.restart {
            // The tap sends the power-up output itself; the model starts afresh, EEPROM kept.
            let config = DeviceConfig { nv: self.link.device().nv().clone(), ..self.config.clone() };
            self.link = SimLink::new(self.link.device().profile().clone(), config);
            let _ = self.link.recv(&mut Vec::new(), Duration::ZERO);
        }
        let bytes = &shaped.bytes[..];
        if bytes.is_empty() {
            return;
        }
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.bytes(sim, Direction::Out, bytes);
        }
        if !self.listening {
            if let Some(t) = &mut self.trace {
                t.event(sim, &format!("no host: {} bytes lost on the line", bytes.len()));
            }
            return;
        }
        if self.out.is_empty() {
            self.out_free_at = self.out_free_at.max(at.min(Instant::now()));
        }
        if let Some((offset, d)) = shaped.hold
            && self.hold.is_none()
        {
            self.hold = Some((self.out.len() + offset, Instant::now() + d));
        }
        self.out.extend(bytes);
        if self.tap.is_some() {
            self.answer_ends.push_back(self.out.len());
        }
        match self.out_rates.back_mut() {
            Some((count, b)) if *b == bt => *count += bytes.len(),
            _ => self.out_rates.push_back((bytes.len(), bt)),
        }
    }

    fn persist(&mut self) {
        let Some(f) = &mut self.eeprom else { return };
        if let Err(e) = f.update(self.link.device().nv())
            && !self.eeprom_warned
        {
            // On stderr; a closed one must not take the hand down (`eprintln!` would panic).
            use std::io::Write as _;
            let _ = writeln!(std::io::stderr(), "gcl sim: warning: {e}");
            self.eeprom_warned = true;
        }
    }
}

/// The line rate (bit/s, ten bits a byte) of a byte time, as [`Engine::head_run`] reports it:
/// rounded, so not always the rate the byte time was made from (115200 comes back as 115201).
pub(crate) fn rate_of(bt: Duration) -> u32 {
    (10_000_000_000f64 / bt.as_nanos().max(1) as f64).round() as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use gcl_model::Profile;

    fn engine_for(profile: &str, time: TimeMode, pace: Pace) -> Engine {
        let mut o = SimOptions::new(Profile::builtin(profile).unwrap());
        o.time = time;
        o.pace = pace;
        Engine::new(&o).unwrap()
    }

    fn engine(time: TimeMode, pace: Pace) -> Engine {
        engine_for("seed", time, pace)
    }

    fn drain(e: &mut Engine) -> Vec<u8> {
        let v = e.ready_output(Instant::now()).to_vec();
        e.consumed(v.len());
        v
    }

    #[test]
    fn fast_time_runs_motion_to_the_end_at_once() {
        let mut e = engine(TimeMode::Fast, Pace::Unpaced);
        assert!(drain(&mut e).ends_with(b"=> "));
        e.input(b"HI\r");
        assert_eq!(drain(&mut e), b"HI\n\r=> ");
        assert!(e.device().now() > Duration::from_millis(100));
        assert_eq!(e.deadline(), None);
    }

    #[test]
    fn real_time_waits_for_the_clock() {
        let mut e = engine(TimeMode::Real, Pace::Unpaced);
        drain(&mut e);
        e.input(b"HI\r");
        assert_eq!(drain(&mut e), b"HI");
        assert!(e.device().is_busy());
        assert!(e.deadline().is_some());
        e.input(b"\x03");
        assert!(drain(&mut e).ends_with(b"=> "));
        assert!(!e.device().is_busy());
    }

    #[test]
    fn pacing_offers_a_byte_once_its_wire_time_has_passed() {
        // t0 before the engine starts its line clock: however long a loaded machine takes to
        // build the engine, the banner's bytes cannot be due before t0 + their wire time.
        let t0 = Instant::now();
        let mut e = engine(TimeMode::Fast, Pace::Fixed(9600));
        let bt = byte_time(9600);
        // Nothing before the first byte has crossed the line; then one byte per byte time.
        assert!(e.ready_output(t0 + bt * 3).len() <= 4);
        let due = e.deadline().unwrap();
        assert!(due >= t0 && due <= Instant::now() + bt);
        assert_eq!(e.ready_output(due + bt * 2 + bt / 2).len(), 3);
    }

    #[test]
    fn host_bytes_reach_the_model_at_their_wire_time() {
        let mut e = engine(TimeMode::Real, Pace::Fixed(1200));
        drain(&mut e);
        let t0 = Instant::now();
        e.input(b"FGET DP\r");
        // 8 bytes at 1200 baud: 66.7 ms before the CR is on the hand's side of the line.
        assert!(e.has_input() || t0.elapsed() >= byte_time(1200) * 8);
        let due = e.deadline().unwrap();
        assert!(due > t0);
        while e.has_input() {
            std::thread::sleep(Duration::from_millis(5));
            e.wake();
        }
        assert!(t0.elapsed() >= byte_time(1200) * 8);
    }

    #[test]
    fn the_hands_baud_sets_the_pace_after_the_answer_that_sets_it() {
        let mut e = engine_for("bh8-262", TimeMode::Fast, Pace::Hand);
        assert_eq!(e.line_baud(), Some(9600));
        while e.has_output() {
            drain(&mut e);
        }
        e.out_free_at = Instant::now();
        e.in_last = Instant::now();
        e.input(b"PSET BAUD 384\r");
        std::thread::sleep(byte_time(9600) * 15);
        e.wake();
        assert_eq!(e.line_baud(), Some(38400));
        // The answer (echo, prompt) still goes at 9600.
        assert_eq!(e.out_rates.front().map(|r| r.1), Some(byte_time(9600)));
    }

    #[test]
    fn a_host_that_does_not_read_is_not_read_and_loses_nothing() {
        let mut e = engine(TimeMode::Fast, Pace::Unpaced);
        drain(&mut e);
        let cmd = b"FGET DP\r";
        let answer_len = b"FGET DP\n\r1000 1000 1000 150\n\r=> ".len();
        let mut sent = 0;
        while e.wants_input() {
            e.input(cmd);
            sent += 1;
        }
        assert!(e.out.len() >= OUT_CAP && e.out.len() < OUT_CAP + 2 * answer_len, "{}", e.out.len());
        // Nothing dropped: every command sent is answered once the host reads.
        let mut got = Vec::new();
        while e.has_output() || e.has_input() {
            got.extend(drain(&mut e));
            e.wake();
        }
        assert_eq!(got.len(), sent * answer_len);
    }

    #[test]
    fn garbage_never_takes_the_hand_down() {
        for time in [TimeMode::Fast, TimeMode::Real] {
            let mut e = engine(time, Pace::Unpaced);
            let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
            for _ in 0..200 {
                let chunk: Vec<u8> = (0..500)
                    .map(|_| {
                        x ^= x << 13;
                        x ^= x >> 7;
                        x ^= x << 17;
                        (x >> 32) as u8
                    })
                    .collect();
                e.input(&chunk);
                e.wake();
                drain(&mut e);
            }
            e.input(&[3; 20]);
            e.input(b"\r");
            assert!(!drain(&mut e).is_empty(), "{time:?}");
        }
    }

    #[test]
    fn output_without_a_listener_is_lost_and_unread_output_is_discarded() {
        let mut e = engine(TimeMode::Fast, Pace::Unpaced);
        assert!(e.has_output());
        e.client_gone("test");
        assert!(!e.has_output(), "the banner nobody read is discarded");
        e.input(b"FGET DP\r");
        assert!(!e.has_output());
        e.client_connected("again");
        e.input(b"FGET DP\r");
        assert_eq!(drain(&mut e), b"FGET DP\n\r1000 1000 1000 150\n\r=> ");
    }
}
