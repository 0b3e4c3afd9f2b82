"""gcl_vectors: use the GCL conformance vectors without the Rust toolchain.

- `python3 -m gcl_vectors replay --target TARGET FILE...` runs golden transcripts
  (vectors/suite/) against a hand, as `gcl replay` does;
- `python3 -m gcl_vectors check [FILE...]` loads JSON vectors (vectors/json/) with their
  schema check;
- `gcl_vectors.loader` loads vector files in your own tests.

Stdlib only, plus pyserial for serial targets."""

__version__ = "1"
