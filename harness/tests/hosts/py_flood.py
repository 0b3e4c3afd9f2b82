"""BUG: writes 100 MB to the port (argv[1] MB), one line that never ends, reading what comes
back (the hand's echo) in a thread, then exits.

Expected: what `gcl check-host` / `gcl fuzz host` keep of it is capped, with a note of what
was cut; their memory stays bounded.
"""
import os
import sys
import threading

mb = int(sys.argv[1]) if len(sys.argv) > 1 else 100
port = os.open(os.environ["GCL_PORT"], os.O_RDWR | os.O_NOCTTY)
done = threading.Event()


def drain():
    while not done.is_set():
        try:
            os.read(port, 1 << 16)
        except OSError:
            return


threading.Thread(target=drain, daemon=True).start()
chunk = b"A" * (1 << 20)
for _ in range(mb):
    os.write(port, chunk)
done.set()
