//! `gcl sim --pty`: the hand behind a pseudo-terminal, which any program that opens a serial
//! port by path (pyserial, termios, the `serial:` target) can use.
//!
//! The slave side is set raw (`cfmakeraw`): no echo by the line discipline, no CR/NL
//! translation, no signals from ^C, so every byte reaches the hand as sent. The pty is created
//! at the hand's line rate, so a host that never sets a speed talks at the hand's rate; that is
//! the only time the simulator sets the port's speed (before its path is known to anyone): from
//! then on the speed is the host's, and the simulator only reads it, at each crossing.
//!
//! The port opens and closes like a serial port. The simulator keeps its own descriptor of the
//! slave, so a host closing the port never hangs up the master and the hand keeps its state
//! across a reopen; it watches the slave's path with inotify to see hosts open and close it.
//! While no host has the port open the hand runs on, but what it sends is lost (so the
//! power-up banner is never seen by a host that opens the port later; the answer to a RESET
//! the host sends is). When the last host closes the port, what it had not read is discarded,
//! both in the simulator's queue and in the slave's input buffer.
//!
//! Both ends of the pty are close-on-exec from creation, so no child (a host under `gcl fuzz host`
//! or `gcl check-host`) holds them: the three commands share one pty behaviour. Each byte crossing
//! is judged at the speed the host has set then (read with `TCGETS2`, so the serialport crate's
//! arbitrary rates too; within 2 % is the same rate), and garbled on a mismatch, which is noted in
//! the trace and told to the CLI once per change. The transport also follows the host's reads and
//! writes in order, to tell a host that writes before reading its answer; on such a (tapped) line
//! the master is in packet mode, so a host's flush of its input (`tcflush(TCIFLUSH)`), which
//! consumes what was waiting as a read does, is seen too.

use std::io::{Read, Write};
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, OwnedFd};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};
use std::time::Instant;

use nix::fcntl::{FcntlArg, OFlag, fcntl};
use nix::poll::{PollFd, PollFlags};
use nix::sys::inotify::{AddWatchFlags, InitFlags, Inotify};
use nix::sys::termios::{self, BaudRate, FlushArg, SetArg};

use super::wait::{BACKOFF, IN, precise_timers, ready, wait};
use super::{Engine, SimError};

/// How soon a write the pty master refused is tried again.
const WRITE_RETRY: std::time::Duration = std::time::Duration::from_millis(5);

/// Who is told of a speed mismatch ([`Pty::on_speed_mismatch`]).
struct Notice(Box<dyn FnMut(&str) + Send>);

impl std::fmt::Debug for Notice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Notice")
    }
}

/// A pseudo-terminal pair held by the simulator.
#[derive(Debug)]
pub struct Pty {
    master: nix::pty::PtyMaster,
    slave: OwnedFd,
    path: PathBuf,
    link: Option<PathBuf>,
    watch: Inotify,
    /// Whether a host has the port open.
    open: bool,
    /// Whether bytes are garbled while the host's speed differs from the hand's.
    speed_check: bool,
    /// The speed the host has set, read once in this turn of the serving loop (`None`: not
    /// read yet): every byte that crosses in one turn crosses at the same moment.
    speed_now: Option<Option<u32>>,
    /// The last mismatch noted in the trace (host rate, hand rate).
    mismatch: Option<(u32, u32)>,
    /// Told each new speed mismatch (the CLI prints it on stderr).
    on_mismatch: Option<Notice>,
    /// The host's reads and writes of the slave (`IN_ACCESS`, `IN_MODIFY`), in the order they
    /// happened. Only a tapped line uses them: on any other the watch is removed when serving
    /// starts, so neither the host's reads and writes nor the simulator's pay for it.
    reads: Option<Inotify>,
    /// Output went to the host since it was last seen reading.
    wrote_since_read: bool,
    /// Host bytes were read whose write (`IN_MODIFY`) had not been seen: it may come late,
    /// even after output that answers them.
    expect_modify: bool,
    /// A write was seen whose bytes have not been read yet.
    pending_write: bool,
    /// The host wrote after output went to it and before it read any of it (a write seen
    /// before the read): the next bytes judged were sent with that output unread.
    wrote_before_read: bool,
    /// The master is in packet mode (a tapped line): the host's flushes of its input are seen.
    packet: bool,
}

/// The status byte a pty master in packet mode puts before the slave's output.
const TIOCPKT_DATA: u8 = 0;
/// The status bit of a pty master in packet mode that says the slave's input was flushed.
const TIOCPKT_FLUSHREAD: u8 = 1;

fn pty_err(what: &str, e: impl std::fmt::Display) -> SimError {
    SimError::Pty(format!("{what}: {e}"))
}

impl Pty {
    /// Creates a raw pty at `rate` bit/s (the hand's line rate, [`Engine::line_baud`]: a host
    /// that sets no speed talks at it; `None`, an unpaced line, leaves the pty's default); with
    /// `link`, also a symbolic link to its slave at that path (an existing symbolic link there
    /// is replaced unless it points at a pty that exists, i.e. whose master is held open, as by
    /// another simulator; any other file is an error). The link is removed when the `Pty` is
    /// dropped.
    ///
    /// The speed is set here, before the path or the link exists for anyone to open, and never
    /// again: a host that opens the port as soon as it is announced and sets its speed keeps
    /// that speed.
    pub fn open(link: Option<&Path>, rate: Option<u32>) -> Result<Pty, SimError> {
        // Both ends close-on-exec from the moment they exist (not set afterwards: a child
        // another thread starts in between would keep them). A host holding the simulator's
        // own slave would keep the port "open" after it closed it, so what it left unread would
        // survive its reopen, unlike on `gcl sim --pty`; a leftover holding the master would
        // keep the line up.
        let master = nix::pty::posix_openpt(OFlag::O_RDWR | OFlag::O_NOCTTY | OFlag::O_CLOEXEC)
            .map_err(|e| pty_err("cannot create a pty", e))?;
        nix::pty::grantpt(&master).map_err(|e| pty_err("cannot create a pty (grantpt)", e))?;
        nix::pty::unlockpt(&master).map_err(|e| pty_err("cannot create a pty (unlockpt)", e))?;
        let path = PathBuf::from(nix::pty::ptsname_r(&master).map_err(|e| pty_err("ptsname", e))?);
        // std opens with O_CLOEXEC.
        let slave: OwnedFd = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::libc::O_NOCTTY | nix::libc::O_NONBLOCK)
            .open(&path)
            .map_err(|e| pty_err("cannot open the pty's slave", e))?
            .into();
        let mut t = termios::tcgetattr(&slave).map_err(|e| pty_err("tcgetattr", e))?;
        termios::cfmakeraw(&mut t);
        if let Some(rate) = rate {
            termios::cfsetspeed(&mut t, speed_for(rate)).map_err(|e| pty_err("cfsetspeed", e))?;
        }
        termios::tcsetattr(&slave, SetArg::TCSANOW, &t).map_err(|e| pty_err("tcsetattr", e))?;
        fcntl(master.as_raw_fd(), FcntlArg::F_SETFL(OFlag::O_NONBLOCK))
            .map_err(|e| pty_err("cannot make the master non-blocking", e))?;
        // The simulator's own slave descriptor only ever drains what a host left unread (it
        // was opened non-blocking).
        struct Pair {
            master: nix::pty::PtyMaster,
            slave: OwnedFd,
        }
        let pair = Pair { master, slave };
        let watch = Inotify::init(InitFlags::IN_NONBLOCK | InitFlags::IN_CLOEXEC)
            .map_err(|e| pty_err("cannot watch the pty (inotify)", e))?;
        watch
            .add_watch(&path, AddWatchFlags::IN_OPEN | AddWatchFlags::IN_CLOSE)
            .map_err(|e| pty_err("cannot watch the pty (inotify)", e))?;
        let reads = Inotify::init(InitFlags::IN_NONBLOCK | InitFlags::IN_CLOEXEC)
            .map_err(|e| pty_err("cannot watch the pty (inotify)", e))?;
        reads
            .add_watch(&path, AddWatchFlags::IN_ACCESS | AddWatchFlags::IN_MODIFY)
            .map_err(|e| pty_err("cannot watch the pty (inotify)", e))?;
        let mut pty = Pty {
            reads: Some(reads),
            wrote_since_read: false,
            expect_modify: false,
            pending_write: false,
            wrote_before_read: false,
            packet: false,
            master: pair.master,
            slave: pair.slave,
            path,
            link: None,
            watch,
            open: true,
            speed_check: true,
            speed_now: None,
            mismatch: None,
            on_mismatch: None,
        };
        if let Some(l) = link {
            make_link(&pty.path, l)?;
            pty.link = Some(l.to_path_buf());
        }
        Ok(pty)
    }

    /// The slave's path (`/dev/pts/N`).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The symbolic link, if one was made.
    pub fn link(&self) -> Option<&Path> {
        self.link.as_deref()
    }

    /// Turns the speed check on (the default) or off: while on, and the line is paced, bytes
    /// cross garbled in both directions whenever the speed the host set on the port differs
    /// from the hand's rate, as through a UART at the wrong rate. Each byte is judged at the
    /// speed set when it crosses: a host byte when the simulator takes it from the line, a
    /// hand byte when its wire time has come and it is written to the host's side.
    pub fn set_speed_check(&mut self, on: bool) {
        self.speed_check = on;
    }

    /// Tells `notice` of each speed mismatch, once per change (the same line goes into the
    /// trace): `gcl sim` prints it, since a client at the wrong speed sees only garbage, and
    /// `check-host` and `fuzz host` put it in the violations the garbled bytes make.
    pub fn on_speed_mismatch(&mut self, notice: impl FnMut(&str) + Send + 'static) {
        self.on_mismatch = Some(Notice(Box::new(notice)));
    }

    /// The speed the host set on the port (the slave's termios, shared by every descriptor of
    /// it), in bit/s, read once per turn of the serving loop. Read with `TCGETS2`, so an
    /// arbitrary rate (`BOTHER`, as the serialport crate sets every rate) is judged like a
    /// standard one. `None` for speed 0 (hang up: a UART keeps its rate) or a port that cannot
    /// be read: the check then stands aside.
    fn host_speed(&mut self) -> Option<u32> {
        let slave = &self.slave;
        *self
            .speed_now
            .get_or_insert_with(|| rustix::termios::tcgetattr(slave).ok().map(|t| t.output_speed()).filter(|&s| s > 0))
    }

    /// Whether bytes at `hand` bit/s arrive garbled at the host's speed (and the reverse);
    /// notes a new mismatch in the trace.
    fn garbled(&mut self, engine: &mut Engine, hand: Option<u32>) -> bool {
        let (Some(hand), true) = (hand, self.speed_check) else { return false };
        let Some(host) = self.host_speed() else { return false };
        if same_rate(host, uart_rate(hand)) {
            self.mismatch = None;
            return false;
        }
        if self.mismatch != Some((host, hand)) {
            self.mismatch = Some((host, hand));
            let line = format!(
                "the host opened the port at {host} baud; the hand runs at {}: bytes are garbled as on a real line",
                uart_rate(hand)
            );
            engine.note(&format!("speed mismatch: {line} (--no-speed-check to turn this off)"));
            if let Some(Notice(tell)) = &mut self.on_mismatch {
                tell(&line);
            }
        }
        true
    }

    /// Tells the engine when a host opened the port and when the last one closed it; on
    /// close, also discards what it left unread in the slave's input buffer.
    ///
    /// inotify merges identical events that follow each other unread (two opens in a row are
    /// one event), so opens are not counted: an open means a host is there, and a close is
    /// the last one when no other process holds the slave open (`/proc/*/fd`), or when an
    /// open follows it in the same batch (a host that closed and reopened at once: what it
    /// left unread is still discarded).
    fn take_port_events(&mut self, engine: &mut Engine) {
        let mut masks = Vec::new();
        self.read_masks(&mut masks);
        let mut i = 0;
        while i < masks.len() {
            let m = masks[i];
            if m.intersects(AddWatchFlags::IN_CLOSE) && self.open {
                // The host's session ends here unless another process still holds the slave;
                // a close followed by an open (a quick reopen) ends it too, so what it left
                // unread is discarded.
                let reopened_in_batch = masks[i + 1..].iter().any(|m| m.contains(AddWatchFlags::IN_OPEN));
                let ended = reopened_in_batch || !self.held_elsewhere() || {
                    let seen = masks.len();
                    self.read_masks(&mut masks);
                    masks[seen..].iter().any(|m| m.contains(AddWatchFlags::IN_OPEN))
                };
                if ended {
                    self.open = false;
                    self.discard_unread();
                    self.forget_reads();
                    engine.client_gone(&format!("{} closed", self.path.display()));
                }
            }
            if m.contains(AddWatchFlags::IN_OPEN) && !self.open {
                self.open = true;
                // Output before the open was lost; the new host's writes (seen, perhaps,
                // before this open) count.
                self.take_reads();
                self.wrote_since_read = false;
                self.wrote_before_read = false;
                engine.client_connected(&format!("{} opened", self.path.display()));
            }
            i += 1;
        }
    }

    fn read_masks(&self, into: &mut Vec<AddWatchFlags>) {
        while let Ok(events) = self.watch.read_events() {
            if events.is_empty() {
                break;
            }
            into.extend(events.into_iter().map(|e| e.mask));
        }
    }

    /// Discards what the host left unread in the slave's input buffer: a read through the
    /// simulator's own (non-blocking) descriptor of the slave, then a flush. Known limit: a
    /// host that reopens within a few milliseconds of its close may still find the old bytes
    /// (the kernel does not show them to the simulator's descriptor then); hosts that change
    /// the rate wait far longer before they reopen.
    fn discard_unread(&mut self) {
        let mut buf = [0u8; 4096];
        for _ in 0..1024 {
            match nix::unistd::read(self.slave.as_raw_fd(), &mut buf) {
                Ok(n) if n > 0 => {}
                Err(nix::errno::Errno::EINTR) => {}
                _ => break,
            }
        }
        let _ = termios::tcflush(&self.slave, FlushArg::TCIFLUSH);
        // That flush is ours, not the host's: its status is taken off the master now, so
        // that the next host's reads are not credited with it.
        if self.packet {
            let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLPRI)];
            let status = nix::poll::poll(&mut fds, nix::poll::PollTimeout::ZERO).is_ok_and(|n| n > 0)
                && fds[0].revents().is_some_and(|r| r.contains(PollFlags::POLLPRI));
            if status {
                // In packet mode a pending status is read before any data, alone.
                let mut one = [0u8; 1];
                let _ = nix::unistd::read(self.master.as_raw_fd(), &mut one);
            }
        }
    }

    /// The host flushed its input (`tcflush(TCIFLUSH)` or `TCIOFLUSH`, pyserial's
    /// `reset_input_buffer`): what was waiting for it is consumed, as by a read. The flush
    /// happened after the master's last read; a write seen since whose bytes have not been read
    /// yet is taken to follow it (a host that writes, then flushes an answer it had not read,
    /// is missed; one that flushes, then writes, is never taken for one that did not read).
    fn flushed(&mut self) {
        self.take_reads();
        self.wrote_since_read = false;
        if self.pending_write {
            self.wrote_before_read = false;
        }
        self.expect_modify = false;
    }

    /// Whether the host left output unread when it wrote the bytes just read: output went out
    /// and the kernel reported no read of the slave since (inotify's `IN_ACCESS`, queued by
    /// the host's read before it can write again, so a host that read its answer is never
    /// taken for one that did not); or it reported a write of the slave (`IN_MODIFY`, in the
    /// same queue, so in the order they happened) after that output and before the host's
    /// first read of it, however fast the host read once it had written; or the slave's input
    /// buffer still holds bytes (seen through the simulator's own descriptor of the slave,
    /// which shares it and only looks).
    ///
    /// A write's `IN_MODIFY` can be queued after the simulator read its bytes, even after the
    /// output that answers them: so when bytes are read whose write was not seen, the next
    /// write seen is taken for that late one, never for a new write (a correct fast host is
    /// never taken for one that wrote before reading; a host that pipelines may be missed
    /// then, as when inotify merges that late write with its next).
    fn host_has_unread(&mut self) -> bool {
        self.take_reads();
        // The bytes just read: their write was seen, or it may come late.
        self.expect_modify = !std::mem::take(&mut self.pending_write);
        let mut fds = [PollFd::new(self.slave.as_fd(), PollFlags::POLLIN)];
        let buffered = nix::poll::poll(&mut fds, nix::poll::PollTimeout::ZERO).is_ok_and(|n| n > 0)
            && fds[0].revents().is_some_and(|r| r.contains(PollFlags::POLLIN));
        let wrote_first = std::mem::take(&mut self.wrote_before_read);
        buffered || self.wrote_since_read || wrote_first
    }

    /// Takes the host's reads and writes of the slave, in order.
    fn take_reads(&mut self) {
        let Some(reads) = &self.reads else { return };
        while let Ok(events) = reads.read_events() {
            if events.is_empty() {
                break;
            }
            for e in events {
                if e.mask.contains(AddWatchFlags::IN_MODIFY) {
                    if std::mem::take(&mut self.expect_modify) {
                        // The late write of bytes already read.
                        continue;
                    }
                    self.pending_write = true;
                    if self.wrote_since_read {
                        self.wrote_before_read = true;
                    }
                }
                if e.mask.contains(AddWatchFlags::IN_ACCESS) {
                    self.wrote_since_read = false;
                    // A late write is queued before the writer can read.
                    self.expect_modify = false;
                }
            }
        }
    }

    /// Output is about to go to the host.
    fn writing(&mut self) {
        self.take_reads();
        self.wrote_since_read = true;
    }

    /// The host went: nothing that happened before counts for the next bytes.
    fn forget_reads(&mut self) {
        self.wrote_since_read = false;
        self.expect_modify = false;
        self.pending_write = false;
        self.wrote_before_read = false;
        // What came since (the new host's first write) counts.
        self.take_reads();
    }

    /// Whether a descriptor other than the simulator's own refers to the slave.
    ///
    /// A child this process is starting (another thread spawning a host, a compiler, ...)
    /// holds a copy of every descriptor of ours, the simulator's own among them, from its
    /// fork until its exec closes them (they are close-on-exec): that copy is still ours, not
    /// a host's. Taken for a host, it kept a closed port's session going, and what the last
    /// host left unread survived into the next one's (a reopen probe read an old answer when
    /// its close met such a fork, on a loaded machine).
    fn held_elsewhere(&self) -> bool {
        let me = std::process::id().to_string();
        let own = self.slave.as_raw_fd().to_string();
        let my_exe = std::fs::read_link("/proc/self/exe").ok();
        let Ok(procs) = std::fs::read_dir("/proc") else { return true };
        for p in procs.flatten() {
            let pid = p.file_name();
            let Some(pid) = pid.to_str().filter(|n| n.bytes().all(|b| b.is_ascii_digit())) else { continue };
            let Ok(fds) = std::fs::read_dir(p.path().join("fd")) else { continue };
            let mut ours_unexeced = None;
            for fd in fds.flatten() {
                if fd.file_name().to_str() == Some(own.as_str()) {
                    if pid == me {
                        continue;
                    }
                    let unexeced = *ours_unexeced.get_or_insert_with(|| {
                        parent_of(&p.path()).as_deref() == Some(me.as_str())
                            && my_exe.is_some()
                            && std::fs::read_link(p.path().join("exe")).ok() == my_exe
                    });
                    if unexeced {
                        continue;
                    }
                }
                if std::fs::read_link(fd.path()).is_ok_and(|t| t == self.path) {
                    return true;
                }
            }
        }
        false
    }

    /// Serves the hand until one of `stops` becomes readable. Returns an error only for a
    /// failure of the pty itself, never for anything a client does.
    pub fn serve(&mut self, engine: &mut Engine, stops: &[BorrowedFd<'_>]) -> Result<(), SimError> {
        precise_timers();
        // A tapped line takes the host's reads and writes as they come, so that inotify
        // never merges a late write with a new one; no other line needs them.
        let tapped = engine.tapped();
        if !tapped {
            self.reads = None;
        }
        // A tapped line also sees the host flush its input (a flush is a read); where the
        // kernel refuses packet mode, a flush goes unseen as before.
        self.packet = tapped && super::host_writes::pty_packet_mode(self.master.as_fd()).is_ok();
        // Nobody has the port open yet (a host that opened it already is seen next).
        if self.open {
            self.open = false;
            engine.client_gone("no host has the port open");
        }
        let mut buf = vec![0u8; 8192];
        let mut backoff_until: Option<Instant> = None;
        let mut write_blocked = false;
        self.take_port_events(engine);
        loop {
            let now = Instant::now();
            let readable_ok = backoff_until.is_none_or(|t| now >= t) && engine.wants_input();
            if backoff_until.is_some_and(|t| now >= t) {
                backoff_until = None;
            }
            // The deadline before the output check: a byte that falls due in between is
            // then either a deadline or ready to write, never neither.
            let mut deadline = engine.deadline();
            let want_write = !engine.ready_output(Instant::now()).is_empty();
            let mut flags = PollFlags::empty();
            if readable_ok {
                flags |= IN;
            }
            if want_write {
                flags |= PollFlags::POLLOUT;
            }
            if let Some(b) = backoff_until {
                deadline = Some(deadline.map_or(b, |d| d.min(b)));
            }
            // A pty master does not always report POLLOUT when its slave's reader frees room:
            // a write that was refused is retried after a short while anyway.
            if want_write && write_blocked {
                let r = now + WRITE_RETRY;
                deadline = Some(deadline.map_or(r, |d| d.min(r)));
            }
            let (master_in, port_events, host_io, stop) = {
                let mut fds = Vec::with_capacity(3 + stops.len());
                fds.push(PollFd::new(self.master.as_fd(), flags));
                fds.push(PollFd::new(self.watch.as_fd(), IN));
                if let Some(reads) = &self.reads {
                    fds.push(PollFd::new(reads.as_fd(), IN));
                }
                let own = fds.len();
                fds.extend(stops.iter().map(|s| PollFd::new(*s, IN)));
                wait(&mut fds, deadline).map_err(|e| SimError::io("waiting on the pty", e))?;
                let stop = fds[own..].iter().any(|f| ready(f, IN));
                (readable_ok && ready(&fds[0], IN), ready(&fds[1], IN), own == 3 && ready(&fds[2], IN), stop)
            };
            // What crosses from here on crosses now, at the speed the host has set now.
            self.speed_now = None;
            if host_io {
                self.take_reads();
            }
            // Opens and closes before the host's bytes: they happened before any byte the host
            // wrote after them. (Only when inotify has something: a wake-up per paced byte
            // should not cost a read of an empty queue.)
            if port_events {
                self.take_port_events(engine);
            }
            if master_in {
                while engine.wants_input() {
                    match self.master.read(&mut buf) {
                        Ok(0) => {
                            backoff_until = Some(Instant::now() + BACKOFF);
                            break;
                        }
                        // In packet mode: a status alone (a flush of the host's input), or
                        // the host's bytes after a 0.
                        Ok(_) if self.packet && buf[0] != TIOCPKT_DATA => {
                            if buf[0] & TIOCPKT_FLUSHREAD != 0 {
                                self.flushed();
                            }
                        }
                        Ok(n) => {
                            let data = if self.packet { &mut buf[1..n] } else { &mut buf[..n] };
                            if data.is_empty() {
                                continue;
                            }
                            if tapped {
                                engine.host_unread(self.host_has_unread());
                            }
                            if self.garbled(engine, engine.line_baud()) {
                                data.iter_mut().for_each(|b| *b = garble(*b));
                            }
                            engine.input(data);
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        // EIO: no process has the slave open. Cannot happen while we hold
                        // it, but a hand does not die of it either.
                        Err(_) => {
                            backoff_until = Some(Instant::now() + BACKOFF);
                            break;
                        }
                    }
                }
            }
            // Stopped: after what the host did before the stop (its open, its bytes) is taken
            // in, so that a host that opened the port, wrote and went just before it counts.
            if stop {
                break;
            }
            engine.wake();
            write_blocked = false;
            loop {
                let now = Instant::now();
                let ready_now = engine.ready_output(now).len();
                if ready_now == 0 {
                    break;
                }
                let (run, rate) = engine.head_run().unwrap_or((0, None));
                let n = ready_now.min(run.max(1));
                let garble_out = self.garbled(engine, rate);
                let out = engine.ready_output(now);
                self.writing();
                let written = if garble_out {
                    let g: Vec<u8> = out[..n].iter().map(|b| garble(*b)).collect();
                    self.master.write(&g)
                } else {
                    self.master.write(&out[..n])
                };
                match written {
                    Ok(0) => {
                        write_blocked = true;
                        break;
                    }
                    Ok(n) => engine.consumed(n),
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    // Full (the host is not reading): the output waits, and the host is not
                    // read beyond the engine's cap meanwhile.
                    Err(_) => {
                        write_blocked = true;
                        break;
                    }
                }
            }
        }
        engine.finish()
    }
}

/// The parent's pid of the process whose `/proc` folder is `proc`, as `/proc/PID/stat` gives it
/// (the fourth field, after the command name in parentheses, which may hold anything).
fn parent_of(proc: &std::path::Path) -> Option<String> {
    let stat = std::fs::read_to_string(proc.join("stat")).ok()?;
    let after_name = &stat[stat.rfind(')')? + 1..];
    after_name.split_whitespace().nth(1).map(str::to_string)
}

/// A byte as a UART at another rate would see it: not a bit-exact model of sampling at the
/// wrong rate, but never the byte sent, and never a byte of the protocol (the top bit is set),
/// so neither side can mistake it for a command, a CR, a ^C or a prompt.
fn garble(b: u8) -> u8 {
    (b.rotate_left(3) ^ 0x5A) | 0x80
}

/// Line rates and their termios speeds.
const SPEEDS: &[(u32, BaudRate)] = &[
    (50, BaudRate::B50),
    (75, BaudRate::B75),
    (110, BaudRate::B110),
    (134, BaudRate::B134),
    (150, BaudRate::B150),
    (200, BaudRate::B200),
    (300, BaudRate::B300),
    (600, BaudRate::B600),
    (1200, BaudRate::B1200),
    (1800, BaudRate::B1800),
    (2400, BaudRate::B2400),
    (4800, BaudRate::B4800),
    (9600, BaudRate::B9600),
    (19200, BaudRate::B19200),
    (38400, BaudRate::B38400),
    (57600, BaudRate::B57600),
    (115_200, BaudRate::B115200),
    (230_400, BaudRate::B230400),
];

/// The standard rate a UART set for `baud` bit/s runs at: a standard rate within 1 % of it
/// (the engine's rate comes back from a whole number of nanoseconds per byte, so 115200
/// reads as 115201), else the nearest standard rate above it.
fn uart_rate(baud: u32) -> u32 {
    let near = |r: u32| u64::from(r.abs_diff(baud)) * 100 <= u64::from(r);
    SPEEDS
        .iter()
        .map(|(r, _)| *r)
        .find(|&r| near(r))
        .or_else(|| SPEEDS.iter().map(|(r, _)| *r).find(|&r| r >= baud))
        .unwrap_or(baud)
}

/// Whether a host at `host` bit/s and a UART at `uart` bit/s understand each other: within 2 %.
/// A UART samples each bit in its middle, timed from the start bit, so over a 10-bit frame the
/// two clocks may drift apart by less than half a bit: about 4.5 % at most, and 2 % is what
/// UART datasheets recommend for 8-bit frames (Microchip's USART operational-range tables),
/// since the other side's clock has its own error. Standard rates are more than 10 % apart,
/// so this only forgives a host's arbitrary rate near the hand's.
fn same_rate(host: u32, uart: u32) -> bool {
    u64::from(host.abs_diff(uart)) * 100 <= 2 * u64::from(uart)
}

/// The termios speed of the UART rate for `baud` (a UART runs at one of these).
fn speed_for(baud: u32) -> BaudRate {
    let rate = uart_rate(baud);
    SPEEDS.iter().find(|(r, _)| *r == rate).map_or(BaudRate::B230400, |(_, b)| *b)
}

fn make_link(target: &Path, link: &Path) -> Result<(), SimError> {
    match std::fs::symlink_metadata(link) {
        Ok(m) if !m.file_type().is_symlink() => {
            return Err(SimError::Pty(format!("--link {}: exists and is not a symbolic link", link.display())));
        }
        Ok(_) => {
            // A pty's node exists only while its master is open: a link to one that exists
            // belongs to a running simulator (or terminal), which must keep it.
            let old = std::fs::read_link(link).unwrap_or_default();
            if old.starts_with("/dev/pts") && std::fs::metadata(&old).is_ok_and(|m| m.file_type().is_char_device()) {
                return Err(SimError::Pty(format!(
                    "--link {}: points at {}, a pty in use (another gcl sim?); stop it, or remove the link",
                    link.display(),
                    old.display()
                )));
            }
            // Only a simulator's leftover (a link to a pty that is gone) is replaced: any other
            // link is somebody's, and is never replaced or deleted.
            if !old.starts_with("/dev/pts") {
                return Err(SimError::Pty(format!(
                    "--link {}: exists (a link to {}) and is not a link a gcl sim left; remove it or choose another name",
                    link.display(),
                    old.display()
                )));
            }
        }
        Err(_) => {}
    }
    let name = link.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // A new temporary link (never one already there: it is not ours to remove), renamed
    // into place.
    let mut n = 0u32;
    let tmp = loop {
        let tmp = link.with_file_name(format!(".{name}.tmp{}.{n}", std::process::id()));
        match std::os::unix::fs::symlink(target, &tmp) {
            Ok(()) => break tmp,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 1000 => n += 1,
            Err(e) => return Err(SimError::Pty(format!("--link {}: {e}", link.display()))),
        }
    };
    std::fs::rename(&tmp, link).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        SimError::Pty(format!("--link {}: {e}", link.display()))
    })
}

impl Drop for Pty {
    fn drop(&mut self) {
        if let Some(l) = &self.link {
            // Only our own link: another simulator may have replaced it since.
            if std::fs::read_link(l).is_ok_and(|t| t == self.path) {
                let _ = std::fs::remove_file(l);
            }
        }
        let _ = self.master.flush();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every standard rate the hand can run at matches a host that set that very rate on
    /// the port, once it has gone through the engine's byte time and back.
    #[test]
    fn every_standard_rate_matches_itself() {
        for &(rate, speed) in SPEEDS {
            let back = super::super::engine::rate_of(gcl_host::link::byte_time(rate));
            assert_eq!(uart_rate(back), rate, "{rate} bit/s came back as {back}");
            assert_eq!(uart_rate(rate), rate);
            assert_eq!(speed_for(rate), speed);
        }
        // A rate between standard ones runs at the next one up.
        assert_eq!(uart_rate(10_000), 19200);
        assert_eq!(uart_rate(1_000_000), 1_000_000);
    }

    /// A child of ours between its fork and its exec holds a copy of the simulator's own
    /// descriptor of the slave: that is no host holding the port. A host's own open is.
    #[test]
    #[allow(unsafe_code)] // fork without exec: nothing safe makes such a child
    fn our_own_descriptor_in_a_child_not_yet_execed_is_not_a_host() {
        use nix::unistd::{ForkResult, fork};
        let pty = Pty::open(None, None).unwrap();
        assert!(!pty.held_elsewhere());
        // A fork that never execs stands for a child caught between the two.
        // SAFETY: the child only sleeps and leaves by _exit, both async-signal-safe.
        match unsafe { fork() }.unwrap() {
            ForkResult::Child => {
                std::thread::sleep(std::time::Duration::from_secs(5));
                // SAFETY: _exit runs no handler of the parent's.
                unsafe { nix::libc::_exit(0) }
            }
            ForkResult::Parent { child } => {
                let held_by_the_child = pty.held_elsewhere();
                let host = std::fs::OpenOptions::new().read(true).write(true).open(pty.path()).unwrap();
                let held_by_a_host = pty.held_elsewhere();
                drop(host);
                let _ = nix::sys::signal::kill(child, nix::sys::signal::Signal::SIGKILL);
                let _ = nix::sys::wait::waitpid(child, None);
                assert!(!held_by_the_child, "the child's copy of our own descriptor taken for a host");
                assert!(held_by_a_host, "a host's open of the port not seen");
            }
        }
    }

    /// A host's arbitrary rate near the hand's is understood; a neighbouring standard rate
    /// never is.
    #[test]
    fn a_rate_within_two_percent_is_the_same_rate() {
        assert!(same_rate(115_000, 115_200));
        assert!(same_rate(9_500, 9_600) && !same_rate(9_400, 9_600));
        for pair in SPEEDS.windows(2) {
            assert!(!same_rate(pair[0].0, pair[1].0) && !same_rate(pair[1].0, pair[0].0), "{pair:?}");
        }
    }
}
