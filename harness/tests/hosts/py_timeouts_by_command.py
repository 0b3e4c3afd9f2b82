"""CORRECT: a pyserial host whose timeouts differ by command, as Barrett's API and real hands
have them: 2 s for the prompt after ^C (a sync), 15 s for the banner after RESET, 10 s for
each other answer, 5 s for each RealTime feedback block and for the prompt after the ^C that
leaves the loop. It runs RESET, the supervisory scenario and 30 cycles of a RealTime loop;
anything the hand does wrong (a cut, garbled or refused answer, a broken block, silence) is
reported on one line and the host exits 1, in RealTime or not. (Silenced at its first, middle
and last answer, as calibration did, it waits 2, 5 and 5 s: the hang timeout was 12 s, and
RESET's 15 s a false hang.)

argv[1] (default 1) multiplies every timeout: 0.1 makes them 0.2, 1.5, 1.0 and 0.5 s, for
short test campaigns.

Expected: no finding from `gcl fuzz host` with default options (calibration measures each
kind of answer, the RESET banner's 15 s among them; a wait past the hang timeout is
confirmed before it is reported, and a host that gives up late is a note), and a pass from
`gcl check-host`.
"""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "host_mutants"))
import gclhost  # noqa: E402

SCALE = float(sys.argv[1]) if len(sys.argv) > 1 else 1.0
SYNC, RESET, ANSWER, BLOCK_WAIT = 2.0 * SCALE, 15.0 * SCALE, 10.0 * SCALE, 5.0 * SCALE
BLOCK = 9  # feedback of the loop below (seed profile): 3 x (velocity, position high, low)


def read_exactly(port, n, deadline):
    buf = b""
    stop = time.monotonic() + deadline
    while len(buf) < n:
        if time.monotonic() > stop:
            raise gclhost.HostError("feedback block: %d of %d bytes" % (len(buf), n))
        buf += port.read(n - len(buf))
    return buf


def read_star(port, deadline):
    """Up to the '*' that starts a feedback block, byte by byte (the block may be there too)."""
    stop = time.monotonic() + deadline
    got = b""
    while not got.endswith(b"*"):
        if time.monotonic() > stop:
            raise gclhost.HostError("no '*' after %r" % got[-40:])
        got += port.read(1)
    return got


def scenario(port):
    port.reset_input_buffer()
    port.write(b"\x03")
    gclhost.read_until(port, gclhost.PROMPT, SYNC)
    port.write(b"RESET\r")
    answer = gclhost.read_until(port, gclhost.PROMPT, RESET)
    if not answer.startswith(b"RESET"):
        raise gclhost.HostError("RESET answered %r" % answer[:40])
    for line in gclhost.SCENARIO:
        port.reset_input_buffer()
        gclhost.command(port, line, ANSWER)
    gclhost.command(port, "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0", ANSWER)
    port.write(b"123LOOP\r")
    got = read_star(port, ANSWER)
    if not got.startswith(b"123LOOP"):
        raise gclhost.HostError("LOOP answered %r" % got)
    for _ in range(30):
        port.write(b"C\x14\x14\x14")
        read_star(port, BLOCK_WAIT)
        read_exactly(port, BLOCK, BLOCK_WAIT)
        time.sleep(0.01)
        if port.in_waiting:
            raise gclhost.HostError("feedback block longer than %d bytes" % BLOCK)
    port.write(b"\x03")
    gclhost.read_until(port, gclhost.PROMPT, BLOCK_WAIT)


try:
    gclhost.main(scenario)
except (ValueError, UnicodeDecodeError) as e:
    print("host: %s" % e, file=sys.stderr)
    sys.exit(1)
