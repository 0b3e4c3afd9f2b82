"""A Python host's code coverage for ``gcl fuzz host``, without python-afl.

    python -m gcl.afl_cov [--only DIR]... host.py [ARGS...]

runs ``host.py`` as ``__main__`` with ``ARGS`` (``sys.argv`` as if it had been run itself),
and records the lines Python runs as AFL edges in the shared-memory map whose id
``gcl fuzz host`` gives each run in ``__AFL_SHM_ID`` (its size in ``AFL_MAP_SIZE``): each
line is a location (a CRC-32 of its file's path and its number, so the same line has the
same location in every run), and each step from one line to the next an edge, the map's
byte at ``location ^ (previous >> 1)`` counted up as AFL's instrumentation does. python-afl
writes the same map; this module needs no C extension, only the standard library (``ctypes``
to attach the map, ``sys.settrace`` for the lines).

The standard library's lines are not recorded (their order varies with timing more than the
host's), nor this module's; installed packages (pyserial, the host's own library) are.
``--only DIR`` (repeatable) records only the files under those folders.

A host written for python-afl (``import afl; afl.init()``) runs unchanged: ``afl`` is this
module's stand-in, whose ``init()`` does nothing (the lines are recorded from the start), so
python-afl is never imported under it. Without ``__AFL_SHM_ID``, or when the map cannot be
attached (a warning says why), the host runs untraced.
"""

import ctypes
import os
import runpy
import sys
import sysconfig
import threading
import types
import zlib

MAP_SIZE = 1 << 16
"""The map's size when ``AFL_MAP_SIZE`` does not say it (python-afl's, and AFL's default)."""


def attach(environ=None):
    """The map named by ``__AFL_SHM_ID`` (a ctypes byte array), or None."""
    environ = os.environ if environ is None else environ
    shm = environ.get("__AFL_SHM_ID", "")
    if not shm:
        return None
    try:
        shm_id = int(shm)
        size = int(environ.get("AFL_MAP_SIZE") or MAP_SIZE)
    except ValueError:
        _warn("__AFL_SHM_ID or AFL_MAP_SIZE is not a number")
        return None
    if size <= 0 or size & (size - 1):
        _warn("AFL_MAP_SIZE %d is not a power of two" % size)
        return None
    libc = ctypes.CDLL(None, use_errno=True)
    libc.shmat.restype = ctypes.c_void_p
    libc.shmat.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_int]
    addr = libc.shmat(shm_id, None, 0)
    if addr is None or addr == ctypes.c_void_p(-1).value:
        _warn("shmat(%d): %s" % (shm_id, os.strerror(ctypes.get_errno())))
        return None
    return (ctypes.c_ubyte * size).from_address(addr)


def _warn(why):
    sys.stderr.write("gcl.afl_cov: no coverage recorded: %s\n" % why)


class Recorder:
    """Writes each step from one recorded line to the next into ``area``."""

    def __init__(self, area, only=()):
        self.area = area
        self.mask = len(area) - 1
        self.prev = 0
        self.only = tuple(os.path.join(os.path.abspath(d), "") for d in only)
        self.locations = {}
        self.recorded = {}
        paths = sysconfig.get_paths()
        self.stdlib = tuple(
            os.path.join(os.path.realpath(paths[k]), "") for k in ("stdlib", "platstdlib") if k in paths
        )
        self.installed = tuple(
            os.path.join(os.path.realpath(paths[k]), "") for k in ("purelib", "platlib") if k in paths
        )
        self.own = os.path.realpath(__file__)

    def records(self, filename):
        """Whether the lines of ``filename`` are recorded (decided once per file)."""
        known = self.recorded.get(filename)
        if known is not None:
            return known
        path = os.path.realpath(filename) if not filename.startswith("<") else ""
        if not path or path == self.own:
            yes = False
        elif self.only:
            yes = path.startswith(self.only)
        else:
            yes = path.startswith(self.installed) or not path.startswith(self.stdlib)
        self.recorded[filename] = yes
        return yes

    def line(self, filename, lineno):
        """Records a step to line ``lineno`` of ``filename``."""
        key = (filename, lineno)
        cur = self.locations.get(key)
        if cur is None:
            cur = zlib.crc32(("%s:%d" % key).encode("utf-8", "surrogateescape")) & self.mask
            self.locations[key] = cur
        at = cur ^ self.prev
        hits = self.area[at]
        if hits < 255:
            self.area[at] = hits + 1
        self.prev = cur >> 1

    def on_call(self, frame, event, arg):
        """``sys.settrace``'s function: the frames of recorded files get ``on_line``."""
        if event == "call" and self.records(frame.f_code.co_filename):
            return self.on_line
        return None

    def on_line(self, frame, event, arg):
        if event == "line":
            self.line(frame.f_code.co_filename, frame.f_lineno)
        return self.on_line

    def start(self):
        """Records from now on, in this thread and in threads started later."""
        threading.settrace(self.on_call)
        sys.settrace(self.on_call)


def afl_stand_in():
    """A module named ``afl`` with python-afl's ``init`` and ``loop``: lines are recorded already."""
    afl = types.ModuleType("afl")
    afl.__doc__ = "gcl.afl_cov's stand-in for python-afl: coverage is recorded from the start."
    afl.init = lambda: None
    state = {"left": 1}

    def loop(max=None):  # noqa: A002 (python-afl's name)
        """True once: without AFL's fork server there is one run."""
        if state["left"]:
            state["left"] = 0
            return True
        return False

    afl.loop = loop
    return afl


def main(argv=None):
    args = list(sys.argv[1:] if argv is None else argv)
    only = []
    while len(args) >= 2 and args[0] == "--only":
        only.append(args[1])
        args = args[2:]
    if not args or args[0].startswith("-"):
        sys.stderr.write("usage: python -m gcl.afl_cov [--only DIR]... host.py [ARGS...]\n")
        return 2
    script = args[0]
    sys.argv = args
    sys.path[0] = os.path.dirname(os.path.abspath(script))
    sys.modules["afl"] = afl_stand_in()
    area = attach()
    if area is not None:
        Recorder(area, only).start()
    runpy.run_path(script, run_name="__main__")
    return 0


if __name__ == "__main__":
    sys.exit(main())
