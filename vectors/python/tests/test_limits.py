"""The runner's input limits, the same as the Rust reader's (host/src/files.rs), and its
deadlines, as the adversarial round of issue 20 tried them: `check` and `replay` of /dev/zero
and of an 8 GB sparse file, `check` of a FIFO, 100k-deep JSON among good files, `replay` of a
1 MB line to a hand that never reads, and a 64-hex pattern against a value with a trailing
newline. Each attack runs in a child process under a memory limit (RLIMIT_AS) and a
wall-clock bound, so a regression fails the test instead of the machine."""

import os
import shutil
import subprocess
import sys
import tempfile
import unittest

from gcl_vectors import loader
from gcl_vectors.files import FileError, read_limited
from gcl_vectors.schema import SchemaError, validate

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE_ROOT = os.path.dirname(HERE)
MEMORY = 512 << 20
WALL = 60


def bounded(*args):
    """`python3 -m gcl_vectors ARGS` under MEMORY of address space and WALL seconds."""
    code = (
        "import resource, sys; resource.setrlimit(resource.RLIMIT_AS, (%d, %d)); "
        "from gcl_vectors.__main__ import main; sys.exit(main(sys.argv[1:]))" % (MEMORY, MEMORY)
    )
    return subprocess.run(
        [sys.executable, "-c", code] + list(args),
        cwd=PACKAGE_ROOT,
        capture_output=True,
        text=True,
        timeout=WALL,
    )


class Limits(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.dir)

    def path(self, name):
        return os.path.join(self.dir, name)

    def test_the_reader_refuses_what_the_rust_reader_refuses(self):
        with open(self.path("ok.gcl"), "wb") as f:
            f.write(b"hello")
        self.assertEqual(read_limited(self.path("ok.gcl")), b"hello")
        with self.assertRaisesRegex(FileError, "larger than"):
            read_limited(self.path("ok.gcl"), 4)
        os.mkfifo(self.path("x.gcl"))
        with self.assertRaisesRegex(FileError, "named pipe"):
            read_limited(self.path("x.gcl"))
        with self.assertRaisesRegex(FileError, "character device"):
            read_limited("/dev/zero")
        with self.assertRaisesRegex(FileError, "directory"):
            read_limited(self.dir)

    def test_check_and_replay_refuse_devices_fifos_and_huge_files(self):
        os.mkfifo(self.path("fifo.json"))
        with open(self.path("big.json"), "wb") as f:
            f.truncate(8 << 30)
        zero = self.path("zero.json")
        os.symlink("/dev/zero", zero)
        for args, says in [
            (["check", "/dev/zero"], "character device"),
            (["check", zero], "character device"),
            (["check", self.path("fifo.json")], "named pipe"),
            (["check", self.path("big.json")], "larger than"),
            (["replay", "--target", "exec:true", "/dev/zero"], "character device"),
            (["replay", "--target", "exec:true", self.path("fifo.json")], "named pipe"),
            (["replay", "--target", "exec:true", self.path("big.json")], "larger than"),
        ]:
            r = bounded(*args)
            out = r.stdout + r.stderr
            self.assertIn(r.returncode, (1, 2), "%s: %s" % (args, out))
            self.assertIn(says, out, args)
            self.assertNotIn("Traceback", out, args)

    def test_deep_json_is_one_bad_file_and_the_others_are_checked(self):
        deep = self.path("deep.json")
        with open(deep, "w") as f:
            f.write("[" * 100000 + "]" * 100000)
        good = os.path.join(loader.VECTORS, "json", "seed", "status.json")
        r = bounded("check", deep, good)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("BAD %s" % deep, r.stdout)
        self.assertIn("nested too deeply", r.stdout)
        self.assertIn("ok %s" % good, r.stdout)
        self.assertNotIn("Traceback", r.stderr)

    def test_a_long_line_to_a_hand_that_never_reads_ends(self):
        line = self.path("long.gcl")
        with open(line, "wb") as f:
            f.write(b"gcl-transcript 1\nid: long\ntitle: a long line\nclause: c\nlevel: INFO\nprofile: seed\n\n")
            f.write(b'send "' + b"A" * (1 << 20) + b'\\r"\nexpect "x"\n')
        r = bounded("replay", "--target", "exec:sleep 1000", line)
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertIn("does not read its input", r.stdout + r.stderr)

    def test_patterns_end_at_the_end_of_the_string(self):
        schema = {"type": "string", "pattern": "^[0-9a-f]{64}$"}
        validate("a" * 64, schema)
        with self.assertRaises(SchemaError):
            validate("a" * 64 + "\n", schema)


if __name__ == "__main__":
    unittest.main()
