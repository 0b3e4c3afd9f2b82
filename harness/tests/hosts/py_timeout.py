"""CORRECT: a pyserial host with one long read timeout (10 s unless argv[1] says otherwise),
as real host libraries have (5, 10, 15 s). It runs the supervisory scenario, then a short
RealTime loop; anything the hand does wrong (a cut or garbled answer, a refusal, a broken
feedback block, silence) is reported on one line and the host exits 1, in RealTime or not
(exiting politely on a broken block, without ^C).

With `retry` as argv[2], a supervisory command that times out is reported and the host
goes on with the next one (as hosts that poll do).

Expected: no finding from `gcl fuzz host` with default options (the hang timeout is above
this host's own timeout), and a pass from `gcl check-host`.
"""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "host_mutants"))
import gclhost  # noqa: E402
import serial  # noqa: E402

TIMEOUT = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
RETRY = len(sys.argv) > 2 and sys.argv[2] == "retry"
BLOCK = 9  # feedback of the loop below (seed profile): 3 x (velocity, position high, low)
OBSERVE = int(os.environ.get("GCL_OBSERVE_FD", "2"))


def read_exactly(port, n):
    buf = b""
    stop = time.monotonic() + TIMEOUT
    while len(buf) < n:
        if time.monotonic() > stop:
            raise gclhost.HostError("feedback block: %d of %d bytes" % (len(buf), n))
        buf += port.read(n - len(buf))
    return buf


def read_star(port):
    """Up to the '*' that starts a feedback block, byte by byte (the block may be there too)."""
    stop = time.monotonic() + TIMEOUT
    got = b""
    while not got.endswith(b"*"):
        if time.monotonic() > stop:
            raise gclhost.HostError("no '*' after %r" % got[-40:])
        got += port.read(1)
    return got


def scenario(port):
    port.reset_input_buffer()
    port.write(b"\x03")
    gclhost.read_until(port, gclhost.PROMPT, TIMEOUT)
    for line in gclhost.SCENARIO:
        port.reset_input_buffer()
        try:
            gclhost.command(port, line, TIMEOUT)
        except gclhost.HostError as e:
            if not RETRY:
                raise
            print("host: %s (going on)" % e, file=sys.stderr)
    if RETRY:
        return
    gclhost.command(port, "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0", TIMEOUT)
    port.write(b"123LOOP\r")
    got = read_star(port)
    if not got.startswith(b"123LOOP"):
        raise gclhost.HostError("LOOP answered %r" % got)
    for _ in range(4):
        port.write(b"C\x14\x14\x14")
        read_star(port)
        block = read_exactly(port, BLOCK)
        time.sleep(0.01)
        if port.in_waiting:
            raise gclhost.HostError("feedback block longer than %d bytes" % BLOCK)
        # What it believes, by the observation protocol (GCL_OBSERVE_FD): whole blocks only.
        for m in range(3):
            os.write(OBSERVE, b"gcl-observe: P %d %d\n" % (m + 1, block[3 * m + 1] * 256 + block[3 * m + 2]))
    port.write(b"\x03")
    gclhost.read_until(port, gclhost.PROMPT, TIMEOUT)


try:
    gclhost.main(scenario)
except (ValueError, UnicodeDecodeError) as e:
    print("host: %s" % e, file=sys.stderr)
    sys.exit(1)
