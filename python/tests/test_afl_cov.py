"""gcl.afl_cov, the stand-in for python-afl (issue 42): a host run through
``python -m gcl.afl_cov`` writes the lines it runs as AFL edges into the map of
``__AFL_SHM_ID``, the same edges for the same path, more for a deeper one; ``import afl``
there is the stand-in, never python-afl. gcl's own tests (harness/tests/it/fuzz_host_coverage.rs)
run a fuzzing campaign on a host so.
"""

import ctypes
import os
import subprocess
import sys
import textwrap

import pytest

IPC_PRIVATE, IPC_CREAT, IPC_RMID = 0, 0o1000, 0
SIZE = 1 << 16

HOST = textwrap.dedent(
    """
    import sys
    import afl

    afl.init()
    print(afl.__doc__)


    def parse(word):
        if word == "deep":
            total = 0
            for c in word:
                total += ord(c)
            return total
        return 0


    if parse(sys.argv[1]) > 400:
        raise IndexError("deep " + sys.argv[1])
    """
)


class Map:
    """A SysV map as gcl makes one: attached here, marked for removal at once."""

    def __init__(self):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.shmat.restype = ctypes.c_void_p
        libc.shmat.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_int]
        self.id = libc.shmget(IPC_PRIVATE, SIZE, IPC_CREAT | 0o600)
        assert self.id >= 0, os.strerror(ctypes.get_errno())
        addr = libc.shmat(self.id, None, 0)
        libc.shmctl(self.id, IPC_RMID, None)
        self.bytes = (ctypes.c_ubyte * SIZE).from_address(addr)

    def edges(self):
        return {i for i in range(SIZE) if self.bytes[i]}


def run(tmp_path, word):
    host = tmp_path / "host.py"
    host.write_text(HOST)
    m = Map()
    env = dict(os.environ, __AFL_SHM_ID=str(m.id), AFL_MAP_SIZE=str(SIZE))
    r = subprocess.run(
        [sys.executable, "-m", "gcl.afl_cov", str(host), word],
        env=env, capture_output=True, text=True, timeout=60,
    )
    return r, m.edges()


def test_a_host_writes_the_same_edges_for_the_same_path_and_more_for_a_deeper_one(tmp_path):
    r, shallow = run(tmp_path, "x")
    assert r.returncode == 0, r.stderr
    assert "stand-in for python-afl" in r.stdout, r.stdout
    _, again = run(tmp_path, "x")
    assert shallow and again == shallow
    r, deep = run(tmp_path, "deep")
    # An uncaught exception stays the host's: its traceback and exit code 1.
    assert r.returncode == 1 and "IndexError: deep deep" in r.stderr, r.stderr
    assert "in parse" not in r.stderr and 'host.py", line' in r.stderr, r.stderr
    assert deep - shallow, "the deeper path reaches edges the shallow one did not"


def test_only_records_the_files_under_the_folders_it_names(tmp_path):
    host = tmp_path / "host.py"
    host.write_text(HOST)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    for only, recorded in ((elsewhere, False), (tmp_path, True)):
        m = Map()
        env = dict(os.environ, __AFL_SHM_ID=str(m.id), AFL_MAP_SIZE=str(SIZE))
        r = subprocess.run([sys.executable, "-m", "gcl.afl_cov", "--only", str(only), str(host), "x"],
                           env=env, capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        assert bool(m.edges()) == recorded, (only, len(m.edges()))


def test_without_a_map_the_host_runs_untraced(tmp_path):
    host = tmp_path / "host.py"
    host.write_text(HOST)
    env = {k: v for k, v in os.environ.items() if k != "__AFL_SHM_ID"}
    r = subprocess.run([sys.executable, "-m", "gcl.afl_cov", str(host), "x"], env=env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == "", r.stderr


@pytest.mark.parametrize("shm", ["12x", "2147483647"])
def test_a_map_that_cannot_be_attached_is_said_and_the_host_runs(tmp_path, shm):
    host = tmp_path / "host.py"
    host.write_text(HOST)
    env = dict(os.environ, __AFL_SHM_ID=shm)
    r = subprocess.run([sys.executable, "-m", "gcl.afl_cov", str(host), "x"], env=env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "gcl.afl_cov: no coverage recorded" in r.stderr, r.stderr
