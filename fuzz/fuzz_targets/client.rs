//! cargo-fuzz target `client`, a thin wrapper over [`gcl_fuzz::client`].
//!
//! Built by `cargo fuzz` (with `--cfg fuzzing`) it is a libFuzzer target. In an ordinary
//! build it replays inputs: `cargo run -p gcl-fuzz --bin client -- FILE_OR_DIR...` runs the
//! entry point on each file and panics, with the finding's message, on the first that fails.
#![cfg_attr(fuzzing, no_main)]

#[cfg(fuzzing)]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    gcl_fuzz::client(data);
});

#[cfg(not(fuzzing))]
fn main() -> std::process::ExitCode {
    gcl_fuzz::replay::main("client")
}
