//! The engine: the model, its clock, output pacing, EEPROM persistence and the trace, with no
//! transport. A transport feeds it input, wakes it at [`Engine::deadline`], and writes what
//! [`Engine::ready_output`] offers.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use gcl_model::params::NvMemory;
use gcl_model::{Device, DeviceConfig};

use super::trace::Direction;
use super::{EepromFile, SimError, SimOptions, TimeMode, Trace};
use crate::link::{Link, SimLink, byte_time};

/// Output nobody reads (a pty with no client, a stalled socket) is kept up to this size; the
/// oldest bytes are dropped beyond it, as on a serial line with no listener.
const OUT_CAP: usize = 64 * 1024;

/// In fast time, a motion that has not finished after this much simulated time is left
/// running (a ^C still stops it).
const FAST_MOTION_LIMIT: Duration = Duration::from_secs(3600);

/// A simulated hand with its clock, pacing, EEPROM file and trace.
pub struct Engine {
    link: SimLink,
    time: TimeMode,
    started: Instant,
    eeprom: Option<EepromFile>,
    eeprom_warned: bool,
    trace: Option<Trace>,
    out: VecDeque<u8>,
    byte_time: Option<Duration>,
    wire_free_at: Instant,
    listening: bool,
    dropped: usize,
}

impl std::fmt::Debug for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Engine")
            .field("link", &self.link.describe())
            .field("time", &self.time)
            .field("queued", &self.out.len())
            .finish_non_exhaustive()
    }
}

impl Engine {
    /// Powers up the hand: loads the EEPROM file, opens the trace, and queues the power-up
    /// banner.
    pub fn new(opts: &SimOptions) -> Result<Engine, SimError> {
        let (eeprom, nv) = match &opts.eeprom {
            Some(p) => {
                let (f, nv) = EepromFile::open(p)?;
                (Some(f), nv)
            }
            None => (None, NvMemory::default()),
        };
        let header = format!(
            "profile {}, time {}, seed {}, baud {}, faults [{}]",
            opts.profile.id,
            opts.time.name(),
            opts.seed,
            opts.baud.map_or("unpaced".to_string(), |b| b.to_string()),
            opts.faults.iter().map(|f| f.name()).collect::<Vec<_>>().join(", ")
        );
        let trace = opts.trace.as_deref().map(|p| Trace::create(p, &header)).transpose()?;
        let config = DeviceConfig { seed: opts.seed, scenario: opts.scenario.clone(), nv, faults: opts.faults.clone() };
        let link = SimLink::new(opts.profile.clone(), config);
        let now = Instant::now();
        let mut e = Engine {
            link,
            time: opts.time,
            started: now,
            eeprom,
            eeprom_warned: false,
            trace,
            out: VecDeque::new(),
            byte_time: opts.baud.map(byte_time),
            wire_free_at: now,
            listening: true,
            dropped: 0,
        };
        let mut banner = Vec::new();
        let _ = e.link.recv(&mut banner, Duration::ZERO);
        e.emit(&banner);
        Ok(e)
    }

    /// The model.
    pub fn device(&self) -> &Device {
        self.link.device()
    }

    /// The time mode.
    pub fn time_mode(&self) -> TimeMode {
        self.time
    }

    /// Bytes from the host.
    pub fn input(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.bytes(sim, Direction::In, bytes);
        }
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
                let now = self.started.elapsed();
                let d = self.link.device_mut();
                d.handle_input(now, bytes);
                out = d.take_output();
            }
        }
        self.emit(&out);
        self.persist();
    }

    /// Lets time pass (real time: runs the model up to the wall clock).
    pub fn wake(&mut self) {
        if self.time == TimeMode::Real && self.link.device().poll_timeout().is_some() {
            let now = self.started.elapsed();
            let d = self.link.device_mut();
            d.handle_timeout(now);
            let out = d.take_output();
            self.emit(&out);
            if !self.link.device().is_busy() {
                self.persist();
            }
        }
    }

    /// When [`Engine::wake`] or a paced write is next due, if ever.
    pub fn deadline(&self) -> Option<Instant> {
        let model = match self.time {
            TimeMode::Real => self.link.device().poll_timeout().map(|t| self.started + t),
            TimeMode::Fast => None,
        };
        let pacing = (self.byte_time.is_some() && !self.out.is_empty()).then_some(self.wire_free_at);
        match (model, pacing) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Whether output is waiting to be written (now or later).
    pub fn has_output(&self) -> bool {
        !self.out.is_empty()
    }

    /// The output that may be written now: everything when unpaced, else as many bytes as
    /// the line would have carried by `now`.
    pub fn ready_output(&mut self, now: Instant) -> &[u8] {
        let n = match self.byte_time {
            None => self.out.len(),
            Some(_) if now < self.wire_free_at => 0,
            Some(bt) => {
                let slots = (now - self.wire_free_at).as_nanos() / bt.as_nanos().max(1) + 1;
                (slots.min(self.out.len() as u128)) as usize
            }
        };
        let all = self.out.make_contiguous();
        &all[..n]
    }

    /// Records that the transport wrote `n` bytes of [`Engine::ready_output`].
    pub fn consumed(&mut self, n: usize) {
        let n = n.min(self.out.len());
        self.out.drain(..n);
        if let Some(bt) = self.byte_time {
            self.wire_free_at += bt * n as u32;
        }
    }

    /// A client connected (TCP): output is wanted again.
    pub fn client_connected(&mut self, who: &str) {
        self.listening = true;
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.event(sim, &format!("client connected: {who}"));
        }
    }

    /// The client went away: undelivered output is lost, and output is dropped until the
    /// next client. The hand itself carries on as it was (mid-motion, mid-RealTime).
    pub fn client_gone(&mut self, why: &str) {
        self.listening = false;
        self.out.clear();
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.event(sim, &format!("client gone: {why}"));
        }
        self.persist();
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

    fn emit(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let sim = self.link.elapsed();
        if let Some(t) = &mut self.trace {
            t.bytes(sim, Direction::Out, bytes);
        }
        if !self.listening {
            if let Some(t) = &mut self.trace {
                t.event(sim, &format!("no client: {} bytes dropped", bytes.len()));
            }
            return;
        }
        if self.out.is_empty() {
            self.wire_free_at = self.wire_free_at.max(Instant::now());
        }
        self.out.extend(bytes);
        if self.out.len() > OUT_CAP {
            let excess = self.out.len() - OUT_CAP;
            self.out.drain(..excess);
            self.dropped += excess;
        }
    }

    fn persist(&mut self) {
        let Some(f) = &mut self.eeprom else { return };
        if let Err(e) = f.update(self.link.device().nv())
            && !self.eeprom_warned
        {
            eprintln!("gcl sim: warning: {e}");
            self.eeprom_warned = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gcl_model::Profile;

    fn engine(time: TimeMode, baud: Option<u32>) -> Engine {
        let mut o = SimOptions::new(Profile::builtin("seed").unwrap());
        o.time = time;
        o.baud = baud;
        Engine::new(&o).unwrap()
    }

    fn drain(e: &mut Engine) -> Vec<u8> {
        let v = e.ready_output(Instant::now()).to_vec();
        e.consumed(v.len());
        v
    }

    #[test]
    fn fast_time_runs_motion_to_the_end_at_once() {
        let mut e = engine(TimeMode::Fast, None);
        assert!(drain(&mut e).ends_with(b"=> "));
        e.input(b"HI\r");
        assert_eq!(drain(&mut e), b"HI\n\r=> ");
        assert!(e.device().now() > Duration::from_millis(100));
        assert_eq!(e.deadline(), None);
    }

    #[test]
    fn real_time_waits_for_the_clock() {
        let mut e = engine(TimeMode::Real, None);
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
    fn pacing_offers_bytes_a_slot_at_a_time() {
        let mut e = engine(TimeMode::Fast, Some(9600));
        let t0 = Instant::now();
        let first = e.ready_output(t0).len();
        assert!(first >= 1);
        e.consumed(first);
        // The next byte is due one byte time after the first.
        let due = e.deadline().unwrap();
        assert!(e.ready_output(due - Duration::from_micros(1)).len() <= 1);
        assert!(!e.ready_output(due + Duration::from_millis(5)).is_empty());
    }

    #[test]
    fn garbage_never_takes_the_hand_down() {
        for time in [TimeMode::Fast, TimeMode::Real] {
            let mut e = engine(time, None);
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
    fn output_without_a_listener_is_dropped() {
        let mut e = engine(TimeMode::Fast, None);
        e.client_gone("test");
        assert!(!e.has_output());
        e.input(b"FGET DP\r");
        assert!(!e.has_output());
        e.client_connected("again");
        e.input(b"FGET DP\r");
        assert_eq!(drain(&mut e), b"FGET DP\n\r1000 1000 1000 150\n\r=> ");
    }
}
