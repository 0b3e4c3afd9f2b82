"""bh8host: a small example host library for a Barrett BH8 hand over a serial port.

It is the kind of library the gcl pytest plugin is for; its own test suite (tests/) runs it
against graded simulated hands. Every read has a deadline; whatever the hand does wrong
becomes a BH8Error.

    from bh8host import Hand
    with Hand("/dev/ttyUSB0") as hand:         # any pyserial URL: socket://host:port, ...
        hand.home()
        print(hand.get("P", motors="123"))
        print(hand.realtime_positions(velocities=[20, 20, 20], cycles=4))
"""

import time

import serial

PROMPT = b"=> "
EOL = b"\n\r"
ABORT = b"\x03"
#: RealTime: motors 1-3 send a signed velocity each; the hand answers with its velocity (one
#: byte) and position (two bytes, big-endian) per motor, after the `*` header.
RT_FLAGS = "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0"
RT_MOTORS = 3


class BH8Error(Exception):
    """The hand refused a command, broke the protocol, or did not answer in time."""


class Hand:
    """A hand on a serial port. ``url``: a device path or pyserial URL."""

    #: What ends a command line (GCL: a single CR).
    LINE_END = b"\r"

    def __init__(self, url, baud=9600, timeout=2.0):
        self.timeout = timeout
        try:
            self.port = serial.serial_for_url(url, baudrate=baud, timeout=0.05)
        except (serial.SerialException, OSError) as e:
            raise BH8Error("cannot open {}: {}".format(url, e)) from e
        self.in_loop = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def close(self):
        """Leaves RealTime (^C) if the hand is in it, and closes the port."""
        try:
            if self.in_loop:
                self.port.write(ABORT)
                self._read_until(PROMPT)
        except (BH8Error, serial.SerialException, OSError):
            pass
        finally:
            self.in_loop = False
            self.port.close()

    # -- supervisory mode ------------------------------------------------------------------

    def _read_until(self, end):
        buf = b""
        deadline = time.monotonic() + self.timeout
        while not buf.endswith(end):
            if time.monotonic() > deadline:
                raise BH8Error("no {!r} from the hand within {} s after {!r}".format(end, self.timeout, buf[-40:]))
            try:
                buf += self.port.read(max(1, self.port.in_waiting))
            except (serial.SerialException, OSError) as e:
                raise BH8Error("the line failed: {}".format(e)) from e
        return buf

    def sync(self):
        """^C, and whatever the hand had to say before its prompt is dropped."""
        self.port.write(ABORT)
        self._read_until(PROMPT)

    def command(self, line):
        """Sends one command line; returns the answer's lines (between echo and prompt)."""
        self.port.write(line.encode("ascii") + self.LINE_END)
        answer = self._read_until(PROMPT)[: -len(PROMPT)]
        parts = answer.split(EOL)
        if parts[0] != line.encode("ascii"):
            raise BH8Error("the hand echoed {!r} for {!r}".format(parts[0], line))
        lines = [p.decode("latin-1") for p in parts[1:] if p]
        if lines and lines[-1].startswith("ERR"):
            raise BH8Error("{} refused: {}".format(line, lines[-1]))
        return lines

    def version(self):
        """The firmware's version line."""
        lines = self.command("VERS")
        if not lines:
            raise BH8Error("VERS answered nothing")
        return lines[0]

    def home(self):
        """Initializes the hand (HI)."""
        self.command("HI")

    def get(self, param, motors=""):
        """A parameter's value for each of ``motors`` (``FGET``)."""
        lines = self.command("{}FGET {}".format(motors, param))
        try:
            return [int(v) for v in " ".join(lines).split()]
        except ValueError as e:
            raise BH8Error("{}FGET {}: not numbers: {!r}".format(motors, param, lines)) from e

    # -- RealTime ----------------------------------------------------------------------

    def _read_block(self, size):
        """One feedback block of ``size`` bytes."""
        block = self._read_exactly(size)
        if len(block) < size:
            raise BH8Error("a feedback block of {} bytes, {} expected".format(len(block), size))
        return block

    def _read_exactly(self, size):
        buf = b""
        deadline = time.monotonic() + self.timeout
        while len(buf) < size and time.monotonic() < deadline:
            buf += self.port.read(size - len(buf))
        return buf

    def realtime_positions(self, velocities, cycles=4):
        """Runs ``cycles`` RealTime cycles of motors 1-3 at ``velocities``; returns each
        cycle's positions."""
        self.command(RT_FLAGS)
        self.port.write(b"123LOOP" + self.LINE_END)
        self.in_loop = True
        self._read_until(b"*")
        control = b"C" + bytes(v & 0xFF for v in velocities)
        size = 1 + 3 * RT_MOTORS
        seen = []
        for _ in range(cycles):
            self.port.write(control)
            block = self._read_block(size)
            if block[:1] != b"*":
                raise BH8Error("a feedback block starts with {!r}, not '*'".format(block[:1]))
            seen.append([block[3 * m + 2] * 256 + block[3 * m + 3] for m in range(RT_MOTORS)])
        self.port.write(ABORT)
        self._read_until(PROMPT)
        self.in_loop = False
        return seen
