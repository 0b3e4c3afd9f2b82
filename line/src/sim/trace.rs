//! The trace: one line per chunk of bytes in either direction, timestamped and escaped with
//! `gcl_model::escape::escape`, flushed at once so that a killed simulator loses nothing.
//!
//! ```text
//! # gcl sim trace; columns: wall-seconds sim-seconds direction bytes
//! #   '>' host to hand, '<' hand to host, '#' an event (the link's, or the hand's own:
//! #   power-up, a line done with its status, the RealTime loop entered or left)
//!     0.000000     0.000000 < \n\rBarrettHand Firmware ...\n\r=>
//!     1.204113     0.003125 > FGET P\r
//!     1.204131     0.003125 < FGET P\n\r0 0 0 0\n\r=>
//! ```

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::{Duration, Instant};

use gcl_model::Event;
use gcl_model::escape::escape;

use super::SimError;

/// Which way bytes went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Host to hand.
    In,
    /// Hand to host.
    Out,
}

/// An open trace file.
#[derive(Debug)]
pub struct Trace {
    out: BufWriter<File>,
    started: Instant,
    path: std::path::PathBuf,
    failed: bool,
}

impl Trace {
    /// Creates (truncates) the trace file and writes its header.
    pub fn create(path: &Path, header: &str) -> Result<Trace, SimError> {
        let file = File::create(path)
            .map_err(|e| SimError::Trace { path: path.to_path_buf(), reason: format!("cannot create: {e}") })?;
        let mut t =
            Trace { out: BufWriter::new(file), started: Instant::now(), path: path.to_path_buf(), failed: false };
        t.line(&format!("# gcl sim trace: {header}"));
        t.line("# columns: wall-seconds sim-seconds direction bytes ('>' host to hand, '<' hand to host, '#' event)");
        Ok(t)
    }

    /// Logs bytes.
    pub fn bytes(&mut self, sim: Duration, dir: Direction, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let d = if dir == Direction::In { '>' } else { '<' };
        let wall = self.started.elapsed();
        self.line(&format!("{:12.6} {:12.6} {d} {}", wall.as_secs_f64(), sim.as_secs_f64(), escape(bytes)));
    }

    /// Logs an event (a client connecting, output dropped...).
    pub fn event(&mut self, sim: Duration, what: &str) {
        let wall = self.started.elapsed();
        self.line(&format!("{:12.6} {:12.6} # {what}", wall.as_secs_f64(), sim.as_secs_f64()));
    }

    /// Logs what the hand reported ([`gcl_model::Device::poll_event`]), as `# hand: ...`.
    pub fn device_event(&mut self, sim: Duration, e: Event) {
        let what = match e {
            Event::PoweredUp => "powered up".to_string(),
            Event::LineDone(s) if s.is_empty() => "line done".to_string(),
            Event::LineDone(s) => format!("line done, ERR {}", s.code()),
            Event::LoopEntered => "RealTime loop entered".to_string(),
            Event::LoopLeft => "RealTime loop left".to_string(),
        };
        self.event(sim, &format!("hand: {what}"));
    }

    fn line(&mut self, text: &str) {
        if self.failed {
            return;
        }
        if writeln!(self.out, "{text}").and_then(|_| self.out.flush()).is_err() {
            // A full disk must not take the hand down: warn once and stop tracing.
            self.failed = true;
            // On stderr; a closed one must not take the hand down either.
            let _ = writeln!(
                std::io::stderr(),
                "gcl sim: warning: cannot write trace file {}; tracing stopped",
                self.path.display()
            );
        }
    }
}
