//! Links: a byte pipe to a hand with deadlines, whatever is behind it.
//!
//! Every tool that talks to a hand (the host library, `record`, `replay`, `conform`,
//! `certify`) does so through [`Link`]. The in-process [`SimLink`] runs the reference model
//! with simulated time: waiting on it advances the model's clock instead of the wall clock,
//! so a script behaves the same against the simulator and against a real hand, only faster.
//!
//! `drain` discards until quiet and keeps nothing (it returns a count). On a `SimLink` every byte
//! costs its wire time at the hand's BAUD.

use std::sync::Arc;
use std::time::{Duration, Instant};

use gcl_model::{Device, DeviceConfig, Profile};

/// Why a link failed. A timeout is not an error: [`Link::recv`] returns 0 bytes.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The hand went away: EOF, a closed socket, an exited process.
    #[error("the hand disconnected")]
    Disconnected,
    /// An I/O error from the operating system.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    /// The target could not be opened.
    #[error("cannot open {target}: {reason}")]
    Open {
        /// The target text.
        target: String,
        /// Why.
        reason: String,
    },
}

/// A connection to a hand.
pub trait Link: Send {
    /// Writes bytes to the hand.
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError>;

    /// Waits at most `timeout` for bytes from the hand and appends what arrived to `buf`.
    /// Returns the number of bytes appended; 0 means the timeout passed with nothing.
    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError>;

    /// Lets `d` pass with no traffic (a real sleep, or simulated time).
    fn pause(&mut self, d: Duration) {
        std::thread::sleep(d);
    }

    /// Time since the link opened, as the hand experiences it: simulated time for the
    /// in-process simulator, wall time for everything else.
    fn elapsed(&self) -> Duration;

    /// What is on the other end, for reports.
    fn describe(&self) -> String;

    /// Reads until `done(buf)` holds or `timeout` passes in total. Returns whether `done` held.
    fn recv_until(
        &mut self,
        buf: &mut Vec<u8>,
        timeout: Duration,
        done: &dyn Fn(&[u8]) -> bool,
    ) -> Result<bool, LinkError> {
        let start = self.elapsed();
        loop {
            if done(buf) {
                return Ok(true);
            }
            let spent = self.elapsed().saturating_sub(start);
            if spent >= timeout {
                return Ok(false);
            }
            self.recv(buf, timeout - spent)?;
        }
    }
}

/// Reads and discards whatever the hand sends until it has been quiet for `quiet` (a power-up
/// banner, the tail of an earlier conversation), for at most `limit`. Returns how many bytes
/// it threw away; it keeps none, so a flooding hand costs time, never memory.
pub fn drain(link: &mut dyn Link, quiet: Duration, limit: Duration) -> Result<u64, LinkError> {
    let start = link.elapsed();
    let mut scratch = Vec::with_capacity(8192);
    let mut thrown = 0u64;
    loop {
        scratch.clear();
        let n = link.recv(&mut scratch, quiet)?;
        thrown += n as u64;
        if n == 0 || link.elapsed().saturating_sub(start) >= limit {
            return Ok(thrown);
        }
    }
}

/// Time one byte takes on an 8N1 line at `baud` (10 bits).
pub fn byte_time(baud: u32) -> Duration {
    Duration::from_nanos(10_000_000_000 / u64::from(baud.max(1)))
}

/// The reference model in-process, with simulated time.
///
/// Sent bytes reach the hand after their wire time at the hand's present BAUD; output takes
/// its wire time too. Waiting in [`Link::recv`] or [`Link::pause`] advances simulated time only,
/// so motion completes as fast as the CPU allows while every clock the host can see agrees
/// with a real wire. A clone is the same hand at the same simulated moment (its wall clock
/// included), going on independently.
#[derive(Clone)]
pub struct SimLink {
    device: Device,
    pending: Vec<u8>,
    started: Instant,
    label: String,
}

impl SimLink {
    /// A freshly powered-up hand. Its banner is waiting to be read.
    pub fn new(profile: Arc<Profile>, config: DeviceConfig) -> SimLink {
        let label = format!("sim:{}", profile.id);
        let mut device = Device::new(profile, config);
        let pending = device.take_output();
        SimLink { device, pending, started: Instant::now(), label }
    }

    /// The model behind the link.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The model behind the link, mutably (tests change the scenario mid-run).
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// Wall time since the link opened (to compare with simulated time).
    pub fn wall_elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    fn collect(&mut self) {
        let before = self.pending.len();
        self.device.drain_output(&mut self.pending);
        let n = self.pending.len() - before;
        if n > 0 {
            let t = self.device.now() + byte_time(self.device.baud()) * n as u32;
            self.device.handle_timeout(t);
            // Output produced while the wire was busy (nothing in practice) joins it.
            self.device.drain_output(&mut self.pending);
        }
    }
}

impl Link for SimLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let bt = byte_time(self.device.baud());
        for &b in bytes {
            let t = self.device.now() + bt;
            self.device.handle_input(t, &[b]);
        }
        self.collect();
        Ok(())
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        let deadline = self.device.now() + timeout;
        if self.pending.is_empty() {
            // (the model runs to the deadline or to the first output, in one call)
            self.device.handle_timeout_until_output(deadline);
            self.collect();
        }
        let n = self.pending.len();
        buf.append(&mut self.pending);
        Ok(n)
    }

    fn pause(&mut self, d: Duration) {
        let t = self.device.now() + d;
        self.device.handle_timeout(t);
        self.collect();
    }

    fn elapsed(&self) -> Duration {
        self.device.now()
    }

    fn describe(&self) -> String {
        self.label.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motion_takes_simulated_time_not_wall_time() {
        let mut l = SimLink::new(Profile::builtin("seed").unwrap(), DeviceConfig::default());
        let mut buf = Vec::new();
        assert!(l.recv_until(&mut buf, Duration::from_secs(1), &|b| b.ends_with(b"=> ")).unwrap());
        buf.clear();
        l.send(b"HI\r").unwrap();
        l.send(b"C\r").unwrap();
        assert!(l.recv_until(&mut buf, Duration::from_secs(20), &|b| b.ends_with(b"C\n\r=> ")).unwrap());
        assert!(l.elapsed() > Duration::from_secs(2));
        assert!(l.wall_elapsed() < Duration::from_secs(2));
    }

    #[test]
    fn recv_times_out_with_nothing() {
        let mut l = SimLink::new(Profile::builtin("seed").unwrap(), DeviceConfig::default());
        let mut buf = Vec::new();
        l.recv(&mut buf, Duration::from_millis(10)).unwrap();
        buf.clear();
        assert_eq!(l.recv(&mut buf, Duration::from_millis(50)).unwrap(), 0);
    }
}
