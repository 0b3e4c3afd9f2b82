"""BUG: a pyserial host whose first read, the prompt after its ^C, has no deadline (a loop
that polls a port with a timeout and never gives up); every later read has a 5 s deadline (or
argv[1] seconds).

Expected: one hang, `hang in py_sync_forever.py:sync`, found with default options in a 60 s
campaign: calibration, silencing the hand at that first answer, sees the host wait past the
hang timeout its other answers give, and that hang is confirmed and reported (it was "waited
past 30 s" at answers 1 and 31, the whole --duration 60s spent measuring, and NO FINDING).
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "host_mutants"))
import gclhost  # noqa: E402

TIMEOUT = float(sys.argv[1]) if len(sys.argv) > 1 else 5.0


def sync(port):
    port.write(b"\x03")
    buf = b""
    while not buf.endswith(gclhost.PROMPT):
        buf += port.read(1)  # the port's 50 ms timeout, and no deadline of its own


def scenario(port):
    sync(port)
    for line in gclhost.SCENARIO:
        gclhost.command(port, line, TIMEOUT)


gclhost.main(scenario)
