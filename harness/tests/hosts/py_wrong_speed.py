"""BUG: sets its port to 19200 baud (argv[1]) where the hand runs at 9600, sends ^C and
`FGET P`, reads for a second (argv[2] seconds) and exits.

Expected: in real time, on a paced line, its bytes arrive garbled as on a real serial line,
and `check-host` fails `host-line-ending` with a message that says why: `speed mismatch: the
host opened the port at 19200 baud; the hand runs at 9600` (it said only `unterminated line
"\\xC2..."`). Reading longer than `fuzz host`'s hang timeout, it is suspected of a hang,
then found late by the confirmation run, where it exits and its unended line is graded:
`fuzz host` has that `unterminated line` finding (the confirmation run's violation was
dropped: NO FINDING).
"""
import os
import select
import sys
import termios
import time
import tty

baud = getattr(termios, "B" + (sys.argv[1] if len(sys.argv) > 1 else "19200"))
port = os.open(os.environ["GCL_PORT"], os.O_RDWR | os.O_NOCTTY)
tty.setraw(port)
attrs = termios.tcgetattr(port)
attrs[4] = attrs[5] = baud
termios.tcsetattr(port, termios.TCSANOW, attrs)
os.write(port, b"\x03")
time.sleep(0.5)
os.write(port, b"FGET P\r")
end = time.time() + (float(sys.argv[2]) if len(sys.argv) > 2 else 1)
while time.time() < end:
    ready, _, _ = select.select([port], [], [], 0.2)
    if ready:
        os.read(port, 4096)
