//! Declares the `fuzzing` cfg that `cargo fuzz` sets, so ordinary builds do not warn about it
//! (the crate takes the workspace lints, which cannot be extended with a check-cfg here).

fn main() {
    println!("cargo::rustc-check-cfg=cfg(fuzzing)");
}
