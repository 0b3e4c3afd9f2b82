"""BUG: a pyserial host that reads the prompt after its ^C, and after its last command, without
a deadline (a loop that polls a port with a timeout and never gives up); every other read has
a 5 s deadline (or argv[1] seconds).

Expected: one hang, `hang in py_sync_forever.py:wait_prompt`, found with default options in a
short campaign: calibration, silencing the hand at the first answer, sees the host wait past
the hang timeout its other answers give, and that hang is confirmed and reported. (Calibration
silenced it at its first, middle and last answers, 30 s at each of the first and last: the
whole of a 60 s campaign, which then said NO FINDING.)
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "host_mutants"))
import gclhost  # noqa: E402

TIMEOUT = float(sys.argv[1]) if len(sys.argv) > 1 else 5.0


def wait_prompt(port):
    buf = b""
    while not buf.endswith(gclhost.PROMPT):
        buf += port.read(1)  # the port's 50 ms timeout, and no deadline of its own


def scenario(port):
    port.write(b"\x03")
    wait_prompt(port)
    for line in gclhost.SCENARIO[:-1]:
        gclhost.command(port, line, TIMEOUT)
    port.write(gclhost.SCENARIO[-1].encode() + b"\r")
    wait_prompt(port)


gclhost.main(scenario)
