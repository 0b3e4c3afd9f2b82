"""BUG: writes 2 MB (argv[1] MB) as one line without a CR and never reads the port: the
hand's echo fills the line, the hand takes no more, and the host is blocked in its write for
ever.

Expected: `fuzz host` and `check-host` both have the `unterminated line` violation, whatever
becomes of the hang (it was NO FINDING in `fuzz host`, with the note `hang not reproduced`:
the violation went with its hang suspicion).
"""
import os
import sys

mb = int(sys.argv[1]) if len(sys.argv) > 1 else 2
port = os.open(os.environ["GCL_PORT"], os.O_RDWR | os.O_NOCTTY)
data = b"A" * (mb << 20)
while data:
    data = data[os.write(port, data):]
