//! The integration tests of `gcl-model`, one test binary (issue 41): each former test file is
//! a module here (`cargo test -p gcl-model --test it -- device_props::` runs one of them), with
//! the shared driver in `support`. Insta snapshots are under `snapshots/`, named by module
//! path (`it__snapshots__NAME.snap`).

mod support;

mod device;
mod device_props;
mod grammar_props;
mod grammar_table;
mod lfdp;
mod motion_times;
mod roles;
mod sessions;
mod snapshots;
mod spec_agreement;
mod state_machine;
mod time_jumps;
