"""The example host parser agrees with every host vector of every profile."""

import os
import sys
import unittest

from gcl_vectors import loader

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
import host_parser  # noqa: E402


class HostExample(unittest.TestCase):
    def test_every_host_vector(self):
        n = 0
        for profile in loader.profiles():
            vf = loader.load_profile(profile)["host"]
            for t in vf.tests:
                with self.subTest(profile=profile, id=t["id"]):
                    stream = bytes.fromhex(t["stream"])
                    self.assertEqual(host_parser.parse(t["request"], stream), t["outcome"], t["comment"])
                n += 1
        self.assertGreater(n, 60)

    def test_results_follow_outcomes(self):
        # A violation or an incomplete answer is never a valid GCL answer.
        for profile in loader.profiles():
            for t in loader.load_profile(profile)["host"].tests:
                if t["outcome"]["kind"] in ("violation", "incomplete"):
                    self.assertNotEqual(t["result"], "valid", t["id"])


if __name__ == "__main__":
    unittest.main()
