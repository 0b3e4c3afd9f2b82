"""BUG: starts a helper that leaves its process group (setsid) and keeps the host's stderr
(and the port) open for a minute after the host exits, as a daemonizing logger would.

Expected: `gcl fuzz host` / `gcl check-host` keep their budgets, kill the helper, and say so
(a finding of kind leftover; check-host fails host-exits-cleanly).
"""
import os
import subprocess
import sys

port = os.open(os.environ["GCL_PORT"], os.O_RDWR | os.O_NOCTTY)
subprocess.Popen(
    [sys.executable, "-c", "import time; time.sleep(60)"],
    start_new_session=True,
    pass_fds=(port,),
)
os.write(port, b"\x03")
sys.stderr.write("host: helper started\n")
