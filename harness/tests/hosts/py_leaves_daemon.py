"""BUG (of hygiene): over TCP, starts a daemon that leaves its process group (setsid) and holds
neither the port nor the host's stderr (its stdio on /dev/null), then exits. The daemon
appends a line to LOG (argv[1]) every 50 ms and, when a write fails, makes the folder
LOG.errno-N (making a folder is no write, so it works when writes do not).

Expected over `--tcp`: the daemon is under `gcl`'s write watch (a seccomp filter no process
can leave), whose writes would fail with ENOSYS (errno 38) once the run is over; so
`gcl check-host` / `gcl fuzz host` kill it after the host ended and name it (a leftover
finding; check-host fails host-exits-cleanly), and it never sees ENOSYS.
"""
import os
import socket
import subprocess
import sys

LOOP = """
import os, sys, time
log = sys.argv[1]
while True:
    try:
        fd = os.open(log, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        os.write(fd, b"alive\\n")
        os.close(fd)
    except OSError as e:
        os.makedirs("%s.errno-%d" % (log, e.errno), exist_ok=True)
    time.sleep(0.05)
"""

daemon = subprocess.Popen(
    [sys.executable, "-c", LOOP, sys.argv[1]],
    start_new_session=True,
    stdin=subprocess.DEVNULL,
    stdout=subprocess.DEVNULL,
    stderr=subprocess.DEVNULL,
)
with open(sys.argv[1] + ".pid", "w") as f:
    f.write(str(daemon.pid))
host, port = os.environ["GCL_PORT"].rsplit(":", 1)
s = socket.create_connection((host, int(port)))
s.settimeout(5)
s.sendall(b"\x03")
got = b""
while not got.endswith(b"=> "):
    got += s.recv(256)
s.close()
