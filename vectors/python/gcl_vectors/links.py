"""Links to a hand: `exec:COMMAND ARGS` (a subprocess on stdin/stdout), `tcp://HOST:PORT`
and `serial:PATH?baud=N` (pyserial). Every read and every write has a deadline, and what a
flooding hand sends is held back by its pipe or socket, not kept in memory."""

import os
import queue
import select
import socket
import subprocess
import threading
import time


# A write that makes no progress for this long fails: a hand that does not read (a process
# that ignores its input, a peer that stopped reading) cannot hang a run (as gcl's 5 s).
SEND_STALL = 5.0

# Chunks the exec reader may hold before it waits for the runner (64 x 4 KiB): a flooding
# process is then held back by its pipe.
EXEC_QUEUE_CHUNKS = 64


class TargetError(Exception):
    """A target that does not parse or does not open."""


class Disconnected(Exception):
    """The hand went away or the link failed."""


class Link:
    def send(self, data):
        raise NotImplementedError

    def recv(self, timeout):
        """Bytes that arrive within `timeout` seconds (b"" when none); Disconnected at end."""
        raise NotImplementedError

    def close(self):
        pass


class ExecLink(Link):
    def __init__(self, argv):
        try:
            self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        except OSError as e:
            raise TargetError("cannot start `%s`: %s" % (" ".join(argv), e))
        self.q = queue.Queue(maxsize=EXEC_QUEUE_CHUNKS)
        self.eof = False
        os.set_blocking(self.proc.stdin.fileno(), False)
        threading.Thread(target=self._reader, daemon=True).start()

    def _reader(self):
        out = self.proc.stdout
        while True:
            try:
                b = out.read1(4096)
            except (OSError, ValueError):
                b = b""
            self.q.put(b)
            if not b:
                return

    def send(self, data):
        fd = self.proc.stdin.fileno()
        view = memoryview(data)
        deadline = time.monotonic() + SEND_STALL
        while view:
            try:
                n = os.write(fd, view)
            except BlockingIOError:
                n = 0
            except (OSError, ValueError) as e:
                raise Disconnected("the process closed its input: %s" % e)
            if n:
                view = view[n:]
                deadline = time.monotonic() + SEND_STALL
                continue
            left = deadline - time.monotonic()
            if left <= 0:
                raise Disconnected("the process does not read its input (no progress for %gs)" % SEND_STALL)
            select.select([], [fd], [], left)

    def recv(self, timeout):
        if self.eof:
            raise Disconnected("the process ended (exit %s)" % self.proc.poll())
        try:
            b = self.q.get(timeout=max(timeout, 0))
        except queue.Empty:
            return b""
        if not b:
            self.eof = True
            raise Disconnected("the process ended its output")
        chunks = [b]
        while True:
            try:
                more = self.q.get_nowait()
            except queue.Empty:
                break
            if not more:
                self.eof = True
                break
            chunks.append(more)
        return b"".join(chunks)

    def close(self):
        try:
            self.proc.kill()
        except OSError:
            pass
        self.proc.wait(timeout=5)


class TcpLink(Link):
    def __init__(self, host, port):
        try:
            self.sock = socket.create_connection((host, port), timeout=5)
        except OSError as e:
            raise TargetError("cannot connect to %s:%s: %s" % (host, port, e))

    def send(self, data):
        try:
            self.sock.settimeout(SEND_STALL)
            self.sock.sendall(data)
        except socket.timeout:
            raise Disconnected("the peer does not read (no progress for %gs)" % SEND_STALL)
        except OSError as e:
            raise Disconnected(str(e))

    def recv(self, timeout):
        self.sock.settimeout(max(timeout, 0.001))
        try:
            b = self.sock.recv(4096)
        except socket.timeout:
            return b""
        except OSError as e:
            raise Disconnected(str(e))
        if not b:
            raise Disconnected("the peer closed the connection")
        return b

    def close(self):
        self.sock.close()


class SerialLink(Link):
    def __init__(self, path, baud):
        try:
            import serial  # pyserial, only needed for serial targets
        except ImportError:
            raise TargetError("serial targets need pyserial (python3 -m pip install pyserial)")
        try:
            self.port = serial.Serial(path, baud, timeout=0, write_timeout=SEND_STALL)
        except (serial.SerialException, OSError, ValueError) as e:
            raise TargetError("cannot open %s: %s" % (path, e))
        self.error = serial.SerialException

    def send(self, data):
        try:
            self.port.write(data)
            self.port.flush()
        except (self.error, OSError) as e:
            raise Disconnected(str(e))

    def recv(self, timeout):
        deadline = time.monotonic() + max(timeout, 0)
        try:
            while True:
                b = self.port.read(self.port.in_waiting or 1)
                if b:
                    return b
                if time.monotonic() >= deadline:
                    return b""
                time.sleep(0.002)
        except (self.error, OSError) as e:
            raise Disconnected(str(e))

    def close(self):
        self.port.close()


def parse_target(text):
    """('exec', argv) | ('tcp', host, port) | ('serial', path, baud); TargetError otherwise."""
    def bad(reason):
        return TargetError(
            "bad target `%s`: %s (expected serial:PATH[?baud=N], tcp://HOST:PORT or exec:COMMAND ARGS)" % (text, reason)
        )

    if text.startswith("serial:"):
        rest = text[len("serial:") :]
        path, _, query = rest.partition("?")
        if not path:
            raise bad("empty port path")
        baud = 9600
        if query:
            for kv in query.split("&"):
                k, _, v = kv.partition("=")
                if k != "baud" or not v.isdigit():
                    raise bad("unknown option `%s`" % kv)
                baud = int(v)
        return ("serial", path, baud)
    if text.startswith("tcp://"):
        addr = text[len("tcp://") :]
        host, sep, port = addr.rpartition(":")
        if not sep or not port.isdigit():
            raise bad("missing :PORT")
        return ("tcp", host, int(port))
    if text.startswith("exec:"):
        argv = text[len("exec:") :].split()
        if not argv:
            raise bad("empty command")
        return ("exec", argv)
    if text == "sim" or text.startswith("sim:"):
        raise bad("the in-process simulator is gcl's own; run `exec:gcl sim --stdio` instead")
    raise bad("unknown scheme")


def open_target(spec):
    if spec[0] == "exec":
        return ExecLink(spec[1])
    if spec[0] == "tcp":
        return TcpLink(spec[1], spec[2])
    return SerialLink(spec[1], spec[2])
