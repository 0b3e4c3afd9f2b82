//! The integration tests of `gcl-harness`, one test binary (issue 41): each former test file
//! is a module here, so a fresh clone links the harness into one test binary instead of one per
//! file. A test's full name starts with its module (`fuzz_device::...`): `cargo test -p
//! gcl-harness --test it -- fuzz_device::` runs one former file's tests, and `.ci/run`'s lanes
//! are such filters. The shared helpers (`bounded`, `deps`, `sim_support`) are modules too;
//! data files the tests read stay beside this folder, in `harness/tests/`.

mod bounded;
mod deps;
mod sim_support;

mod adversarial;
mod check_host_serve;
mod client_props;
mod conform_mutants;
mod conform_necessity;
mod conform_runner;
mod conform_target_ends;
mod conform_triage;
mod deps_check;
mod docs;
mod fuzz_device;
mod fuzz_device_baseline_hand;
mod fuzz_device_rate;
mod fuzz_host;
mod fuzz_host_coverage;
mod fuzz_merge;
mod hardening;
mod host_compat;
mod host_verdicts;
mod hostile_output;
mod readme_example;
mod readme_promises;
mod replay_bounds;
mod report_pages;
mod report_schema;
mod sim_cli;
mod sim_examples;
mod sim_port;
mod sim_pyserial;
mod sim_robustness;
mod suite_banner;
mod suite_decisions;
mod suite_effects;
mod suite_fresh;
mod suite_relations;
mod suite_sim;
mod suite_wire_promises;
mod tidy;
mod transcript_cli;
mod transcript_mutants;
mod vectors_fresh;
mod vectors_python;
