"""Every committed vector file loads with its schema check, and the checker refuses what it
should."""

import copy
import glob
import json
import os
import tempfile
import unittest

from gcl_vectors import loader
from gcl_vectors.schema import SchemaError, errors, validate


class Loader(unittest.TestCase):
    def test_every_committed_file_loads(self):
        files = sorted(glob.glob(os.path.join(loader.VECTORS, "json", "*", "*.json")))
        self.assertEqual(len(files), len(loader.KINDS) * len(loader.profiles()))
        for f in files:
            vf = loader.load(f)
            self.assertEqual(os.path.basename(f), vf.kind + ".json")
            self.assertEqual(os.path.basename(os.path.dirname(f)), vf.profile)
            self.assertRegex(vf.suite_hash, "^[0-9a-f]{64}$")
            for t in vf.tests:
                levels = [vf.decisions[fl]["level"] for fl in t["flags"]]
                self.assertEqual(t["result"] == "acceptable", "INFO" in levels, t["id"])

    def test_select_drops_tests_of_a_decision_taken_otherwise(self):
        vf = loader.load_profile("bh8-262-4.4")["grammar"]
        open_ = vf.open_decisions()
        self.assertTrue(open_)
        self.assertTrue(all(vf.decisions[d]["level"] == "INFO" for d in open_))
        some = [t for t in vf.tests if "framing-numbers" in t["flags"]]
        self.assertTrue(some)
        kept = vf.select(decided_otherwise=["framing-numbers"])
        self.assertEqual(len(kept), len(vf.tests) - len(some))

    def test_a_broken_file_is_refused(self):
        path = os.path.join(loader.VECTORS, "json", "seed", "host.json")
        with open(path, encoding="utf-8") as f:
            good = json.load(f)
        breakers = [
            lambda d: d["tests"][0].__setitem__("result", "maybe"),
            lambda d: d["tests"][0].pop("comment"),
            lambda d: d.__setitem__("suite_hash", "abc"),
            lambda d: d.__setitem__("number_of_tests", 1),
            lambda d: d["tests"][1].__setitem__("id", d["tests"][0]["id"]),
            lambda d: d["tests"][0]["flags"].append("no-such-decision"),
            lambda d: d["tests"][0]["outcome"].__setitem__("kind", "maybe"),
        ]
        with tempfile.TemporaryDirectory() as tmp:
            for i, brk in enumerate(breakers):
                bad = copy.deepcopy(good)
                brk(bad)
                p = os.path.join(tmp, "host.json")
                with open(p, "w", encoding="utf-8") as f:
                    json.dump(bad, f)
                with self.assertRaises(SchemaError, msg="breaker %d" % i):
                    loader.load(p)

    def test_checker_keywords(self):
        schema = {
            "type": "object",
            "properties": {"a": {"type": "integer", "minimum": 1, "maximum": 3}, "b": {"$ref": "#/$defs/s"}},
            "required": ["a"],
            "additionalProperties": False,
            "$defs": {"s": {"oneOf": [{"const": "x"}, {"type": "string", "pattern": "^y+$"}]}},
        }
        validate({"a": 2, "b": "yy"}, schema)
        self.assertTrue(errors({"a": 0}, schema))
        self.assertTrue(errors({"a": True}, schema), "a boolean is not an integer")
        self.assertTrue(errors({"a": 1, "c": 1}, schema))
        self.assertTrue(errors({"a": 1, "b": "z"}, schema))
        with self.assertRaises(SchemaError):
            errors(1, {"format": "date"})


if __name__ == "__main__":
    unittest.main()
