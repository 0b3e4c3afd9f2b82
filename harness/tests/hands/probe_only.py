"""A hand that answers only ^C and a bare CR (with a prompt) and nothing else: every command
line is swallowed. Issue 20 item 6: such a hand passes the liveness probe, so the dead-hand
rule must probe a command as well. Run as `exec:python3 probe_only.py`."""
import os
import sys

PROMPT = b"\n\r=> "
line = b""
while True:
    data = os.read(0, 4096)
    if not data:
        sys.exit(0)
    for b in data:
        if b == 3:  # ^C
            line = b""
            os.write(1, PROMPT)
        elif b == 13:  # CR: a bare one is answered, a command line is not
            if not line:
                os.write(1, PROMPT)
            line = b""
        else:
            line += bytes([b])
