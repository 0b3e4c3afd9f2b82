"""BUG: polls `FGET P` for ever and never exits (a monitoring loop with no end), every read
with a deadline (select, 5 s).

Expected: killed at the run budget while it still sends, it never exited by itself:
`check-host` fails `host-exits-cleanly` (TIMEOUT, exit 1) and `fuzz host` has one finding,
`over budget: still sending when the run budget ended` (it was PASS, exit 0, and NO FINDING).
"""
import os
import select

port = os.open(os.environ["GCL_PORT"], os.O_RDWR | os.O_NOCTTY)
while True:
    os.write(port, b"FGET P\r")
    buf = b""
    while not buf.endswith(b"=> "):
        ready, _, _ = select.select([port], [], [], 5)
        if not ready:
            break
        buf += os.read(port, 4096)
