"""The transcript reader and matcher follow vectors/README.md: every committed golden
parses, and the elision rules hold byte by byte."""

import glob
import os
import unittest

from gcl_vectors import loader
from gcl_vectors.matcher import ALIVE, COMPLETE, DEAD, match_prefix
from gcl_vectors.transcript import TranscriptError, parse, parse_segments

GOOD = b"""gcl-transcript 1
# a comment among header lines is dropped
id: sample
title: a sample
clause: seed: Command FGET
level: must
profile: seed, bh8-262-4.4

send "FGET DP\\r"
expect "FGET DP\\n\\r{int 0..20000} {int}\\n\\r=> "

pause 200ms
send hex 41
expect within 3s hex 2A {u16 4950..5050} ??
"""


def expect(text):
    return parse_segments(text, 1, allow_elisions=True)


class Transcripts(unittest.TestCase):
    def test_every_golden_parses(self):
        files = glob.glob(os.path.join(loader.VECTORS, "suite", "*", "*.gcl"))
        self.assertGreater(len(files), 500)
        for f in files:
            with open(f, "rb") as fh:
                t = parse(fh.read())
            self.assertEqual(t.id, os.path.basename(f)[:-4])
            self.assertIn(os.path.basename(os.path.dirname(f)), t.profiles)
            self.assertTrue(t.steps)

    def test_sample(self):
        t = parse(GOOD)
        self.assertEqual(t.id, "sample")
        self.assertEqual(t.profiles, ["seed", "bh8-262-4.4"])
        self.assertEqual(len(t.steps), 2)
        self.assertEqual(t.steps[0].send, b"FGET DP\r")
        self.assertEqual((t.steps[1].pause, t.steps[1].send, t.steps[1].within), (0.2, b"A", 3.0))

    def test_errors_name_their_line(self):
        cases = [
            (GOOD.replace(b"gcl-transcript 1", b"gcl-transcript 2"), 1),
            (GOOD.replace(b"level: must", b"colour: red"), 6),
            (GOOD.replace(b'send hex 41', b'send "{int}"'), 13),
            (GOOD.replace(b"{int 0..20000}", b"{int 9..1}"), 10),
            (GOOD.replace(b"pause 200ms", b"pause soon"), 12),
            (GOOD.replace(b"??", b"{u8 0..300}"), 14),
        ]
        for text, line in cases:
            with self.assertRaises(TranscriptError) as cm:
                parse(text)
            self.assertEqual(cm.exception.line, line, str(cm.exception))
        with self.assertRaises(TranscriptError):
            parse(GOOD.replace(b"id: sample\n", b""))

    def test_integers(self):
        self.assertEqual(match_prefix(expect('"{int}\\n"'), b"-12\n"), (COMPLETE, 4))
        self.assertEqual(match_prefix(expect('"{int}\\n"'), b"0\n"), (COMPLETE, 2))
        self.assertEqual(match_prefix(expect('"{int}\\n"'), b"007\n")[0], DEAD)
        self.assertEqual(match_prefix(expect('"{int}\\n"'), b"-0\n")[0], DEAD)
        self.assertEqual(match_prefix(expect('"{int}\\n"'), b"+5\n"), (DEAD, 0))
        # A range parts at the first digit that can no longer lead into it.
        self.assertEqual(match_prefix(expect('"{int 4950..5050}\\n"'), b"5100\n"), (DEAD, 1))
        self.assertEqual(match_prefix(expect('"{int 4950..5050}\\n"'), b"4990\n"), (COMPLETE, 5))
        self.assertEqual(match_prefix(expect('"{int -5..5}x"'), b"-6x"), (DEAD, 1))

    def test_binary_fields(self):
        e = expect("hex 2A {u16 4950..5050}")
        self.assertEqual(match_prefix(e, b"\x2a\x13\x88"), (COMPLETE, 3))
        self.assertEqual(match_prefix(e, b"\x2a\x88\x13"), (DEAD, 1), "parts at the high byte")
        self.assertEqual(match_prefix(expect("hex {i8 -2..2}"), b"\xfe"), (COMPLETE, 1))
        self.assertEqual(match_prefix(expect("hex {i8 -2..2}"), b"\xfd"), (DEAD, 0))
        self.assertEqual(match_prefix(expect("hex {i16 -1..1}"), b"\xff\xff"), (COMPLETE, 2))

    def test_shortest_match_and_lines(self):
        e = expect('"RESET{any}BarrettHand Firmware{any}\\n\\r=> "')
        data = b"RESET\n\rBarrettHand Firmware 4.4\n\r=> \n\r=> "
        self.assertEqual(match_prefix(e, data), (COMPLETE, len(data) - 5))
        self.assertEqual(match_prefix(expect('"{line}\\n\\r"'), b"ab\rc\n\r"), (DEAD, 2))
        self.assertEqual(match_prefix(expect('""'), b"x"), (COMPLETE, 0))
        self.assertEqual(match_prefix(expect('"ab"'), b"a"), (ALIVE, 1))

    def test_text_is_lines_that_are_not_a_status(self):
        e = expect('"VERS\\n\\r{text}\\n\\r=> "')
        for ok in (b"GCL seed hand 0.1", b"Firmware 4.4x\n\rBarrett", b"no ERR here", b"ER\n\rEEROR", b"\n\rx"):
            data = b"VERS\n\r" + ok + b"\n\r=> "
            self.assertEqual(match_prefix(e, data), (COMPLETE, len(data)), ok)
        # A line that begins with ERR parts the answer at its second R, first line or later.
        self.assertEqual(match_prefix(e, b"VERS\n\rERR 64\n\r=> "), (DEAD, 8))
        self.assertEqual(match_prefix(e, b"VERS\n\rv1\n\rERR 64\n\r=> "), (DEAD, 12))
        # No text at all, or only line breaks, never completes.
        self.assertEqual(match_prefix(e, b"VERS\n\r=> "), (ALIVE, 9))
        self.assertEqual(match_prefix(e, b"VERS\n\r\n\r\n\r=> ")[0], ALIVE)

    def test_text_stands_between_line_breaks(self):
        def with_expect(e):
            return parse(GOOD + b'\nsend "VERS\\r"\nexpect ' + e.encode() + b"\n")

        self.assertEqual(with_expect('"VERS\\n\\r{text}\\n\\r=> "').steps[-1].expect[6], ("text",))
        for bad in ('"x{text}\\n"', '"\\n{text}x"', '"\\n{text}"', '"{int}{text}\\n"', '"{text as a}\\n"'):
            with self.assertRaises(TranscriptError, msg=bad):
                with_expect(bad)

if __name__ == "__main__":
    unittest.main()


RELATIONS = b"""gcl-transcript 1
id: relations
title: captures, relations and a timing window
clause: seed: Parameter LCVC
level: MUST
profile: seed

send "12FGET P\\r"
expect "12FGET P\\n\\r{int 1..17800 as p1} {int p1*11/2 +-15%}\\n\\r=> "

send hex 41
expect hex 2A {i8 1..127 as v1} {i8 v1/2 +-25% as v2} {u16 p1 +-0%}

send "SM 4000\\r"
expect within 5s..30s "SM 4000\\n\\rERR 16\\n\\r=> "
"""


class Relations(unittest.TestCase):
    def test_bands_round_outward(self):
        from gcl_vectors.transcript import relation_band

        self.assertEqual(relation_band(("p1", 11, 2, 15), 100), (467, 633))
        self.assertEqual(relation_band(("v", 1, 2, 25), -80), (-50, -30))

    def test_captures_bound_later_values(self):
        from gcl_vectors.matcher import Matcher

        t = parse(RELATIONS)
        e0, e1 = t.steps[0].expect, t.steps[1].expect
        self.assertEqual(match_prefix(e0, b"12FGET P\n\r100 633\n\r=> ")[0], COMPLETE)
        self.assertEqual(match_prefix(e0, b"12FGET P\n\r100 467\n\r=> ")[0], COMPLETE)
        self.assertEqual(match_prefix(e0, b"12FGET P\n\r100 634\n\r=> ")[0], DEAD)
        self.assertEqual(match_prefix(e0, b"12FGET P\n\r0 0\n\r=> ")[0], DEAD)
        self.assertEqual(match_prefix(e0, b"12FGET P\n\r100 9"), (DEAD, 14))
        m = Matcher(e0)
        for b in b"12FGET P\n\r100 550\n\r=> ":
            m.feed(b)
        known = m.captures()
        self.assertEqual(known, {"p1": 100})
        m = Matcher(e1, known)
        for b in bytes([0x2A, 80, 40, 0, 100]):
            r = m.feed(b)
        self.assertEqual(r, COMPLETE)
        self.assertEqual(m.captures(), {"p1": 100, "v1": 80, "v2": 40})
        self.assertEqual(match_prefix(e1, bytes([0x2A, 80, 51, 0, 100]), known)[0], DEAD)
        self.assertEqual(match_prefix(e1, bytes([0x2A, 80, 40, 0, 101]), known)[0], DEAD)
        # Without the earlier capture, the relation to p1 matches nothing.
        self.assertEqual(match_prefix(e1, bytes([0x2A, 80, 40, 0, 100]))[0], DEAD)
        self.assertEqual((t.steps[2].earliest, t.steps[2].within), (5.0, 30.0))

    def test_capture_errors(self):
        for old, new in [
            (b"{int p1*11/2 +-15%}", b"{int q*11/2 +-15%}"),
            (b"as v2", b"as p1"),
            (b"v1/2 +-25%", b"v1/0 +-25%"),
            (b"v1/2 +-25%", b"v1/2 +-101%"),
            (b"v1/2 +-25%", b"2*v1 +-25%"),
            (b"{i8 1..127 as v1}", b"{line as v1}"),
            (b"within 5s..30s", b"within 30s..5s"),
        ]:
            self.assertIn(old, RELATIONS)
            with self.assertRaises(TranscriptError, msg=new):
                parse(RELATIONS.replace(old, new))
