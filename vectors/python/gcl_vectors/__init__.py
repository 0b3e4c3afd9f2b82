"""gcl_vectors: use the GCL conformance vectors without the Rust toolchain.

- `python3 -m gcl_vectors replay --target TARGET FILE...` runs golden transcripts
  (vectors/suite/) against a hand, as `gcl replay` does;
- `python3 -m gcl_vectors check [FILE...]` loads JSON vectors (vectors/json/) with their
  schema check;
- `gcl_vectors.loader` loads vector files in your own tests.

Stdlib only, plus pyserial for serial targets. Written from vectors/README.md alone: the
runner has `gcl replay`'s targets, verdicts and exit codes, the loader its own small schema
checker. `files.py` reads input files with the Rust reader's limits; the links have write
deadlines and a bounded exec queue (`tests/test_limits.py` runs the attacks under a memory
limit)."""

__version__ = "1"
