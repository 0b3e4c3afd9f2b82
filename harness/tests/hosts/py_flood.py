"""BUG: writes 100 MB to the port (argv[1] MB), a line that never ends, then exits.

Expected: what `gcl check-host` / `gcl fuzz host` keep of it is capped, with a note of what
was cut; memory stays bounded.
"""
import os
import sys

mb = int(sys.argv[1]) if len(sys.argv) > 1 else 100
port = os.open(os.environ["GCL_PORT"], os.O_RDWR | os.O_NOCTTY)
chunk = b"A" * (1 << 20)
for _ in range(mb):
    os.write(port, chunk)
os.close(port)
