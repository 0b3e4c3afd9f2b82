"""The runner's verdicts and exit codes against a scripted hand on a loopback TCP port (no
gcl needed): PASS, FAIL where the answer parts, TIMEOUT, bytes after the last step, a banner
drained before the first step, and a hand that hangs up (ERROR)."""

import contextlib
import io
import os
import socket
import tempfile
import threading
import unittest

from gcl_vectors.__main__ import main

TRANSCRIPT = b"""gcl-transcript 1
id: scripted
title: a scripted hand
clause: seed: Command FGET
level: MUST
profile: seed

send "FGET DP\\r"
expect "FGET DP\\n\\r{int 0..2000}\\n\\r=> "

send hex 41
expect hex 2A {u16 4950..5050}
"""


class ScriptedHand:
    """Accepts one connection, sends `banner`, then answers each expected input with its reply
    (None: hang up). Stops itself when the test ends."""

    def __init__(self, script, banner=b""):
        self.server = socket.create_server(("127.0.0.1", 0))
        self.server.settimeout(10)
        self.port = self.server.getsockname()[1]
        self.script, self.banner = script, banner
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self):
        try:
            conn, _ = self.server.accept()
        except OSError:
            return
        with conn:
            conn.settimeout(10)
            conn.sendall(self.banner)
            buf = b""
            for expected, reply in self.script:
                while not buf.endswith(expected):
                    chunk = conn.recv(4096)
                    if not chunk:
                        return
                    buf += chunk
                buf = b""
                if reply is None:
                    return
                conn.sendall(reply)
            try:
                conn.recv(4096)  # until the runner closes
            except OSError:
                pass

    def close(self):
        self.server.close()
        self.thread.join(timeout=10)


ANSWER = b"FGET DP\n\r1000\n\r=> "
BLOCK = b"\x2a\x13\x88"


class Runner(unittest.TestCase):
    def setUp(self):
        fd, self.path = tempfile.mkstemp(suffix=".gcl")
        with os.fdopen(fd, "wb") as f:
            f.write(TRANSCRIPT)

    def tearDown(self):
        os.unlink(self.path)

    def write(self, text):
        with open(self.path, "wb") as f:
            f.write(text)

    def run_against(self, script, banner=b"", extra=()):
        hand = ScriptedHand(script, banner)
        out = io.StringIO()
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
                code = main(["replay", "--target", "tcp://127.0.0.1:%d" % hand.port, "--timeout", "300", *extra, self.path])
        finally:
            hand.close()
        return code, out.getvalue()

    def test_pass_after_a_banner(self):
        code, out = self.run_against([(b"FGET DP\r", ANSWER), (b"A", BLOCK)], banner=b"\n\rBarrettHand\n\r=> ")
        self.assertEqual(code, 0, out)
        self.assertIn("PASS", out)
        self.assertEqual(out.splitlines()[-1], "1 passed, 0 failed, 0 skipped", out)

    def test_fail_where_the_answer_parts(self):
        code, out = self.run_against([(b"FGET DP\r", ANSWER.replace(b"1000", b"3000"))])
        self.assertEqual(code, 1, out)
        self.assertIn("FAIL", out)
        self.assertIn("at byte 12", out)
        # The golden and the actual answer both from byte 0, the caret under the parting byte.
        lines = out.splitlines()
        actual = next(l for l in lines if l.startswith("  actual:   "))
        caret = lines[lines.index(actual) + 1]
        self.assertTrue(actual.startswith('  actual:   "FGET DP'), out)
        # The matcher knows at the fourth digit that 3000 is out of 0..2000: byte 12.
        self.assertEqual(actual[: caret.index("^")], '  actual:   "FGET DP\\n\\r300', out)

    def test_fail_on_a_block_in_the_wrong_byte_order(self):
        code, out = self.run_against([(b"FGET DP\r", ANSWER), (b"A", b"\x2a\x88\x13")])
        self.assertEqual(code, 1, out)
        self.assertIn("step 2", out)
        self.assertIn("88 13", out)

    def test_timeout_on_an_incomplete_answer(self):
        code, out = self.run_against([(b"FGET DP\r", ANSWER[:-1])])
        self.assertEqual(code, 1, out)
        self.assertIn("TIMEOUT", out)
        self.assertEqual(out.splitlines()[-1], "0 passed, 1 failed, 0 skipped", out)

    def test_bytes_after_the_last_step_fail(self):
        code, out = self.run_against([(b"FGET DP\r", ANSWER), (b"A", BLOCK + b"!")])
        self.assertEqual(code, 1, out)
        self.assertIn("sent more", out)

    def test_a_hand_that_hangs_up_is_an_error(self):
        code, out = self.run_against([(b"FGET DP\r", None)])
        self.assertEqual(code, 2, out)
        self.assertIn("ERROR", out)
        self.assertEqual(out.splitlines()[-1], "0 passed, 0 failed, 0 skipped, 1 errors", out)


    def test_a_relation_carries_a_value_from_step_to_step(self):
        related = TRANSCRIPT.replace(b"{int 0..2000}", b"{int 1..2000 as dp}").replace(
            b"{u16 4950..5050}", b"{u16 dp*5 +-1%}"
        )
        self.write(related)
        code, out = self.run_against([(b"FGET DP\r", ANSWER), (b"A", BLOCK)])
        self.assertEqual(code, 0, out)
        # DP 1100: the block must read 5445..5555, and 5000 parts at its high byte.
        code, out = self.run_against([(b"FGET DP\r", ANSWER.replace(b"1000", b"1100")), (b"A", BLOCK)])
        self.assertEqual(code, 1, out)
        self.assertIn("step 2", out)

    def test_an_answer_sooner_than_its_window_fails(self):
        self.write(TRANSCRIPT.replace(b'expect "FGET', b'expect within 300ms..2s "FGET'))
        code, out = self.run_against([(b"FGET DP\r", ANSWER), (b"A", BLOCK)])
        self.assertEqual(code, 1, out)
        self.assertIn("sooner than its window", out)

    def test_a_setup_is_skip_unless_declared_in_place(self):
        placed = TRANSCRIPT.replace(b"profile: seed\n", b"profile: seed\nrequires: object\nsetup: object 1 8500\n")
        self.write(placed)
        code, out = self.run_against([(b"FGET DP\r", ANSWER), (b"A", BLOCK)])
        self.assertEqual(code, 0, out)
        self.assertTrue(out.startswith("SKIP ") and "object 1 8500" in out and "--fixture object" in out, out)
        self.assertEqual(out.splitlines()[-1], "0 passed, 0 failed, 1 skipped", out)
        code, out = self.run_against([(b"FGET DP\r", ANSWER), (b"A", BLOCK)], extra=("--fixture", "object"))
        self.assertEqual(code, 0, out)
        self.assertTrue(out.startswith("PASS "), out)
        # A setup without the requirement does not parse (exit 2).
        self.write(TRANSCRIPT.replace(b"profile: seed\n", b"profile: seed\nsetup: object 1 8500\n"))
        code, _ = self.run_against([])
        self.assertEqual(code, 2)


if __name__ == "__main__":
    unittest.main()
