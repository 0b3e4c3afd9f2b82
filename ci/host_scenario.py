"""One scenario of a host program against a BH8 hand, for `gcl check-host` and `gcl fuzz host`
in CI (docs/src/host-libraries.md, "Grading a host and fuzzing it in CI"; the recipes in this
folder run such a command).

    python3 ci/host_scenario.py PORT        # a device path or a pyserial URL (socket://...)

It stands for your host library's own scenario: it talks to the hand as a careful host does
(^C to resync, one command line at a time ended by CR, each answer read to its prompt with a
deadline), initializes the hand, reads positions, closes and opens the fingers, and exits
0 when it ran, or 1 when it reported a broken hand (a refused command, a wrong echo, no
answer in time, a failed line) on stderr. Anything else (a crash, a hang) is a host bug for
`gcl fuzz host` to find. It needs pyserial.
"""

import sys
import time

import serial

PROMPT = b"=> "
EOL = b"\n\r"
#: How long an answer may take, seconds: most come at once; HI and a motion take a few
#: seconds on a hand.
DEADLINE = 2.0
MOTION_DEADLINE = 10.0
MOTIONS = ("HI", "C", "O")


class BrokenHand(Exception):
    """The hand did something a hand does not do."""


def read_to_prompt(port, deadline=DEADLINE):
    buf = b""
    end = time.monotonic() + deadline
    while not buf.endswith(PROMPT):
        if time.monotonic() > end:
            raise BrokenHand("no prompt within {} s; got {!r}".format(deadline, buf[-60:]))
        try:
            buf += port.read(max(1, port.in_waiting))
        except (serial.SerialException, OSError) as e:
            raise BrokenHand("the line failed: {}".format(e)) from e
    return buf[: -len(PROMPT)]


def command(port, line):
    """Sends one line; returns the answer's lines between the echo and the prompt."""
    try:
        port.write(line.encode("ascii") + b"\r")
    except (serial.SerialException, OSError) as e:
        raise BrokenHand("the line failed: {}".format(e)) from e
    parts = read_to_prompt(port, MOTION_DEADLINE if line in MOTIONS else DEADLINE).split(EOL)
    if parts[0] != line.encode("ascii"):
        raise BrokenHand("{!r} echoed as {!r}".format(line, parts[0]))
    lines = [p.decode("latin-1") for p in parts[1:] if p]
    if lines and lines[-1].startswith("ERR"):
        raise BrokenHand("{} refused: {}".format(line, lines[-1]))
    return lines


def positions(port):
    lines = command(port, "FGET P")
    try:
        return [int(v) for v in " ".join(lines).split()]
    except ValueError as e:
        raise BrokenHand("FGET P answered {!r}".format(lines)) from e


def main(url):
    try:
        port = serial.serial_for_url(url, baudrate=9600, timeout=0.05)
    except (serial.SerialException, OSError) as e:
        print("cannot open {}: {}".format(url, e), file=sys.stderr)
        return 1
    try:
        port.write(b"\x03")
        read_to_prompt(port)
        command(port, "HI")
        print("after HI:", positions(port))
        command(port, "C")
        print("closed:", positions(port))
        command(port, "O")
        print("opened:", positions(port))
        return 0
    except BrokenHand as e:
        print("broken hand: {}".format(e), file=sys.stderr)
        return 1
    finally:
        port.close()


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python3 ci/host_scenario.py PORT")
    sys.exit(main(sys.argv[1]))
