"""A hand that works for a while, then hangs: it runs COMMAND (a hand on stdin/stdout, such
as `gcl sim --stdio`) and relays bytes both ways for SECONDS, then stops answering while it
keeps the pipes open. Issue 20 item 7. Usage: hangs_after.py SECONDS COMMAND ARGS..."""
import os
import subprocess
import sys
import threading
import time

seconds = float(sys.argv[1])
child = subprocess.Popen(sys.argv[2:], stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=0)
until = time.monotonic() + seconds


def to_child():
    while True:
        data = os.read(0, 4096)
        if not data:
            os._exit(0)
        if time.monotonic() < until:
            child.stdin.write(data)


def from_child():
    while True:
        data = child.stdout.read(4096)
        if not data:
            return
        if time.monotonic() < until:
            os.write(1, data)


threading.Thread(target=from_child, daemon=True).start()
to_child()
