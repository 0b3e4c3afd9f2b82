//! How much of the hand's output a host started by us had read when it made each write to
//! its TCP connection: over TCP, the order of the host's own read and write is what tells a
//! host that waits for its answer from one that pipelines, and only the moment of the write
//! can tell it.
//!
//! Looking later cannot: a host that writes `GC` with the answer to `1FGET MCV` unread in its
//! socket and reads it a few microseconds later has an empty receive queue by the time the
//! hand's side has woken up and read the `G` (`/proc/net/tcp`, the look [`super::tcp`] falls
//! back on, itself takes milliseconds on a machine with a large connection table). So the
//! host's write calls are stopped on their way into the kernel (a seccomp filter installed in
//! the child before it runs the host, answered through a user notification listener): while
//! the host waits there, its socket is looked at through a copy of its descriptor
//! (`pidfd_getfd`), and the stream offset of the first byte the write will send is noted with
//! the bytes of output the host had read (those its socket received, less those waiting
//! unread in it); then the call goes on unchanged. The hand's side meets those offsets in the
//! stream in order and compares with all the output it had sent by then, so the verdict does
//! not depend on who runs first. The host sees nothing but a pause of a few microseconds per
//! write; a host that had read all the output sent to it is never taken for one that had not.
//!
//! Only where the kernel allows it (Linux 5.6 or later, x86-64 or aarch64, seccomp and pidfds
//! not disabled, and the right to look into the child): otherwise no listener arrives,
//! [`Marks::watched`] stays false and the TCP transport looks as before. What bypasses
//! `write`, `writev`, `sendto`, `sendmsg` and `sendmmsg` (io_uring, `sendfile`, `splice`) is
//! not seen. The host runs with `no_new_privs` (a set-uid program it starts does not gain
//! privileges), and a signal that reaches it during one of those pauses interrupts the call
//! as it would a blocked write.
//!
//! The filter stays on every process the host starts, for its whole life, and its writes are
//! answered only while the watch lasts: a process the host leaves behind (a daemon holding
//! neither the port nor stderr) would get ENOSYS from every write after the run. So when some
//! process still uses the filter after the host ended ([`WriteWatch::outlived`]), the run
//! finds it by the `GCL_HOST_RUN` mark in its environment, kills it and names it, as it does
//! a process left holding the port. A host that installs a seccomp listener of its own gets
//! EBUSY (a process tree has one listener at most; `--pty` watches without one).
#![allow(unsafe_code)]

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::sync::{Arc, Mutex};

use nix::libc;

use super::wait::{StopHandle, StopSignal, stop_pair};

/// For each write of a host to its connection: where in the stream its bytes begin, and how
/// much of the hand's output the host had read when it made it.
#[derive(Debug, Clone, Default)]
pub struct Marks(Arc<Mutex<MarksInner>>);

#[derive(Debug, Default)]
struct MarksInner {
    /// A listener arrived: every write of the host is seen.
    watched: bool,
    /// A write to a socket could not be looked into (a host that forbade it): the marks are
    /// not the whole truth.
    blind: bool,
    /// By the host's local port (one connection each): the writes not yet taken, as the
    /// offset of their first byte and the bytes of output the host had read then.
    by_port: BTreeMap<u16, BTreeMap<u64, u64>>,
    /// By the host's local port: the connection's socket (its inode: a port may serve a
    /// later connection too), and the count of bytes written at its first write (where its
    /// stream begins; the kernel's count may include the SYN).
    origin: BTreeMap<u16, (String, u64)>,
}

impl Marks {
    /// Whether the host's writes are seen (the filter is in place): the marks are then the
    /// whole truth about its writes.
    pub fn watched(&self) -> bool {
        self.0.lock().is_ok_and(|m| m.watched && !m.blind)
    }

    /// Whether a write on the connection from the host's `port` was seen (one from a process
    /// outside the watch, a program the host asked to talk to the hand, is not).
    pub fn seen(&self, port: u16) -> bool {
        self.0.lock().is_ok_and(|m| m.origin.contains_key(&port))
    }

    /// Takes the writes that begin in `from..to` of the connection from the host's `port`,
    /// in order: each one's offset and how many bytes of output the host had read when it
    /// made it.
    pub fn take(&self, port: u16, from: u64, to: u64) -> Vec<(u64, u64)> {
        let Ok(mut m) = self.0.lock() else { return Vec::new() };
        let Some(writes) = m.by_port.get_mut(&port) else { return Vec::new() };
        let found: Vec<(u64, u64)> = writes.range(from..to).map(|(o, r)| (*o, *r)).collect();
        for (o, _) in &found {
            writes.remove(o);
        }
        found
    }

    /// A write on the connection from `port` (its socket `socket`) that begins after
    /// `written` bytes (by the kernel's count), made when the host had read `read` bytes.
    fn write(&self, port: u16, socket: &str, written: u64, read: u64) {
        if let Ok(mut m) = self.0.lock() {
            if m.origin.get(&port).is_none_or(|(s, _)| s != socket) {
                // A new connection: its stream begins here.
                m.origin.insert(port, (socket.to_string(), written));
                m.by_port.remove(&port);
            }
            let offset = written.saturating_sub(m.origin[&port].1);
            m.by_port.entry(port).or_default().insert(offset, read);
        }
    }

    fn set_blind(&self) {
        if let Ok(mut m) = self.0.lock() {
            m.blind = true;
        }
    }

    fn set_watched(&self) {
        if let Ok(mut m) = self.0.lock() {
            m.watched = true;
        }
    }
}

/// Watches the writes of one host to the hand at `hand` (its TCP address), from before it
/// starts: [`WriteWatch::prepare`] readies the command, and
/// [`WriteWatch::spawned`] is called once the spawn has returned, whatever it returned.
#[derive(Debug)]
pub struct WriteWatch {
    marks: Marks,
    /// The child's end of the pair the listener comes back through (close-on-exec, at a high
    /// number so that the host is unlikely to reuse it for a descriptor of its own: writes to
    /// that number are not stopped).
    child_end: Option<OwnedFd>,
    stop: StopHandle,
    thread: Option<std::thread::JoinHandle<()>>,
}

/// The lowest descriptor number for the child's end of the pair.
const HIGH_FD: RawFd = 900;

#[cfg(target_arch = "x86_64")]
const AUDIT_ARCH: u32 = 0xC000_003E;
#[cfg(target_arch = "aarch64")]
const AUDIT_ARCH: u32 = 0xC000_00B7;

impl WriteWatch {
    /// Prepares the watch (`None` where this platform cannot have one).
    pub fn new(hand: SocketAddr) -> Option<WriteWatch> {
        if !cfg!(any(target_arch = "x86_64", target_arch = "aarch64")) {
            return None;
        }
        let mut pair = [-1 as RawFd; 2];
        // SAFETY: `pair` has room for the two descriptors the call makes.
        if unsafe { libc::socketpair(libc::AF_UNIX, libc::SOCK_SEQPACKET | libc::SOCK_CLOEXEC, 0, pair.as_mut_ptr()) }
            != 0
        {
            return None;
        }
        // SAFETY: the call just made them, and nothing else owns them.
        let (ours, theirs) = unsafe { (OwnedFd::from_raw_fd(pair[0]), OwnedFd::from_raw_fd(pair[1])) };
        let high = nix::fcntl::fcntl(theirs.as_raw_fd(), nix::fcntl::FcntlArg::F_DUPFD_CLOEXEC(HIGH_FD)).ok()?;
        drop(theirs);
        // SAFETY: `high` is a new descriptor that nothing else owns.
        let child_end = unsafe { OwnedFd::from_raw_fd(high) };
        let marks = Marks::default();
        let (stop, stopped) = stop_pair().ok()?;
        let thread = {
            let marks = marks.clone();
            std::thread::Builder::new()
                .name("host-writes".into())
                .spawn(move || {
                    if let Some(listener) = receive_listener(&ours) {
                        drop(ours);
                        marks.set_watched();
                        serve(&listener, hand, &marks, &stopped);
                    }
                })
                .ok()?
        };
        Some(WriteWatch { marks, child_end: Some(child_end), stop, thread: Some(thread) })
    }

    /// The marks the hand's side reads.
    pub fn marks(&self) -> Marks {
        self.marks.clone()
    }

    /// Has the child install the filter and hand its listener back before it runs the host.
    /// A failure there leaves the host unwatched, never unstarted.
    pub fn prepare(&self, command: &mut std::process::Command) {
        use std::os::unix::process::CommandExt;
        let Some(fd) = self.child_end.as_ref().map(|f| f.as_raw_fd()) else { return };
        let filter = filter(fd);
        // SAFETY: the hook runs between fork and exec; it only makes system calls on memory
        // made before the fork (`filter`, moved in), with no allocation and no lock.
        unsafe {
            command.pre_exec(move || {
                install(fd, &filter);
                Ok(())
            });
        }
    }

    /// After the spawn: our copy of the child's end goes (the listener, or the end of the
    /// stream when the child sent none, reaches the watch's thread).
    pub fn spawned(&mut self) {
        self.child_end = None;
    }

    /// Whether some process still uses the filter `grace` after the host ended: one the host
    /// left behind (a daemon that holds neither the port nor stderr). It cannot outlive the
    /// watch unharmed (once the listener goes, its every write fails with ENOSYS), so the run
    /// looks for it, kills it and names it. The listener says when the last process using
    /// the filter is gone (the watch's thread then ends).
    pub fn outlived(&self, grace: std::time::Duration) -> bool {
        let Some(thread) = self.thread.as_ref().filter(|_| self.marks.0.lock().is_ok_and(|m| m.watched)) else {
            return false;
        };
        let until = std::time::Instant::now() + grace;
        while !thread.is_finished() {
            if std::time::Instant::now() >= until {
                return true;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        false
    }
}

impl Drop for WriteWatch {
    fn drop(&mut self) {
        self.child_end = None;
        self.stop.stop();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The seccomp program: the write calls of this architecture are handed to the listener,
/// except on `skip` (the pair's end the listener itself goes through); everything else runs.
fn filter(skip: RawFd) -> Vec<libc::sock_filter> {
    const LD: u16 = (libc::BPF_LD | libc::BPF_W | libc::BPF_ABS) as u16;
    const JEQ: u16 = (libc::BPF_JMP | libc::BPF_JEQ | libc::BPF_K) as u16;
    const JGE: u16 = (libc::BPF_JMP | libc::BPF_JGE | libc::BPF_K) as u16;
    const RET: u16 = (libc::BPF_RET | libc::BPF_K) as u16;
    let op = |code: u16, jt: u8, jf: u8, k: u32| libc::sock_filter { code, jt, jf, k };
    #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
    let arch = AUDIT_ARCH;
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    let arch = 0;
    let writes = [libc::SYS_write, libc::SYS_writev, libc::SYS_sendto, libc::SYS_sendmsg, libc::SYS_sendmmsg];
    let n = writes.len() as u8;
    // 0: arch; 1: other arch -> allow; 2: nr; 3: x32 -> allow; 4..4+n: writes -> check;
    // 4+n: allow; 5+n: args[0]; 6+n: skip -> allow; 7+n: notify; 8+n: allow.
    let mut p = vec![op(LD, 0, 0, 4), op(JEQ, 0, 2 + n, arch), op(LD, 0, 0, 0), op(JGE, n, 0, 0x4000_0000)];
    for (i, nr) in writes.iter().enumerate() {
        p.push(op(JEQ, n - i as u8, 0, *nr as u32));
    }
    p.push(op(RET, 0, 0, libc::SECCOMP_RET_ALLOW));
    p.push(op(LD, 0, 0, 16));
    p.push(op(JEQ, 1, 0, skip as u32));
    p.push(op(RET, 0, 0, libc::SECCOMP_RET_USER_NOTIF));
    p.push(op(RET, 0, 0, libc::SECCOMP_RET_ALLOW));
    p
}

/// In the child: installs `filter` with a listener and sends the listener through `fd`.
fn install(fd: RawFd, filter: &[libc::sock_filter]) {
    let prog = libc::sock_fprog { len: filter.len() as u16, filter: filter.as_ptr() as *mut libc::sock_filter };
    // SAFETY: plain system calls on memory made before the fork and alive for the call; no
    // allocation, no lock (this runs between fork and exec).
    unsafe {
        if libc::prctl(libc::PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 {
            return;
        }
        let listener = libc::syscall(
            libc::SYS_seccomp,
            libc::SECCOMP_SET_MODE_FILTER,
            libc::SECCOMP_FILTER_FLAG_NEW_LISTENER,
            &prog as *const libc::sock_fprog,
        );
        if listener < 0 {
            return;
        }
        let listener = listener as RawFd;
        let mut byte = [0u8; 1];
        let mut iov = libc::iovec { iov_base: byte.as_mut_ptr().cast(), iov_len: 1 };
        // Room for one descriptor's control message, aligned.
        let mut control = [0u64; 4];
        let mut msg: libc::msghdr = std::mem::zeroed();
        msg.msg_iov = &mut iov;
        msg.msg_iovlen = 1;
        msg.msg_control = control.as_mut_ptr().cast();
        msg.msg_controllen = libc::CMSG_SPACE(std::mem::size_of::<RawFd>() as u32) as _;
        let cmsg = libc::CMSG_FIRSTHDR(&msg);
        if !cmsg.is_null() {
            (*cmsg).cmsg_level = libc::SOL_SOCKET;
            (*cmsg).cmsg_type = libc::SCM_RIGHTS;
            (*cmsg).cmsg_len = libc::CMSG_LEN(std::mem::size_of::<RawFd>() as u32) as _;
            std::ptr::write_unaligned(libc::CMSG_DATA(cmsg).cast::<RawFd>(), listener);
            libc::sendmsg(fd, &msg, libc::MSG_NOSIGNAL);
        }
        // Our copy goes: the watch holds the listener, and a host that outlives it gets an
        // error (ENOSYS) from its writes rather than waiting for ever. (So would one whose
        // listener could not be sent: a one-byte message on a local pair whose other end
        // waits for it.)
        libc::close(listener);
    }
}

/// In the watch's thread: the listener the child sent, if it sent one.
fn receive_listener(ours: &OwnedFd) -> Option<OwnedFd> {
    let mut byte = [0u8; 1];
    let mut iov = libc::iovec { iov_base: byte.as_mut_ptr().cast(), iov_len: 1 };
    let mut control = [0u64; 4];
    // SAFETY: a zeroed msghdr is a valid empty one; it points at the buffers above, which
    // outlive the call, and the control message is read only within the length the kernel
    // wrote.
    unsafe {
        let mut msg: libc::msghdr = std::mem::zeroed();
        msg.msg_iov = &mut iov;
        msg.msg_iovlen = 1;
        msg.msg_control = control.as_mut_ptr().cast();
        msg.msg_controllen = std::mem::size_of_val(&control) as _;
        let n = loop {
            let n = libc::recvmsg(ours.as_raw_fd(), &mut msg, libc::MSG_CMSG_CLOEXEC);
            if n >= 0 || nix::errno::Errno::last() != nix::errno::Errno::EINTR {
                break n;
            }
        };
        if n <= 0 {
            return None;
        }
        let cmsg = libc::CMSG_FIRSTHDR(&msg);
        if cmsg.is_null() || (*cmsg).cmsg_level != libc::SOL_SOCKET || (*cmsg).cmsg_type != libc::SCM_RIGHTS {
            return None;
        }
        let fd = std::ptr::read_unaligned(libc::CMSG_DATA(cmsg).cast::<RawFd>());
        (fd >= 0).then(|| OwnedFd::from_raw_fd(fd))
    }
}

/// Answers the host's write calls until no process uses the filter any more, or the watch
/// is dropped.
fn serve(listener: &OwnedFd, hand: SocketAddr, marks: &Marks, stop: &StopSignal) {
    use nix::poll::{PollFd, PollFlags, PollTimeout};
    use std::os::fd::AsFd;
    loop {
        let mut fds = [PollFd::new(listener.as_fd(), PollFlags::POLLIN), PollFd::new(stop.as_fd(), PollFlags::POLLIN)];
        match nix::poll::poll(&mut fds, PollTimeout::NONE) {
            Ok(_) => {}
            Err(nix::errno::Errno::EINTR) => continue,
            Err(_) => return,
        }
        if fds[1].any().unwrap_or(true) {
            return;
        }
        let revents = fds[0].revents().unwrap_or(PollFlags::empty());
        if !revents.contains(PollFlags::POLLIN) {
            if revents.intersects(PollFlags::POLLHUP | PollFlags::POLLERR | PollFlags::POLLNVAL) {
                return;
            }
            continue;
        }
        // SAFETY: the kernel fills the zeroed structure it is given.
        let mut notif: libc::seccomp_notif = unsafe { std::mem::zeroed() };
        // SAFETY: the ioctl's argument is the structure it names.
        let got = unsafe { libc::ioctl(listener.as_raw_fd(), libc::SECCOMP_IOCTL_NOTIF_RECV, &mut notif) };
        if got < 0 {
            // The caller went away before we took it (ENOENT), or a signal: look again.
            continue;
        }
        look(&notif, hand, marks);
        let mut resp = libc::seccomp_notif_resp {
            id: notif.id,
            val: 0,
            error: 0,
            flags: libc::SECCOMP_USER_NOTIF_FLAG_CONTINUE as u32,
        };
        // SAFETY: as above. A caller that died meanwhile makes this fail, harmlessly.
        unsafe { libc::ioctl(listener.as_raw_fd(), libc::SECCOMP_IOCTL_NOTIF_SEND, &mut resp) };
    }
}

/// One stopped write call: if it goes to the connection to `hand`, notes where in the stream
/// its bytes begin and how much output the host had read (received, less what waits unread
/// in its socket).
fn look(notif: &libc::seccomp_notif, hand: SocketAddr, marks: &Marks) {
    let tid = notif.pid as i32;
    let fd = notif.data.args[0] as i32;
    // Most writes are to files and pipes: a look at the link is enough for them.
    let link = match std::fs::read_link(format!("/proc/{tid}/fd/{fd}")) {
        Ok(l) => l,
        // A host that may not be looked into.
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => return marks.set_blind(),
        // Not a descriptor (the call fails by itself), or a caller gone.
        Err(_) => return,
    };
    if !link.as_os_str().as_encoded_bytes().starts_with(b"socket:") {
        return;
    }
    let Some(sock) = their_descriptor(tid, fd) else { return marks.set_blind() };
    if address(&sock, libc::getpeername) != Some(hand) {
        return;
    }
    let port = address(&sock, libc::getsockname).map(|a| a.port());
    let counts = tcp_info(&sock).map(|i| (i.tcpi_bytes_acked, i.tcpi_bytes_received));
    match (port, queue(&sock, libc::FIONREAD), queue(&sock, libc::TIOCOUTQ), counts) {
        (Some(port), Some(unread), Some(unacked), Some((acked, received))) => {
            marks.write(port, &link.to_string_lossy(), acked + unacked, received.saturating_sub(unread))
        }
        _ => marks.set_blind(),
    }
}

/// A copy of the descriptor `fd` of the process that thread `tid` belongs to.
fn their_descriptor(tid: i32, fd: RawFd) -> Option<OwnedFd> {
    let pidfd = |pid: i32| {
        // SAFETY: a plain system call; a non-negative result is a new descriptor we own.
        let r = unsafe { libc::syscall(libc::SYS_pidfd_open, pid, 0) };
        (r >= 0).then(|| unsafe { OwnedFd::from_raw_fd(r as RawFd) })
    };
    let process = pidfd(tid).or_else(|| {
        let status = std::fs::read_to_string(format!("/proc/{tid}/status")).ok()?;
        let tgid = status.lines().find_map(|l| l.strip_prefix("Tgid:"))?.trim().parse().ok()?;
        pidfd(tgid)
    })?;
    // SAFETY: as above.
    let r = unsafe { libc::syscall(libc::SYS_pidfd_getfd, process.as_raw_fd(), fd, 0) };
    (r >= 0).then(|| unsafe { OwnedFd::from_raw_fd(r as RawFd) })
}

/// A socket queue length (`FIONREAD`: received and unread; `TIOCOUTQ`: sent and not yet
/// acknowledged, or not yet sent).
fn queue(sock: &OwnedFd, request: libc::Ioctl) -> Option<u64> {
    let mut n: libc::c_int = 0;
    // SAFETY: both requests write one int.
    let r = unsafe { libc::ioctl(sock.as_raw_fd(), request, &mut n) };
    (r == 0 && n >= 0).then_some(n as u64)
}

/// The socket's own address or its peer's (`getsockname`, `getpeername`), if IP.
fn address(
    sock: &OwnedFd,
    call: unsafe extern "C" fn(libc::c_int, *mut libc::sockaddr, *mut libc::socklen_t) -> libc::c_int,
) -> Option<SocketAddr> {
    // SAFETY: a zeroed sockaddr_storage is valid, the call writes within the length given,
    // and it is read as the family it says it is.
    unsafe {
        let mut a: libc::sockaddr_storage = std::mem::zeroed();
        let mut len = std::mem::size_of_val(&a) as libc::socklen_t;
        if call(sock.as_raw_fd(), (&mut a as *mut libc::sockaddr_storage).cast(), &mut len) != 0 {
            return None;
        }
        match a.ss_family as libc::c_int {
            libc::AF_INET => {
                let v4 = &*(&a as *const libc::sockaddr_storage).cast::<libc::sockaddr_in>();
                let ip = std::net::Ipv4Addr::from(u32::from_be(v4.sin_addr.s_addr));
                Some(SocketAddr::from((ip, u16::from_be(v4.sin_port))))
            }
            libc::AF_INET6 => {
                let v6 = &*(&a as *const libc::sockaddr_storage).cast::<libc::sockaddr_in6>();
                let ip = std::net::Ipv6Addr::from(v6.sin6_addr.s6_addr);
                Some(SocketAddr::from((ip, u16::from_be(v6.sin6_port))))
            }
            _ => None,
        }
    }
}

/// The socket's `TCP_INFO`, if the kernel gives it as far as `tcpi_bytes_received` (Linux
/// 4.1): the bytes of the stream the other end acknowledged (`tcpi_bytes_acked`, which may
/// count the SYN; with `TIOCOUTQ`, what is not acknowledged yet or not sent, all that was
/// written) and those received (`tcpi_bytes_received`, read or not).
fn tcp_info(sock: &OwnedFd) -> Option<libc::tcp_info> {
    // SAFETY: a zeroed tcp_info is valid, and the kernel writes at most `len` bytes of it.
    unsafe {
        let mut info: libc::tcp_info = std::mem::zeroed();
        let mut len = std::mem::size_of_val(&info) as libc::socklen_t;
        let r = libc::getsockopt(
            sock.as_raw_fd(),
            libc::IPPROTO_TCP,
            libc::TCP_INFO,
            (&mut info as *mut libc::tcp_info).cast(),
            &mut len,
        );
        let end = std::mem::offset_of!(libc::tcp_info, tcpi_bytes_received) + 8;
        (r == 0 && len as usize >= end).then_some(info)
    }
}

/// Puts a pty's master in packet mode (`TIOCPKT`): each read of it then begins with a status
/// byte, 0 before the slave's output, or alone with `TIOCPKT_FLUSHREAD` set once the slave's
/// input was flushed (`tcflush(TCIFLUSH)` by the host), which [`super::pty`] takes for a read.
/// No safe wrapper we use has this ioctl.
pub fn pty_packet_mode(master: std::os::fd::BorrowedFd<'_>) -> std::io::Result<()> {
    let on: libc::c_int = 1;
    // SAFETY: TIOCPKT reads one c_int through the pointer, which lives across the call; the
    // descriptor is borrowed, so open.
    if unsafe { libc::ioctl(master.as_raw_fd(), libc::TIOCPKT, &on) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offsets count from the connection's first write, whatever the kernel's count began
    /// at, and a new connection on the same port begins anew.
    #[test]
    fn writes_are_placed_in_each_connections_own_stream() {
        let m = Marks::default();
        // A client's count includes its SYN: its first write begins after "1".
        m.write(40000, "socket:[7]", 1, 0);
        m.write(40000, "socket:[7]", 11, 5);
        assert_eq!(m.take(40000, 0, 10), vec![(0, 0)]);
        assert_eq!(m.take(40000, 10, 13), vec![(10, 5)]);
        // Taken once.
        assert_eq!(m.take(40000, 10, 13), Vec::<(u64, u64)>::new());
        // A write not yet taken goes with its connection.
        m.write(40000, "socket:[7]", 14, 9);
        m.write(40000, "socket:[8]", 0, 0);
        assert_eq!(m.take(40000, 0, 20), vec![(0, 0)]);
        assert_eq!(m.take(40001, 0, 20), Vec::<(u64, u64)>::new());
        // A connection no write was seen on is not judged by the marks.
        assert!(m.seen(40000) && !m.seen(40001));
    }
}
