//! Waiting on file descriptors with a deadline, and the stop switch that ends a transport
//! loop from another thread (or, in `gcl sim`, from a signal).
//!
//! Waits stop on signals. The serving thread runs without timer slack and wakes ahead of each
//! deadline by how late its wakes have been running (at most 50 µs), waiting out the rest on the
//! clock, so a paced byte leaves at its wire time, not 20–50 µs later.

use std::cell::Cell;
use std::os::fd::{AsFd, BorrowedFd, OwnedFd};
use std::time::{Duration, Instant};

use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags};
use nix::sys::time::TimeSpec;

/// The sending side of a stop switch: [`StopHandle::stop`], or dropping it, stops the loop
/// that holds the matching [`StopSignal`].
#[derive(Debug)]
pub struct StopHandle {
    tx: Option<OwnedFd>,
}

impl StopHandle {
    /// Asks the loop to stop (closes the pipe; the loop sees end of file).
    pub fn stop(&mut self) {
        self.tx = None;
    }
}

/// The receiving side of a stop switch: readable once the loop should stop.
#[derive(Debug)]
pub struct StopSignal {
    rx: OwnedFd,
}

impl AsFd for StopSignal {
    fn as_fd(&self) -> BorrowedFd<'_> {
        self.rx.as_fd()
    }
}

/// A new stop switch (a pipe).
pub fn stop_pair() -> std::io::Result<(StopHandle, StopSignal)> {
    // Close-on-exec from the start: a child started meanwhile (a host) that kept the write
    // end would keep the stop from ever being seen.
    let (rx, tx) = nix::unistd::pipe2(nix::fcntl::OFlag::O_CLOEXEC)?;
    Ok((StopHandle { tx: Some(tx) }, StopSignal { rx }))
}

/// Waits until one of `fds` is ready or `deadline` passes (`None`: no deadline). Returns
/// normally on a timeout; the caller reads `revents`. An interrupted wait counts as a timeout.
///
/// On a thread that asked for [`precise_timers`], a deadline is met on time: the kernel is
/// asked to wake the thread ahead of it by how late its timed wakes have been running (an
/// average, learned here, at most [`MAX_EARLY`]), and the rest is waited out on the clock.
/// A timer wakes a thread some 20–35 µs late on a virtual machine even without timer slack:
/// at 38400 baud that is a tenth of a byte on every paced byte, and on a RealTime cycle's last
/// byte it is time the host waits. Never returns before `deadline` unless a descriptor is
/// ready or a signal came.
pub(crate) fn wait(fds: &mut [PollFd<'_>], deadline: Option<Instant>) -> std::io::Result<()> {
    let early = LATENESS.get();
    let target = deadline.map(|d| d.checked_sub(early.unwrap_or_default()).unwrap_or(d));
    let timeout = target.map(|t| TimeSpec::from_duration(t.saturating_duration_since(Instant::now())));
    match nix::poll::ppoll(fds, timeout, None) {
        Ok(0) => {
            if let (Some(late), Some(target), Some(deadline)) = (early, target, deadline) {
                let woke = Instant::now();
                let over = woke.saturating_duration_since(target).min(MAX_EARLY);
                LATENESS.set(Some(late * 7 / 8 + over / 8));
                while Instant::now() < deadline {
                    std::hint::spin_loop();
                }
            }
            Ok(())
        }
        Ok(_) | Err(Errno::EINTR) => Ok(()),
        Err(e) => Err(e.into()),
    }
}

/// The most a precise thread wakes ahead of a deadline (and so the most it waits on the clock).
const MAX_EARLY: Duration = Duration::from_micros(50);

thread_local! {
    /// How late this thread's timed waits have been waking (an average), once it asked for
    /// [`precise_timers`]; `None` before.
    static LATENESS: Cell<Option<Duration>> = const { Cell::new(None) };
}

/// Asks the kernel to wake the calling thread at its deadlines without the default timer
/// slack (50 µs for an ordinary thread), and [`wait`] to meet them on time, so that a paced
/// byte goes out at its wire time and not up to 50 µs after it: at 38400 baud that is a fifth
/// of a byte per exchange. Best effort: where the slack cannot be set, deadlines are only a
/// little late.
pub(crate) fn precise_timers() {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_timerslack(1);
    if LATENESS.get().is_none() {
        LATENESS.set(Some(Duration::ZERO));
    }
}

/// Whether a polled descriptor reported any of `flags`.
pub(crate) fn ready(fd: &PollFd<'_>, flags: PollFlags) -> bool {
    fd.revents().is_some_and(|r| r.intersects(flags))
}

/// Readable, or closed (which a reader learns by reading).
pub(crate) const IN: PollFlags = PollFlags::POLLIN.union(PollFlags::POLLHUP).union(PollFlags::POLLERR);

/// A short pause used when a descriptor keeps reporting a condition the loop cannot clear
/// (a pty whose last client just closed), so that the loop does not spin.
pub(crate) const BACKOFF: Duration = Duration::from_millis(20);

#[cfg(test)]
mod tests {
    use super::*;

    /// Waking ahead of a deadline never makes a paced byte early: the wait ends at the
    /// deadline or after it, however far ahead the thread has learned to wake.
    #[test]
    fn a_precise_wait_never_ends_before_its_deadline() {
        std::thread::spawn(|| {
            precise_timers();
            for _ in 0..200 {
                let deadline = Instant::now() + Duration::from_micros(300);
                wait(&mut [], Some(deadline)).unwrap();
                assert!(Instant::now() >= deadline);
            }
        })
        .join()
        .unwrap();
    }
}
