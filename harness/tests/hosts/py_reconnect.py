"""CORRECT: a host that reconnects. It asks FGET P, closes the port without reading the
answer (as a library does when it resets its connection), waits 1 s, reopens, and goes on
with its scenario; after the reopen it sends one CR to get a fresh prompt (the resync Barrett's
API does after it changes the port's speed). On a serial port what it left unread is gone,
and a lone CR after a reopen is no doubled line ending.

Expected: a pass from `gcl check-host`; no finding from `gcl fuzz host`.
"""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "host_mutants"))
import gclhost  # noqa: E402


def scenario(port):
    gclhost.sync(port)
    port.write(b"FGET P\r")
    time.sleep(0.2)
    port.close()
    time.sleep(1.0)
    port.open()
    port.write(b"\r")
    got = gclhost.read_until(port, gclhost.PROMPT, 2.0)
    if got != b"\n\r=> ":
        raise gclhost.HostError("after the reopen the port held %r" % got)
    for line in ["FGET P", "HI", "FGET DP"]:
        gclhost.command(port, line, 5.0)


gclhost.main(scenario)
