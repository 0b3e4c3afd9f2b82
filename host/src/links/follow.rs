//! A serial link that follows the hand's line rate: when a line the host sends moves the hand to
//! another rate (a set of the profile's line-rate parameter, a RESET that loads a saved rate),
//! the port moves with it, and the hand is set back to the port's first rate before the link
//! closes (`gcl fuzz device --allow rate-change`, issue 37).
//!
//! What the hand does with each line is known from a shadow: the reference model, fed every
//! byte the host sends, on the wall clock. The moment of the switch is the one the profile's
//! decision `bh8-baud-timing` states, and `gcl sim --pty` keeps: the answer to the line that
//! changes the rate (its echo, its errors, its prompt) goes out at the old rate, and the new
//! rate applies from then on. So the link counts the bytes the shadow answered up to that
//! line, reads at most that many more at the old rate, then sets the port's speed. Bytes the
//! host sends after such a line in the same write wait for that switch first. A hand that
//! answers the line with fewer bytes than the model is switched for at its next line all the
//! same (its case has failed by then; the rate it is at is the model's best guess).
//!
//! The shadow starts as a hand at the port's rate that has that rate saved: the rate a RESET
//! loads is taken to be the rate the hand was met at. A hand whose saved rate differs is a
//! hand the campaign would lose at its first RESET whatever it followed; the check after the
//! campaign (the port reopened at the first rate and the hand probed) says so.

use std::sync::Arc;
use std::time::Duration;

use gcl_model::spec::{CommandKind, ValueSource};
use gcl_model::{Device, DeviceConfig, Profile};

use super::SerialLink;
use crate::link::{Link, LinkError};

/// A [`SerialLink`] whose port follows the hand's line rate (see the module's text).
pub struct RateFollowingLink {
    port: SerialLink,
    profile: Arc<Profile>,
    shadow: Device,
    /// The rate the port was opened at, and the hand is set back to before the link closes.
    first: u32,
    /// The rate the port is at now.
    rate: u32,
    /// Bytes the shadow has answered so far, and bytes received from the hand so far.
    said: u64,
    heard: u64,
    /// A switch owed: the rate, once `heard` reaches the count (the answer at the old rate).
    owed: Option<(u32, u64)>,
    /// How many times the port changed its rate.
    switches: u32,
    /// Bytes read while a write waited for a switch, not yet given to the host.
    kept: Vec<u8>,
}

impl std::fmt::Debug for RateFollowingLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RateFollowingLink").field("port", &self.port).field("rate", &self.rate).finish_non_exhaustive()
    }
}

/// How long the link waits for the answer it is owed before a switch, at most, beyond the
/// answer's own wire time at the old rate. The wait ends when the answer is in, so it costs
/// nothing on a hand that answers; it is long because a hand built for a host (or simulated)
/// on a busy machine can answer late, and a switch before its answer ends garbles the rest.
const ANSWER_WAIT: Duration = Duration::from_secs(2);

impl RateFollowingLink {
    /// Opens `path` at `baud` for a hand `profile` describes.
    pub fn open(path: &str, baud: u32, profile: Arc<Profile>) -> Result<RateFollowingLink, LinkError> {
        let port = SerialLink::open(path, baud)?;
        let mut shadow = Device::new(profile.clone(), DeviceConfig::default());
        // (a hand met at another rate than the model's default: that rate set and saved)
        if shadow.baud() != baud {
            let mut lines = Vec::new();
            if let Some(set) = rate_line(&profile, baud) {
                lines.push(set);
            }
            if let Some(save) = profile.command_of_kind(CommandKind::GlobalSave) {
                lines.push(profile.command(save).name.clone().into_bytes());
            }
            for mut l in lines {
                l.push(profile.framing.terminator);
                shadow.handle_input(Duration::ZERO, &l);
            }
        }
        shadow.clear_output();
        Ok(RateFollowingLink {
            port,
            profile,
            shadow,
            first: baud,
            rate: baud,
            said: 0,
            heard: 0,
            owed: None,
            switches: 0,
            kept: Vec::new(),
        })
    }

    /// The rate the port is at now.
    pub fn rate(&self) -> u32 {
        self.rate
    }

    /// How many times the port changed its rate so far.
    pub fn switches(&self) -> u32 {
        self.switches
    }

    /// Lets the shadow's clock reach the link's and counts what it said meanwhile (the end of
    /// a motion, a RealTime answer).
    fn catch_up(&mut self) {
        let now = self.port.elapsed();
        if self.shadow.poll_timeout().is_some_and(|t| t <= now) {
            self.shadow.handle_timeout(now);
        }
        self.said += self.shadow.take_output().len() as u64;
    }

    /// Sets the port to `rate` (a no-op at the rate it is at).
    fn switch_to(&mut self, rate: u32) -> Result<(), LinkError> {
        self.owed = None;
        if rate != self.rate {
            self.port.set_rate(rate)?;
            self.rate = rate;
            self.switches += 1;
        }
        Ok(())
    }

    /// Before more host bytes: the switch owed is made, once the answer it waits for came (at
    /// most its wire time and [`ANSWER_WAIT`]); what came meanwhile is kept for the next read.
    fn settle_owed(&mut self, keep: &mut Vec<u8>) -> Result<(), LinkError> {
        let Some((rate, at)) = self.owed else { return Ok(()) };
        let wire = crate::link::byte_time(self.rate) * (at.saturating_sub(self.heard)).min(4096) as u32;
        let until = self.port.elapsed() + wire + ANSWER_WAIT;
        while self.heard < at {
            let left = until.saturating_sub(self.port.elapsed());
            if left.is_zero() {
                break;
            }
            let n = self.port.recv_at_most(keep, left, (at - self.heard) as usize)?;
            self.heard += n as u64;
        }
        self.switch_to(rate)
    }

    /// Sets the hand back to the port's first rate, if the model says it is elsewhere: ^C, the
    /// set at the rate the hand is at, its answer read, the port switched. Says whether the hand
    /// is (by the model) at the first rate now.
    pub fn restore(&mut self) -> bool {
        self.catch_up();
        if self.shadow.baud() == self.first && self.owed.is_none() {
            return true;
        }
        let _ = self.settle_owed(&mut Vec::new());
        let Some(mut line) = rate_line(&self.profile, self.first) else { return false };
        line.push(self.profile.framing.terminator);
        let prompt = self.profile.framing.prompt.trim_end().as_bytes().to_vec();
        let mut got = Vec::new();
        let wait = crate::link::byte_time(self.rate) * 64 + ANSWER_WAIT;
        let abort = [self.profile.framing.abort];
        for bytes in [&abort[..], &line[..]] {
            if self.send(bytes).is_err() {
                return false;
            }
            got.clear();
            let done = |b: &[u8]| !prompt.is_empty() && b.windows(prompt.len()).any(|w| w == prompt.as_slice());
            if self.recv_until(&mut got, wait, &done).is_err() {
                return false;
            }
        }
        let _ = self.settle_owed(&mut Vec::new());
        self.shadow.baud() == self.first && self.rate == self.first
    }
}

/// The line that sets the hand's line rate to `baud` (`PSET BAUD 96`), without its terminator;
/// `None` for a profile whose rate is fixed, or a rate that is not a whole number of its units.
pub fn rate_line(p: &Profile, baud: u32) -> Option<Vec<u8>> {
    let ValueSource::Param(id) = p.hand_sources().baud else { return None };
    baud.is_multiple_of(100).then(|| format!("{} {} {}", p.setter(id), p.param(id).name, baud / 100).into_bytes())
}

impl Link for RateFollowingLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let f = &self.profile.framing;
        let (term, abort) = (f.terminator, f.abort);
        let mut rest = bytes;
        while !rest.is_empty() {
            let end = rest.iter().position(|&b| b == term || b == abort).map_or(rest.len(), |i| i + 1);
            let (chunk, after) = rest.split_at(end);
            rest = after;
            if self.owed.is_some() {
                // (bytes read while waiting for the switch: the answer, kept for the host)
                let mut early = std::mem::take(&mut self.kept);
                let r = self.settle_owed(&mut early);
                self.kept = early;
                r?;
            }
            self.port.send(chunk)?;
            self.catch_up();
            self.shadow.handle_input(self.port.elapsed().max(self.shadow.now()), chunk);
            self.said += self.shadow.take_output().len() as u64;
            let now = self.shadow.baud();
            if now != self.rate {
                self.owed = Some((now, self.said));
            } else {
                self.owed = None;
            }
        }
        Ok(())
    }

    fn recv(&mut self, buf: &mut Vec<u8>, timeout: Duration) -> Result<usize, LinkError> {
        if !self.kept.is_empty() {
            let n = self.kept.len();
            buf.append(&mut self.kept);
            return Ok(n);
        }
        self.catch_up();
        let n = match self.owed {
            Some((rate, at)) if self.heard >= at => {
                self.switch_to(rate)?;
                self.port.recv(buf, timeout)?
            }
            Some((_, at)) => self.port.recv_at_most(buf, timeout, (at - self.heard) as usize)?,
            None => self.port.recv(buf, timeout)?,
        };
        self.heard += n as u64;
        if let Some((rate, at)) = self.owed
            && self.heard >= at
        {
            self.switch_to(rate)?;
        }
        Ok(n)
    }

    fn pause(&mut self, d: Duration) {
        self.port.pause(d);
    }

    fn elapsed(&self) -> Duration {
        self.port.elapsed()
    }

    fn describe(&self) -> String {
        self.port.describe()
    }
}

impl Drop for RateFollowingLink {
    fn drop(&mut self) {
        let _ = self.restore();
    }
}
