"""Loading the JSON vectors of vectors/json/ with their schema check, and choosing tests by
flag. Stdlib only."""

import json
import os

from .files import read_text_limited
from .schema import SchemaError, validate

HERE = os.path.dirname(os.path.abspath(__file__))
VECTORS = os.path.normpath(os.path.join(HERE, "..", ".."))  # the vectors/ directory
KINDS = ("grammar", "parameters", "status", "layout", "codec", "lfdp", "host")


class VectorFile:
    """One file: its header fields and its tests (dicts, as in the file)."""

    def __init__(self, data):
        self.data = data
        self.kind = data["kind"]
        self.profile = data["profile"]
        self.suite_hash = data["suite_hash"]
        self.decisions = data["decisions"]
        self.tests = data["tests"]

    def open_decisions(self):
        """The ids of the open decisions (level INFO) the tests flag."""
        return sorted(d for d, v in self.decisions.items() if v["level"] == "INFO")

    def select(self, decided_otherwise=()):
        """The tests to hold an implementation to: all of them, minus those that flag a
        decision the implementation took differently (as Wycheproof's users filter)."""
        skip = set(decided_otherwise)
        return [t for t in self.tests if not skip.intersection(t["flags"])]


def schema_for(kind, vectors_dir=VECTORS):
    if kind not in KINDS:
        raise SchemaError("unknown kind `%s`" % kind)
    with open(os.path.join(vectors_dir, "schema", "%s.schema.json" % kind), encoding="utf-8") as f:
        return json.load(f)


def parse_json(text, what):
    """JSON text to a value; a document nested too deeply for the parser is a SchemaError for
    this file, never a RecursionError that stops the other files."""
    try:
        return json.loads(text)
    except RecursionError:
        raise SchemaError("%s: nested too deeply to be a vector file" % what)


def load(path, vectors_dir=VECTORS):
    """Reads and checks one vector file: its schema, its test count, unique ids and flags that
    name decisions listed in its header. The file is read with the limits of files.py (a FIFO
    or a device is refused, at most 4 MiB read). Raises SchemaError, FileError or OSError."""
    data = parse_json(read_text_limited(path), path)
    if not isinstance(data, dict) or data.get("kind") not in KINDS:
        raise SchemaError("%s: not a gcl vector file (no known `kind`)" % path)
    try:
        validate(data, schema_for(data["kind"], vectors_dir))
    except SchemaError as e:
        raise SchemaError("%s: %s" % (path, e))
    if data["number_of_tests"] != len(data["tests"]):
        raise SchemaError("%s: number_of_tests is %d but %d tests follow" % (path, data["number_of_tests"], len(data["tests"])))
    ids = [t["id"] for t in data["tests"]]
    if len(set(ids)) != len(ids):
        raise SchemaError("%s: duplicate test ids" % path)
    for t in data["tests"]:
        for fl in t["flags"]:
            if fl not in data["decisions"]:
                raise SchemaError("%s: %s flags %s, which the header does not list" % (path, t["id"], fl))
    return VectorFile(data)


def load_profile(profile, vectors_dir=VECTORS):
    """Every kind of one profile, by kind."""
    return {k: load(os.path.join(vectors_dir, "json", profile, "%s.json" % k), vectors_dir) for k in KINDS}


def profiles(vectors_dir=VECTORS):
    d = os.path.join(vectors_dir, "json")
    return sorted(p for p in os.listdir(d) if os.path.isdir(os.path.join(d, p)))
