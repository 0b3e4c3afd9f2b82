//! Every sentence of README.md and the guides (`docs/src/`) that promises something a user can
//! observe (an exit code, a message, a file written, a default, a limit) is held by a test (issue 21 item 2: "Sentences
//! that promise behaviour get a test too"). `PROMISES` pairs a verbatim fragment of each such
//! sentence with the tests that hold it; `every_promise_is_quoted_as_written_and_held_by_a_test`
//! fails when a sentence is reworded (its fragment is no longer in README.md or a guide) or a
//! test is renamed or deleted, so the table cannot drift from either. The documents' commands
//! are `docs.rs`'s; descriptions that promise nothing checkable are not listed.
//! The other tests here hold the promises no test held before.

use crate::sim_support;

use std::path::{Path, PathBuf};
use std::process::Command;

use gcl_harness::fuzz::device::{Budget, FuzzError, FuzzOptions, check_real_time, run};
use gcl_host::target::Target;
use gcl_model::Profile;
use sim_support::{GCL, SimProcess, Transport};

const SELF: &str = "harness/tests/it/readme_promises.rs";

/// A README fragment (whitespace as in the README or collapsed: lines wrap) and the tests that
/// hold it, each `FILE::NAME` from the repository root (`.ci/run::LINE` for a check of
/// `.ci/run`, named by the line it prints when it holds, where no `cargo test` can: the C++
/// example needs CMake and a C++ compiler).
const PROMISES: &[(&str, &[&str])] = &[
    // The documents themselves.
    (
        "Every command in this README, in the guides and in `gcl --help` is run by the tests (`harness/tests/it/docs.rs`): as written, or by a stand-in that says what stands for what",
        &[
            "harness/tests/it/docs.rs::every_documented_command_is_run",
            "harness/tests/it/docs.rs::documented_commands_run_as_written_or_by_their_stand_ins",
            "harness/tests/it/docs.rs::the_check_catches_a_command_nobody_runs",
        ],
    ),
    (
        "so does a relative link of README.md or a chapter to a file that is not there or to an anchor no heading has",
        &[
            "harness/tests/it/docs.rs::every_link_of_the_documents_leads_somewhere",
            "harness/tests/it/docs.rs::the_link_check_catches_a_link_to_nowhere",
        ],
    ),
    // The two commands.
    (
        "`cargo test --workspace -- --include-ignored` runs them too, as `.ci/run` does.",
        &["harness/tests/it/tidy.rs::every_test_left_out_of_the_default_run_is_run_by_ci"],
    ),
    (
        "they use `GCL_PYTHON`, else a virtual environment at `target/pyvenv`, else",
        &["harness/tests/it/deps_check.rs::python_is_found_the_same_way_by_every_test"],
    ),
    (
        "they skip with a `SKIPPED <test>: ...` line that `cargo test` shows",
        &["harness/tests/it/deps_check.rs::a_missing_tool_is_a_visible_skip_here_and_a_failure_under_ci"],
    ),
    (
        "after each test binary's result a line says how many of its tests did not run though libtest counts them as passed, with the run's total so far and the command that fixes it",
        &["harness/tests/it/deps_check.rs::a_missing_tool_is_a_visible_skip_here_and_a_failure_under_ci"],
    ),
    (
        "under `CI=true` a missing tool fails the test instead",
        &["harness/tests/it/deps_check.rs::a_missing_tool_is_a_visible_skip_here_and_a_failure_under_ci"],
    ),
    // Objects in the fingers' way.
    (
        "runs on the in-process `sim`, which places the object for that case alone. On any other hand it is SKIP, with a reason that says how to run it",
        &[
            "harness/tests/it/conform_mutants.rs::a_case_that_needs_an_object_runs_where_it_is_placed_or_declared_and_is_skip_elsewhere",
        ],
    ),
    (
        "`gcl replay` and the Python runner take `--fixture object` too",
        &[
            "harness/tests/it/transcript_cli.rs::a_setup_is_recorded_and_replayed_with_its_object",
            "vectors/python/tests/test_runner.py::test_a_setup_is_skip_unless_declared_in_place",
        ],
    ),
    (
        "Declared but missing, the case fails.",
        &[
            "harness/tests/it/conform_mutants.rs::a_case_that_needs_an_object_runs_where_it_is_placed_or_declared_and_is_skip_elsewhere",
            "harness/tests/it/transcript_cli.rs::a_setup_is_recorded_and_replayed_with_its_object",
        ],
    ),
    // Who it is for.
    ("`--fault NAME` makes the hand misbehave on purpose", &["harness/tests/it/sim_cli.rs::faults_reach_the_hand"]),
    (
        "real time, every byte paced at the hand's BAUD (9600 at the factory) in both directions",
        &[
            "line/src/sim/engine.rs::pacing_offers_a_byte_once_its_wire_time_has_passed",
            "line/src/sim/engine.rs::host_bytes_reach_the_model_at_their_wire_time",
            "line/src/sim/engine.rs::real_time_waits_for_the_clock",
        ],
    ),
    (
        "`PSET BAUD`/`FSET BAUD` changing the pace after their answer",
        &[
            "line/src/sim/engine.rs::the_hands_baud_sets_the_pace_after_the_answer_that_sets_it",
            "harness/tests/it/host_compat.rs::a_library_that_changes_the_baud_rate_reopens_to_one_fresh_prompt",
        ],
    ),
    (
        "what the host left unread is discarded on close",
        &[
            "harness/tests/it/sim_port.rs::an_answer_left_unread_is_gone_after_a_close_and_reopen",
            "line/src/sim/engine.rs::output_without_a_listener_is_lost_and_unread_output_is_discarded",
        ],
    ),
    (
        "a late host sees no power-up banner",
        &["harness/tests/it/sim_port.rs::a_host_that_opens_the_pty_after_start_up_sees_no_banner_but_sees_a_reset"],
    ),
    (
        "Nothing is dropped while a host reads slowly: the simulator stops reading it instead.",
        &[
            "line/src/sim/engine.rs::a_host_that_does_not_read_is_not_read_and_loses_nothing",
            "harness/tests/it/sim_port.rs::ten_thousand_pipelined_commands_lose_no_byte_over_the_pty_and_tcp",
        ],
    ),
    (
        "without the harness's suite, reports or CLI",
        &["harness/tests/it/tidy.rs::the_host_library_needs_nothing_of_the_harness"],
    ),
    ("reads, prints and matches transcripts with no I/O", &["harness/tests/it/tidy.rs::pure_crates_do_no_io"]),
    // A tour of the CLI.
    (
        "`check` says when either is stale",
        &[
            "harness/tests/it/suite_fresh.rs::check_reports_stale_missing_and_extra_files_and_regenerate_fixes_them",
            "harness/tests/it/vectors_fresh.rs::check_reports_stale_missing_and_extra_files_and_regenerate_fixes_them",
        ],
    ),
    (
        "`gcl suite list` shows the catalogue built into `gcl` from any directory",
        &[
            "harness/tests/it/hardening.rs::suite_commands_outside_the_repository_read_the_built_in_catalogue_or_say_what_is_missing",
        ],
    ),
    (
        "(found in the current directory or above it, or given with `--dir`)",
        &[
            "harness/tests/it/hardening.rs::suite_commands_outside_the_repository_read_the_built_in_catalogue_or_say_what_is_missing",
        ],
    ),
    (
        "with known failures kept as data (XFAIL; XPASS when they start passing)",
        &["harness/tests/it/conform_mutants.rs::known_failures_turn_into_xfail_and_stale_entries_into_xpass"],
    ),
    (
        "a one-line probe says so and the abort-timing",
        &[
            "harness/tests/it/conform_target_ends.rs::a_hand_whose_motions_end_at_once_skips_the_abort_timing_cases_and_says_why",
        ],
    ),
    (
        "drop exactly the cases resting on it",
        &["harness/tests/it/conform_mutants.rs::skip_decision_drops_exactly_the_cases_resting_on_it"],
    ),
    (
        "(each case lists its decisions in index.json and the reports",
        &["harness/tests/it/suite_decisions.rs::index_json_lists_every_case_decisions"],
    ),
    (
        "`gcl sim --pty` and `--tcp` run in real time by default",
        &["harness/tests/it/readme_promises.rs::pty_and_tcp_sims_run_in_real_time_and_stdio_in_fast_time_by_default"],
    ),
    (
        "(the default of `--stdio`, and an opt-in speed-up elsewhere)",
        &["harness/tests/it/readme_promises.rs::pty_and_tcp_sims_run_in_real_time_and_stdio_in_fast_time_by_default"],
    ),
    (
        "it counts only the cases that ran to their end or to a mismatch",
        &["harness/tests/it/hardening.rs::absurd_bauds_are_refused_and_the_bound_counts_only_pass_and_fail"],
    ),
    (
        "a case that homes the fingers after one that closed them counts the move back",
        &["conformance/src/conform.rs::the_wire_bound_counts_the_echo_once_and_where_the_case_before_left_the_fingers"],
    ),
    // Certificates, inputs, outputs.
    (
        "`gcl certify` refuses `--skip`, `--only`, `--fault` and `--suite` unless given `--partial`",
        &["harness/tests/it/hardening.rs::certify_refuses_selections_unless_partial_and_says_partial"],
    ),
    (
        "`--known-failures` also needs `--partial`",
        &["harness/tests/it/adversarial.rs::known_failures_narrow_a_certificate_and_verify_needs_a_key"],
    ),
    (
        "and the certificate lists the excused cases",
        &["harness/tests/it/adversarial.rs::known_failures_narrow_a_certificate_and_verify_needs_a_key"],
    ),
    (
        "A run where nothing ran is never a PASS.",
        &["harness/tests/it/hardening.rs::only_matching_nothing_is_a_usage_error_and_a_run_of_nothing_is_no_pass"],
    ),
    (
        "says `AUTHENTICITY NOT CHECKED`",
        &["harness/tests/it/adversarial.rs::known_failures_narrow_a_certificate_and_verify_needs_a_key"],
    ),
    (
        "exits 1 unless `--allow-unverified` is given",
        &["harness/tests/it/adversarial.rs::known_failures_narrow_a_certificate_and_verify_needs_a_key"],
    ),
    (
        "Every option that changed what ran is in the certificate and in every report.",
        &["harness/tests/it/hardening.rs::certify_refuses_selections_unless_partial_and_says_partial"],
    ),
    (
        "`--only` matching no case is a usage error",
        &["harness/tests/it/hardening.rs::only_matching_nothing_is_a_usage_error_and_a_run_of_nothing_is_no_pass"],
    ),
    (
        "a known-failures entry matching no case is warned about and recorded",
        &["harness/tests/it/hardening.rs::a_known_failure_that_matches_nothing_is_reported_and_recorded"],
    ),
    (
        "a port another run holds is an error (exit 2)",
        &["harness/tests/it/hardening.rs::a_busy_serial_port_is_one_clear_line_and_exit_2"],
    ),
    (
        "a FIFO or `/dev/zero` is refused at once",
        &[
            "harness/tests/it/hardening.rs::no_file_input_is_read_whole_or_waited_on",
            "host/src/files.rs::refuses_what_is_not_a_regular_file_without_blocking",
            "harness/tests/it/adversarial.rs::checks_refuse_fifos_devices_and_huge_files",
        ],
    ),
    (
        "(4 MiB; 64 KiB for keys)",
        &["harness/tests/it/readme_promises.rs::inputs_are_refused_one_byte_past_4_mib_and_keys_one_byte_past_64_kib"],
    ),
    (
        "A profile expands to at most 256 files and 16 MiB of text",
        &["harness/tests/it/adversarial.rs::an_include_bomb_is_refused_within_the_memory_limit"],
    ),
    (
        "a symbolic link at an output's name is replaced, never written through",
        &[
            "harness/tests/it/adversarial.rs::regenerate_never_writes_through_a_symlink",
            "harness/tests/it/adversarial.rs::outputs_never_write_through_or_remove_a_users_link",
            "line/src/outputs.rs::writes_replace_files_and_links_never_their_targets",
        ],
    ),
    (
        "Output files are always new files renamed into place",
        &["harness/tests/it/hardening.rs::record_replaces_its_output_atomically"],
    ),
    (
        "a write that fails (a full disk) leaves no temporary and names its file",
        &["harness/tests/it/adversarial.rs::a_full_disk_leaves_no_temporaries_and_no_bundle_that_looks_valid"],
    ),
    (
        "a second run there is refused (exit 2)",
        &["harness/tests/it/adversarial.rs::fuzz_device_holds_its_folders_and_reports_on_sigterm"],
    ),
    ("(`NAME-2.gcl` instead)", &["harness/tests/it/adversarial.rs::a_finding_is_never_replaced_by_another_bugs"]),
    ("Every duration argument is bounded", &["harness/tests/it/adversarial.rs::absurd_durations_are_refused_at_once"]),
    // How conform reaches a verdict.
    (
        "name gross framing faults in one line on stderr as the run starts and at the top of every report",
        &[
            "harness/tests/it/conform_runner.rs::the_pre_flight_names_a_broken_prompt_first_in_the_console_and_in_every_report",
        ],
    ),
    (
        "× 2 + 50 ms (`--margin MS`), at least 500 ms on serial and 200 ms on TCP targets",
        &["conformance/src/deadline.rs::deadlines_follow_the_model_with_a_margin_and_a_floor"],
    ),
    (
        "reads or writes its EEPROM, keeps at least its golden `within`",
        &["conformance/src/deadline.rs::eeprom_steps_keep_their_golden_deadline"],
    ),
    (
        "one that stopped short (a prompt without its space) is judged at once",
        &["line/src/replay.rs::a_short_answer_times_out_at_the_step_deadline"],
    ),
    (
        "fails the case as a flood",
        &[
            "harness/tests/it/conform_runner.rs::a_hand_that_floods_costs_bounded_memory_and_reports_and_ends_the_run",
            "line/src/replay.rs::a_hand_that_floods_an_open_elision_fails_with_a_bounded_prefix",
        ],
    ),
    (
        "`--fail-fast` and `--max-failures N` stop the run (exit 1)",
        &["harness/tests/it/conform_runner.rs::fail_fast_and_max_failures_stop_the_run_and_list_the_rest_as_not_run"],
    ),
    (
        "the rest of the cases are not run and the run exits 2",
        &[
            "harness/tests/it/conform_runner.rs::a_hand_that_stops_answering_ends_the_run_early_with_exit_2",
            "harness/tests/it/conform_mutants.rs::a_silent_hand_is_an_infrastructure_error_not_a_hang",
        ],
    ),
    (
        "a hand that answers only the first is not alive",
        &["harness/tests/it/adversarial.rs::a_hand_answering_only_the_probe_ends_the_run"],
    ),
    (
        "(\"the hand floods\")",
        &[
            "harness/tests/it/conform_runner.rs::a_hand_that_floods_costs_bounded_memory_and_reports_and_ends_the_run",
            "harness/tests/it/adversarial.rs::the_liveness_message_says_what_happened",
        ],
    ),
    (
        "Cases that did not run are SKIP, \"not run: ...\"",
        &["harness/tests/it/conform_runner.rs::fail_fast_and_max_failures_stop_the_run_and_list_the_rest_as_not_run"],
    ),
    (
        "lead with the failures grouped by where they part from their goldens",
        &[
            "harness/tests/it/conform_triage.rs::fget_reversed_leads_with_one_group_of_reordered_fget_answers",
            "harness/tests/it/conform_triage.rs::the_largest_group_of_failures_names_the_clause_each_fault_breaks",
        ],
    ),
    (
        "A target that vanishes is reopened, drained and probed before the next case",
        &[
            "harness/tests/it/conform_runner.rs::a_hand_that_restarts_is_drained_and_probed_before_the_next_case",
            "harness/tests/it/conform_target_ends.rs::a_hand_that_vanishes_mid_run_is_an_error_not_a_clause",
        ],
    ),
    (
        "a line as the run starts, one every 10 s",
        &[
            "harness/tests/it/report_pages.rs::a_ci_log_gets_progress_lines_with_counts_and_the_end",
            "harness/src/cli/progress.rs::a_plain_line_is_due_every_10_s",
        ],
    ),
    // Reading a report.
    (
        "is one self-contained file, no script, no network",
        &[
            "harness/tests/it/report_pages.rs::the_certify_and_passing_conform_pages_parse",
            "harness/tests/it/report_pages.rs::host_pages_have_their_own_titles_tables_and_replay_commands",
        ],
    ),
    (
        "the exact command that runs it again",
        &[
            "harness/tests/it/report_pages.rs::the_fuzz_device_page_indexes_findings_with_replay_commands_and_plots_coverage",
            "harness/tests/it/report_pages.rs::host_pages_have_their_own_titles_tables_and_replay_commands",
        ],
    ),
    (
        "`5000: in range, the bytes are swapped`",
        &["harness/tests/it/report_pages.rs::realtime_failures_are_decoded_field_by_field_and_plotted"],
    ),
    (
        "Every RealTime case, passing or failing, is plotted block by block",
        &["harness/tests/it/report_pages.rs::every_realtime_case_is_plotted_passing_ones_included"],
    ),
    (
        "shows each motor's window against where it was",
        &["harness/tests/it/report_pages.rs::a_motion_effect_failure_shows_the_window_it_missed"],
    ),
    (
        "plots the seed's RealTime example program",
        &["harness/tests/it/report_pages.rs::the_realtime_example_program_is_plotted_block_by_block_against_the_model"],
    ),
    (
        "from new ones (JUnit skips them)",
        &["harness/tests/it/fuzz_device.rs::a_baseline_keeps_known_findings_apart_from_new_ones"],
    ),
    (
        "a `certify` page links every case to its transcript in the bundle",
        &["harness/tests/it/report_pages.rs::the_certify_and_passing_conform_pages_parse"],
    ),
    (
        "A JUnit failure's message is the one-line diff",
        &["harness/tests/it/conform_runner.rs::a_failures_diff_numbers_its_step_as_its_message_does"],
    ),
    (
        "Exit codes: 0 success, 1 conformance failures or mismatches, 2 usage or infrastructure",
        &[
            "harness/tests/it/transcript_cli.rs::replay_exits_0_on_a_match",
            "harness/tests/it/transcript_cli.rs::replay_exits_1_and_shows_the_parting_byte_on_a_mismatch",
            "harness/tests/it/transcript_cli.rs::replay_exits_2_on_a_file_that_does_not_parse",
            "harness/tests/it/conform_mutants.rs::every_mutant_fails_gcl_conform_over_exec",
        ],
    ),
    (
        "a hand that does not answer the liveness probe is one",
        &["harness/tests/it/conform_mutants.rs::a_silent_hand_is_an_infrastructure_error_not_a_hang"],
    ),
    // Fuzzing a hand.
    (
        "minimized by dropping and simplifying actions while the signature holds",
        &["harness/tests/it/fuzz_device.rs::every_fault_is_found_minimized_and_replays_or_is_listed_with_a_reason"],
    ),
    (
        "`prefix 123+4`, a parameter set without effect, `MCV set without effect`",
        &["harness/tests/it/fuzz_device.rs::a_bug_read_back_by_many_commands_is_one_finding_named_by_its_explanation"],
    ),
    (
        "a refused set applied in part or RESET keeping the values set; in process, a model holding the hypothesis must answer the failing case byte for byte as the hand did",
        &["harness/tests/it/fuzz_device.rs::a_bug_the_rewrite_cannot_follow_is_named_by_a_model_that_has_it"],
    ),
    (
        "outside it the case built anew on that model must expect what the hand answered",
        &[
            "harness/tests/it/fuzz_device_baseline_hand.rs::a_hand_outside_this_process_is_named_by_a_model_that_behaves_as_it_does",
        ],
    ),
    (
        "the hand must answer that case so when it is replayed",
        &[
            "harness/tests/it/fuzz_device_baseline_hand.rs::a_known_deviation_on_a_field_does_not_hide_another_bug_on_it",
            "harness/tests/it/fuzz_device.rs::a_realtime_flag_without_effect_over_a_pty_is_named_by_the_flag",
        ],
    ),
    (
        "corpora of several workers, machines or runs merge by copying",
        &["harness/tests/it/fuzz_device.rs::the_unmutated_sim_yields_no_findings_and_workers_share_one_corpus"],
    ),
    (
        "`junit.xml` (one testcase per distinct finding) and `fuzz-device.html`",
        &[
            "harness/tests/it/fuzz_device.rs::the_report_validates_against_its_schema_with_one_junit_testcase_per_finding",
        ],
    ),
    (
        "`conform`: 0 no finding, 1 findings, 2 usage or infrastructure",
        &["harness/tests/it/fuzz_device.rs::the_cli_exits_1_on_findings_0_without_and_2_on_a_bad_target"],
    ),
    (
        "one that does not answer ends the campaign at once (exit 2)",
        &["harness/tests/it/adversarial.rs::fuzz_device_ends_early_on_a_dead_hand"],
    ),
    (
        "end the campaign with its findings and reports written",
        &["harness/tests/it/adversarial.rs::fuzz_device_holds_its_folders_and_reports_on_sigterm"],
    ),
    (
        "minimization stops at `--duration`",
        &["fuzzers/src/fuzz/device/mod.rs::minimization_stops_at_the_campaigns_duration"],
    ),
    (
        "a listed case that fails otherwise is a FAIL, `fails otherwise than its known failure`",
        &["harness/tests/it/hardening.rs::a_run_writes_the_known_failures_its_next_run_takes"],
    ),
    (
        "A status finding's transcript names every command its bits showed on in its campaign",
        &["harness/tests/it/fuzz_device.rs::a_hand_against_its_own_findings_has_nothing_new"],
    ),
    (
        "there they are known only on the command the baseline had them on",
        &["fuzzers/src/fuzz/device/mod.rs::a_status_the_baseline_has_on_another_command_is_new"],
    ),
    (
        "so a flood is one `unterminated line` violation whether it ends or the budget stops it",
        &["harness/tests/it/host_verdicts.rs::a_flood_is_one_violation_whether_it_ends_or_the_budget_stops_it"],
    ),
    (
        "but it never exited by itself: one finding, `over budget: still sending when the run budget ended`, whatever it sent (`check-host` fails `host-exits-cleanly`)",
        &["harness/tests/it/host_verdicts.rs::a_host_killed_at_the_run_budget_did_not_exit_cleanly"],
    ),
    (
        "A session of `check-host --serve` has no host process, so `host-exits-cleanly` is \"not exercised\" there, and a session whose client exercised no clause (it sent only ^C) is an ERROR, exit 2.",
        &["harness/tests/it/check_host_serve.rs::a_served_session_invents_no_exit"],
    ),
    (
        "what else that second run shows (a line it leaves unended when it exits, a crash) is a finding like any run's",
        &["harness/tests/it/host_verdicts.rs::a_violation_of_a_hangs_second_run_is_a_finding"],
    ),
    (
        "killed as hung too, and that violation stands whatever the hang's confirmation says",
        &["harness/tests/it/host_verdicts.rs::a_violation_stands_whatever_becomes_of_its_hang"],
    ),
    (
        "Against such a hand the strain at rest and what VERS says are the hand's own",
        &[
            "conformance/src/actions/case.rs::a_hand_outside_this_process_says_its_own_version_and_reads_its_own_strain_at_rest",
        ],
    ),
    (
        "not on how an earlier answer that passed is written",
        &[
            "fuzzers/src/fuzz/device/mod.rs::a_bug_after_an_answer_resting_on_an_open_format_is_must",
            "fuzzers/src/fuzz/device/mod.rs::a_finding_rests_on_its_failing_steps_decisions_and_earlier_state_decisions",
        ],
    ),
    (
        "A case rests on the model's joint stops when the model answers it otherwise with the stops taken away",
        &[
            "conformance/src/actions/case.rs::a_case_whose_answers_rest_on_the_joint_stops_names_the_motion_decision",
            "fuzzers/src/fuzz/device/mod.rs::a_finding_past_the_joint_stop_is_info",
        ],
    ),
    (
        "`--write-budget N` caps EEPROM writes (restores included) over the whole run",
        &["harness/tests/it/readme_promises.rs::the_write_budget_caps_a_campaigns_eeprom_writes"],
    ),
    (
        "on a `serial:` target no case sets the hand's line rate",
        &[
            "conformance/src/actions/mod.rs::a_guarded_line_rate_is_never_set_to_another_rate",
            "conformance/src/actions/mod.rs::what_changes_the_rate_is_read_as_a_hand_would",
            "harness/tests/it/fuzz_device.rs::a_serial_campaign_leaves_the_hand_at_its_starting_rate",
        ],
    ),
    (
        "After a serial campaign the port is opened again at the rate it started at and the hand probed",
        &["harness/tests/it/fuzz_device.rs::a_serial_campaign_leaves_the_hand_at_its_starting_rate"],
    ),
    (
        "every replay must fail with the same signature",
        &[
            "harness/tests/it/fuzz_device.rs::a_failure_that_does_not_reproduce_on_a_fresh_connection_is_a_note_not_a_finding",
        ],
    ),
    (
        "is told so in the very first line",
        &[
            "harness/tests/it/conform_runner.rs::a_hand_of_another_firmware_is_named_first",
            "harness/tests/it/fuzz_device.rs::a_campaign_on_a_hand_of_another_firmware_says_so_first",
            "conformance/src/preflight.rs::a_hand_of_another_firmware_is_named_from_its_vers_or_its_banner",
        ],
    ),
    (
        "no FSAVE or PSAVE at all unless `--write-budget N` allows N writes",
        &["harness/tests/it/readme_promises.rs::serial_targets_are_fuzzed_without_eeprom_writes_and_by_one_worker"],
    ),
    (
        "a target that took under a quarter of it is refused at once (exit 2, naming `--no abort-timing`)",
        &[
            "harness/tests/it/fuzz_device.rs::a_sim_in_fast_time_is_refused_unless_abort_timing_is_off",
            "harness/tests/it/fuzz_device.rs::a_sim_in_real_time_passes_the_real_time_check",
        ],
    ),
    (
        "are judged again by a replay with the full quiet drain",
        &[
            "harness/tests/it/fuzz_device.rs::bytes_after_a_quick_case_send_it_to_a_thorough_run_that_reports_it",
            "harness/tests/it/fuzz_device.rs::a_faulty_sim_over_a_pty_is_found_and_the_transcript_replays",
        ],
    ),
    (
        "mid-motion are judged only by their ranges (the hand's clock and the model's part there)",
        &[
            "harness/tests/it/readme_promises.rs::positions_read_after_a_mid_motion_abort_are_judged_by_their_range_outside_this_process",
        ],
    ),
    // Fuzzing a host library in CI.
    (
        "schema `reports/fuzz-host.schema.json`",
        &["harness/tests/it/report_schema.rs::fuzz_host_campaigns_validate_against_their_schema"],
    ),
    (
        "exit 0 with no finding, 1 with findings, 2 on a usage or infrastructure error",
        &[
            "harness/tests/it/fuzz_host.rs::the_cli_writes_minimized_bundles_that_replay_and_junit_reports",
            "harness/tests/it/fuzz_host.rs::check_host_cli_compares_with_a_golden_and_exits_like_conform",
        ],
    ),
    ("`--ok-exit-codes`, default `0,1`", &["harness/tests/it/adversarial.rs::ok_exit_codes_are_exit_codes"]),
    (
        "is a JUnit failure and a bundle folder",
        &["harness/tests/it/fuzz_host.rs::the_cli_writes_minimized_bundles_that_replay_and_junit_reports"],
    ),
    (
        "`gcl fuzz host --replay BUNDLE -- COMMAND` runs one again",
        &["harness/tests/it/fuzz_host.rs::the_cli_writes_minimized_bundles_that_replay_and_junit_reports"],
    ),
    (
        "fails the `host-golden` case when the host's bytes change",
        &["harness/tests/it/fuzz_host.rs::check_host_cli_compares_with_a_golden_and_exits_like_conform"],
    ),
    (
        "so a library that gives up after 10 or 15 s has no hang finding",
        &["harness/tests/it/host_verdicts.rs::a_host_that_waits_out_its_own_timeout_is_not_hung"],
    ),
    (
        "A host that never gives up in 30 s is measured as having no timeout",
        &["harness/tests/it/readme_promises.rs::a_host_that_never_gives_up_is_measured_as_having_no_timeout"],
    ),
    (
        "`gcl check-host`, whose hand never goes silent, calls a hang after 20 s by default",
        &["harness/tests/it/readme_promises.rs::check_host_calls_a_hang_after_20_s_unless_told_otherwise"],
    ),
    (
        "`hang in host.py:read_prompt`",
        &[
            "harness/tests/it/host_verdicts.rs::one_wait_without_a_deadline_is_one_hang_named_by_its_code",
            "fuzzers/src/fuzz/host/detect.rs::a_python_host_blocked_in_pyserial_is_signed_by_the_call_in_its_program",
        ],
    ),
    (
        "so a port without one is one finding whichever of the host's functions reads from it",
        &["harness/tests/it/host_verdicts.rs::one_port_without_a_timeout_is_one_hang_whichever_function_reads_it"],
    ),
    (
        "The hang clock runs only while the host holds the port open",
        &["harness/tests/it/host_verdicts.rs::a_host_slow_to_open_its_port_is_not_hung"],
    ),
    (
        "`python port hang-up (pyserial) not handled`",
        &["fuzzers/src/fuzz/host/detect.rs::a_hang_up_is_one_signature_whatever_pyserial_raised_it_as"],
    ),
    (
        "`exit-code: not an accepted code, in supervisory mode`",
        &[
            "harness/tests/it/host_verdicts.rs::one_exit_habit_is_one_finding_whatever_the_code",
            "fuzzers/src/fuzz/host/mod.rs::an_unexpected_exit_is_signed_by_its_class_and_mode_not_its_code",
        ],
    ),
    (
        "Sanitizers write their reports to a file of the run's own",
        &["harness/tests/it/host_verdicts.rs::sanitizer_reports_are_read_from_a_log_file_per_run"],
    ),
    (
        "a FIFO or a symbolic link in it is named, never opened or followed",
        &[
            "harness/tests/it/host_verdicts.rs::what_a_host_leaves_in_its_log_folder_is_read_as_its_data_and_capped",
            "fuzzers/src/fuzz/host/session.rs::a_run_folders_logs_are_read_as_the_hosts_data_within_their_room",
        ],
    ),
    (
        "within its 256 KiB (stderr and the logs each have half",
        &[
            "harness/tests/it/host_verdicts.rs::what_a_host_leaves_in_its_log_folder_is_read_as_its_data_and_capped",
            "fuzzers/src/fuzz/host/session.rs::stderr_and_what_follows_it_are_kept_within_the_cap",
        ],
    ),
    (
        "named in a `leftover` finding, signed by its command line",
        &["harness/tests/it/host_verdicts.rs::a_process_left_behind_is_killed_and_named_within_the_budget"],
    ),
    (
        "is found by the `GCL_HOST_RUN` mark in its environment, killed and named the same way",
        &["harness/tests/it/host_verdicts.rs::a_daemon_left_under_the_write_watch_is_killed_and_named"],
    ),
    (
        "a host that installs a seccomp listener of its own gets EBUSY",
        &["harness/tests/it/host_verdicts.rs::a_hosts_own_seccomp_listener_is_refused_over_tcp_only"],
    ),
    (
        "A crash's signature is its kind and where it was raised, never the callers that led there",
        &[
            "fuzzers/src/fuzz/host/detect.rs::one_exception_from_one_place_is_one_signature_whatever_the_caller",
            "fuzzers/src/fuzz/host/detect.rs::asan_reports_are_signed_by_the_hosts_frame_nearest_the_bad_access",
        ],
    ),
    (
        "A host blocked in its write while the hand holds an answer back waits for the hand",
        &["harness/tests/it/host_verdicts.rs::a_host_blocked_in_its_write_while_the_hand_holds_an_answer_is_not_hung"],
    ),
    (
        "What the host writes is kept up to 1 MiB each way",
        &["harness/tests/it/host_verdicts.rs::what_a_flooding_host_writes_is_capped"],
    ),
    (
        "is an INFO note in the report and in `fuzz.json`'s `notes`",
        &["harness/tests/it/host_verdicts.rs::a_reaction_to_the_hands_misbehaviour_is_a_note_not_a_finding"],
    ),
    (
        "`restart` puts the hand back in supervisory mode, and the checker follows",
        &["harness/tests/it/host_verdicts.rs::the_checker_follows_the_hand_through_a_restart"],
    ),
    (
        "is a resync, never \"CR CR\"",
        &["harness/tests/it/host_verdicts.rs::a_host_that_reconnects_and_resyncs_with_one_cr_passes"],
    ),
    (
        "writes the run's failing cases as such a list",
        &["harness/tests/it/hardening.rs::a_run_writes_the_known_failures_its_next_run_takes"],
    ),
    (
        "is flagged at any speed, paced or not, fast or real time",
        &[
            "harness/tests/it/host_verdicts.rs::a_host_that_pipelines_is_flagged_at_any_speed",
            "harness/tests/it/host_verdicts.rs::a_host_that_pipelines_after_the_answer_came_is_flagged_over_pty_and_tcp",
            "harness/tests/it/fuzz_host.rs::waiting_for_the_answer_is_judged_when_its_last_byte_is_delivered",
        ],
    ),
    (
        "A write made before the host had read all the output sent to it is flagged however fast the host reads afterwards, at any speed, fast or real time; a host that had read everything is never flagged",
        &["harness/tests/it/host_verdicts.rs::a_host_that_pipelines_after_the_answer_came_is_flagged_over_pty_and_tcp"],
    ),
    (
        "is a `silent-wrong-value` finding",
        &["harness/tests/it/host_verdicts.rs::a_host_that_trusts_a_short_block_gives_a_silent_wrong_value"],
    ),
    (
        "is a hang for a host that waits without a deadline",
        &["harness/tests/it/fuzz_host.rs::silence_hangs_a_host_without_a_deadline_only"],
    ),
    (
        "A campaign is reproducible run for run for the same `--seed` and `--jobs`",
        &["harness/tests/it/fuzz_host.rs::parallel_campaigns_are_reproducible_run_for_run"],
    ),
    (
        "has fourteen small buggy hosts",
        &[
            "harness/tests/it/readme_promises.rs::there_are_fourteen_host_mutants",
            "harness/tests/it/fuzz_host.rs::python_mutants_are_found_with_the_right_kind",
            "harness/tests/it/fuzz_host.rs::c_mutants_are_found_with_the_right_kind",
            "harness/tests/it/fuzz_host.rs::a_rust_mutant_panic_is_found",
        ],
    ),
    (
        "The hand runs in fast time, unpaced, by default; `--time real` gives a hand paced at its BAUD",
        &[
            "harness/tests/it/readme_promises.rs::the_host_fuzzers_hand_is_unpaced_by_default_and_paced_at_its_baud_in_real_time",
            "line/src/sim/engine.rs::pacing_offers_a_byte_once_its_wire_time_has_passed",
            "line/src/sim/engine.rs::the_hands_baud_sets_the_pace_after_the_answer_that_sets_it",
        ],
    ),
    // Host libraries in Python, C++ and CI.
    (
        "name, version and metadata from `harness/Cargo.toml`",
        &["python/tests/test_wheel.py::test_name_version_and_metadata_come_from_cargo_toml"],
    ),
    (
        "When the test body ends the hand grades everything the host code sent",
        &[
            "python/tests/test_wheel.py::test_a_hand_grades_its_session",
            "python/tests/test_wheel.py::test_the_lf_bug_fails_every_test_naming_the_clause",
        ],
    ),
    (
        "`gcl_misbehaving_hand` runs the test once per seeded misbehaviour schedule",
        &[
            "python/tests/test_wheel.py::test_a_misbehaving_hand_plays_the_fuzzers_schedule",
            "harness/tests/it/check_host_serve.rs::a_served_hand_plays_a_schedule_of_the_fuzzer",
        ],
    ),
    (
        "`schedules` that is not a whole number from 1 to 10000, a `seed` that `--seed` does not take, or a `timeout` of 0 or less is an error naming it",
        &["python/tests/test_plugin_limits.py::test_values_out_of_range_are_refused_by_name"],
    ),
    (
        "A test that calls `pytest.skip()` or `pytest.xfail()` is reported skipped or xfailed, ungraded",
        &["python/tests/test_plugin_limits.py::test_skip_and_xfail_inside_a_gcl_hand_test_are_reported_as_such"],
    ),
    (
        "Ctrl-C stops the session as pytest stops it, never as a failed test",
        &["python/tests/test_plugin_limits.py::test_ctrl_c_stops_the_session_and_fails_no_test"],
    ),
    (
        "so no `gcl-hand-*` folder is left, and pytest then ends by SIGTERM",
        &["python/tests/test_plugin_limits.py::test_sigterm_leaves_no_hand_folder_and_ends_pytest_by_it"],
    ),
    (
        "a timer already running (`pytest-timeout`'s) keeps its deadline and handler",
        &["python/tests/test_plugin_limits.py::test_a_users_pytest_timeout_is_kept_under_a_misbehaving_hand"],
    ),
    (
        "A `gcl` whose `--version` is not this kit's is refused at once",
        &["python/tests/test_plugin_limits.py::test_another_program_named_gcl_is_refused_at_once"],
    ),
    (
        "a hand that cannot start or writes no report raises `gcl.HandError`",
        &[
            "python/tests/test_plugin_limits.py::test_a_missing_binary_is_a_hand_error_and_leaves_no_folder",
            "python/tests/test_plugin_limits.py::test_a_hand_that_fails_to_start_leaves_no_folder",
            "python/tests/test_plugin_limits.py::test_a_hand_that_writes_no_report_is_a_hand_error_and_leaves_no_folder",
        ],
    ),
    (
        "The example host library's suite, from its folder (`pytest` or `python -m pytest`)",
        &[
            "python/tests/test_wheel.py::test_the_example_host_library_passes_its_suite",
            "python/tests/test_wheel.py::test_the_example_runs_with_the_bare_pytest_command_too",
        ],
    ),
    (
        "fails every test with `the host code broke GCL",
        &["python/tests/test_wheel.py::test_the_lf_bug_fails_every_test_naming_the_clause"],
    ),
    (
        "`misbehaviours that fired: truncate at answer 7",
        &["python/tests/test_wheel.py::test_the_short_block_bug_fails_under_misbehaviour_with_what_fired"],
    ),
    // Checked by `.ci/run`, which builds the C++ example with CMake (a check there is named
    // by the line it prints: `.ci/run::LINE`).
    (
        "`-DBH8HOST_PLANTED_LF=ON` plants a CR LF bug that fails both tests: the check-host test on its clause `host-line-ending`, and the campaign with the finding `violation: line-ending: LF sent` in its first run",
        &[".ci/run::the planted CR LF bug fails both gcl tests, as it should"],
    ),
    (
        "build the wheel in their first job (`gcl-wheel`: gcl is not on PyPI, so maturin builds it once from gcl's source",
        &[
            "python/tests/test_ci_recipes.py::test_github_builds_the_wheel_first_and_every_job_installs_that_artifact",
            "python/tests/test_ci_recipes.py::test_gitlab_builds_the_wheel_first_and_every_job_installs_that_artifact",
            "python/tests/test_ci_recipes.py::test_the_recipes_run_the_commands_of_ci_run",
        ],
    ),
    (
        "The cases a root cause blocks (they fail on its clause's bug, not their own) are folded under one line for it, apart from the cases that fail on their own; in JUnit their message starts `blocked by root-cause-N (CLAUSE): `.",
        &["harness/tests/it/report_pages.rs::the_cases_a_bug_blocks_are_folded_under_its_root_cause"],
    ),
    (
        "a test holds the recipes to them",
        &["python/tests/test_ci_recipes.py::test_the_recipes_run_the_commands_of_ci_run"],
    ),
    (
        "over a 4-way matrix",
        &[
            "python/tests/test_ci_recipes.py::test_github_runs_a_four_way_matrix_merged_with_junit_bundles_and_a_cached_corpus",
            "python/tests/test_ci_recipes.py::test_gitlab_runs_a_four_way_matrix_merged_with_junit_bundles_and_a_cached_corpus",
        ],
    ),
    (
        "For `gcl fuzz host` the merged report equals that of one machine running the same runs",
        &["harness/tests/it/fuzz_merge.rs::merged_host_shards_equal_one_machine_running_the_same_runs"],
    ),
    (
        "findings deduplicated by signature (the first found stands, hits add up), corpus entries by content hash",
        &["harness/tests/it/fuzz_merge.rs::device_shards_are_disjoint_and_merge_by_signature_and_content_hash"],
    ),
    // Issue 29 items 4 and 5, issue 32 items 4 and 5.
    (
        "That verdict line is computed once and is the same in the console's `result:` line",
        &[
            "harness/tests/it/report_pages.rs::a_partial_certificate_page_says_partial_the_firmware_and_the_key",
            "harness/tests/it/report_pages.rs::a_conform_run_with_known_failures_is_partial_on_its_page_and_every_output",
        ],
    ),
    (
        "`gcl conform` too says PARTIAL when cases of its levels were skipped or known failures excused (it still exits 0)",
        &[
            "harness/tests/it/report_pages.rs::a_conform_run_with_known_failures_is_partial_on_its_page_and_every_output",
            "harness/tests/it/conform_target_ends.rs::a_hand_whose_motions_end_at_once_skips_the_abort_timing_cases_and_says_why",
        ],
    ),
    (
        "The bundle's page says it is a certificate and shows the firmware's VERS and the signing key's fingerprint",
        &["harness/tests/it/report_pages.rs::a_partial_certificate_page_says_partial_the_firmware_and_the_key"],
    ),
    (
        "A certificate names a built-in profile only when the spec that ran is that built-in's",
        &["harness/tests/it/hardening.rs::a_profile_file_claiming_a_built_in_id_is_certified_as_the_file_it_is"],
    ),
    (
        "A baseline recorded under another profile is refused, and the baseline used is named in the report",
        &["harness/tests/it/hardening.rs::a_baseline_of_another_profile_is_refused_and_a_baseline_is_named"],
    ),
    (
        "records its `--shard K/N`, seed and every option that changed what ran (`provenance`)",
        &[
            "harness/tests/it/fuzz_merge.rs::merged_host_shards_equal_one_machine_running_the_same_runs",
            "harness/tests/it/fuzz_merge.rs::device_shards_are_disjoint_and_merge_by_signature_and_content_hash",
        ],
    ),
    (
        "The merge refuses the same shard twice, another campaign's folder or another N; missing shards are merged but every report says INCOMPLETE and it exits 2",
        &["harness/tests/it/fuzz_merge.rs::a_duplicated_missing_or_mismatched_shard_set_is_never_green"],
    ),
    (
        "It reads shard files without following links, copies no link, FIFO or device, refuses a file over 4 MiB",
        &[
            "harness/tests/it/fuzz_merge.rs::a_merge_copies_no_link_or_fifo_and_reads_no_huge_file",
            "harness/tests/it/fuzz_merge.rs::merged_host_shards_equal_one_machine_running_the_same_runs",
        ],
    ),
    (
        "holds `--out` against campaigns and other merges, and replaces what an earlier merge wrote there",
        &["harness/tests/it/fuzz_merge.rs::merges_hold_their_folder_and_replace_what_a_merge_wrote"],
    ),
    // Issue 39 items 8 to 11.
    (
        "A shard is merged only as gcl wrote it",
        &["harness/tests/it/fuzz_merge.rs::an_edited_relabelled_or_unsealed_shard_is_refused"],
    ),
    (
        "What every shard finds in the campaign's own run 0 (calibration, the run without misbehaviour) is one finding of the merge",
        &["harness/tests/it/fuzz_merge.rs::what_every_shard_found_at_run_0_is_one_finding"],
    ),
    (
        "A merge is written beside `--out` and put in place whole once every input is read",
        &["harness/tests/it/fuzz_merge.rs::a_merge_into_its_own_input_keeps_everything"],
    ),
    (
        "a baseline recorded on another spec (a file declaring a built-in's id with",
        &["harness/tests/it/hardening.rs::a_baseline_of_the_built_in_excuses_nothing_on_a_file_declaring_its_id"],
    ),
    // Added after a second reading.
    (
        "`bh8-262-4.4` (alias `bh8-262`), or a spec TOML file",
        &[
            "harness/tests/it/readme_promises.rs::the_built_in_profiles_and_the_alias_are_the_ones_named",
            "harness/tests/it/hardening.rs::a_profile_file_is_simulated_as_written",
        ],
    ),
    (
        "replays a transcript and shows where the answer parts from the golden one",
        &[
            "harness/tests/it/transcript_cli.rs::replay_exits_1_and_shows_the_parting_byte_on_a_mismatch",
            "harness/tests/it/transcript_mutants.rs::crlf_mismatch_shows_expected_and_actual_at_the_parting_byte",
        ],
    ),
    (
        "turns a script of host lines and blocks into a golden transcript",
        &[
            "harness/tests/it/transcript_cli.rs::a_recording_of_the_simulator_replays_against_it",
            "line/src/record.rs::records_lines_loops_blocks_and_banners",
        ],
    ),
    (
        "a certificate bundle with a SHA-256 manifest and an Ed25519 signature, its check, and a key pair",
        &[
            "harness/tests/it/conform_mutants.rs::certificates_are_written_and_tampering_is_caught",
            "harness/tests/it/hardening.rs::signed_certificates_verify_and_forgeries_do_not",
            "conformance/src/certify.rs::generated_keys_load_back_and_are_never_overwritten",
        ],
    ),
    (
        "the same hand for whoever connects (a test suite), graded when stopped",
        &["harness/tests/it/check_host_serve.rs::a_served_hand_grades_whoever_connected"],
    ),
    (
        "(JSON + schema, JUnit XML, HTML; results.jsonl as cases end)",
        &[
            "harness/tests/it/conform_mutants.rs::the_unmutated_simulator_passes_over_exec_with_reports",
            "harness/tests/it/report_schema.rs::reports_with_every_kind_of_verdict_validate_against_the_schema",
        ],
    ),
    (
        "`certify`, `fuzz device`, `fuzz host` and `check-host` print the same.",
        &["harness/tests/it/readme_promises.rs::certify_and_the_fuzzers_and_check_host_print_progress_as_conform_does"],
    ),
    (
        "The hand runs in fast time",
        &["harness/tests/it/readme_promises.rs::certify_and_the_fuzzers_and_check_host_print_progress_as_conform_does"],
    ),
    (
        "runs the campaign's run indices K-1, K-1+N, ...",
        &[
            "fuzzers/src/fuzz/shard.rs::shards_partition_the_indices",
            "harness/tests/it/fuzz_merge.rs::merged_host_shards_equal_one_machine_running_the_same_runs",
        ],
    ),
    (
        "A step whose answer has not started by its deadline waits up to 2 s",
        &["conformance/src/deadline.rs::deadlines_follow_the_model_with_a_margin_and_a_floor"],
    ),
    (
        "`--no eeprom`, `--no motion`, `--no realtime` and `--no abort-timing` refuse what a case may do",
        &["harness/tests/it/readme_promises.rs::no_motion_realtime_eeprom_or_abort_timing_keeps_a_campaign_from_them"],
    ),
    (
        "A hang is then silence for twice the longest plus 2 s (at least 3 s, at most `--run-budget`, default 60 s)",
        &["harness/tests/it/readme_promises.rs::fuzz_host_measures_its_hang_timeout_unless_given_one"],
    ),
    (
        "`--timeout-hang D` sets the hang timeout by hand and skips the measure",
        &["harness/tests/it/readme_promises.rs::fuzz_host_measures_its_hang_timeout_unless_given_one"],
    ),
    (
        "measures the host's own give-up time at every kind of answer the systematic pass knows",
        &["harness/tests/it/host_verdicts.rs::a_host_whose_timeouts_differ_by_command_has_no_finding"],
    ),
    (
        "Calibration takes at most a quarter of `--duration`: what it has not measured by then it leaves, says so, and the campaign goes on with what it measured.",
        &["harness/tests/it/host_verdicts.rs::a_hang_calibration_sees_is_reported_in_a_short_campaign"],
    ),
    (
        "A hang is confirmed before it is reported: its (minimized) schedule runs again",
        &[
            "harness/tests/it/host_verdicts.rs::a_host_that_gives_up_late_is_a_note_not_a_hang",
            "harness/tests/it/host_verdicts.rs::one_wait_without_a_deadline_is_one_hang_named_by_its_code",
        ],
    ),
    (
        "A host that waits past the hang timeout where calibration silenced the hand has its hang found there, confirmed and reported like any other.",
        &["harness/tests/it/host_verdicts.rs::a_hang_calibration_sees_is_reported_in_a_short_campaign"],
    ),
    (
        "Without `--runs` or `--duration` a campaign lasts 5 minutes, its calibration included",
        &[
            "fuzzers/src/fuzz/host/mod.rs::a_default_campaign_is_a_time_budget_under_ten_minutes",
            "harness/tests/it/readme_promises.rs::fuzz_host_help_says_how_long_a_default_campaign_lasts",
        ],
    ),
    (
        "an overflow through `sscanf` or `strcpy` is signed by the host's function that called it",
        &[
            "harness/tests/it/host_verdicts.rs::an_overflow_through_sscanf_is_one_finding_per_function_of_the_host",
            "fuzzers/src/fuzz/host/detect.rs::an_overflow_through_sscanf_is_signed_by_the_hosts_function",
        ],
    ),
    (
        "is signed by what was thrown and where: `uncaught C++ exception std::system_error in Port::check`",
        &[
            "harness/tests/it/host_verdicts.rs::an_uncaught_cpp_exception_is_named_by_what_was_thrown_and_where",
            "fuzzers/src/fuzz/host/detect.rs::an_uncaught_cpp_exception_is_signed_by_what_was_thrown_and_where",
        ],
    ),
    (
        "A host that crashes has that one finding, not also the RealTime loop or the line it was in when it died.",
        &["harness/tests/it/host_verdicts.rs::a_crash_in_realtime_is_one_finding"],
    ),
    (
        "the frames of the system's libraries it waits in (libc's `syscall`, libstdc++, Boost.Asio's `poll_read`, Poco) in the message",
        &["fuzzers/src/fuzz/host/detect.rs::a_hang_under_system_libraries_is_named_by_the_hosts_frame"],
    ),
    (
        "(`gcl fuzz host --help` lists them)",
        &["harness/tests/it/readme_promises.rs::fuzz_host_help_lists_every_misbehaviour"],
    ),
    (
        "after `--dead-after N` (default 5) timeouts in a row the hand is probed",
        &[
            "harness/tests/it/conform_runner.rs::a_hand_that_stops_answering_ends_the_run_early_with_exit_2",
            "harness/tests/it/readme_promises.rs::conform_dead_after_defaults_to_5",
        ],
    ),
    (
        "The in-process `sim` target keeps simulated time on both sides and runs them.",
        &["harness/tests/it/conform_mutants.rs::the_unmutated_simulator_passes_every_case_of_every_profile"],
    ),
    (
        "a re-signed or unsigned forgery verifies the same",
        &["harness/tests/it/hardening.rs::signed_certificates_verify_and_forgeries_do_not"],
    ),
    (
        "`harness/tests/hosts/py_trusts_short_block.py` is a host that trusts a block two bytes short",
        &["harness/tests/it/host_verdicts.rs::a_host_that_trusts_a_short_block_gives_a_silent_wrong_value"],
    ),
    (
        "a SIGTERM (a CI job's time limit) ends the campaign at once (the hosts in flight are killed), bundles and reports still written",
        &[
            "harness/tests/it/readme_promises.rs::sigterm_ends_a_host_campaign_killing_its_hosts_and_writing_its_reports",
        ],
    ),
    (
        "stopped campaign says `stopped by SIGTERM after N of M runs`: without a new finding it exits 2 (no verdict)",
        &["harness/tests/it/adversarial.rs::a_stopped_device_campaign_says_so_and_has_no_verdict"],
    ),
    (
        "Options that leave no case are refused at the start (`--runs 0`; a `--skip-decision` that every case's preamble rests on, such as `framing-line-ending`)",
        &["harness/tests/it/adversarial.rs::campaigns_that_would_test_nothing_are_refused_at_the_start"],
    ),
    (
        "is an ERROR in `check-host` (the command, how it ended and the last lines of its stderr; every clause \"not exercised\") and ends a `fuzz host` campaign after its first run: exit 2 either way",
        &[
            "harness/tests/it/adversarial.rs::check_host_passes_no_clause_of_a_host_that_never_talked",
            "harness/tests/it/adversarial.rs::fuzz_host_stops_at_once_when_no_run_reaches_the_host",
        ],
    ),
    (
        "every report says how much it judged (`4 of 6 clauses exercised`, `12 of 12 runs reached the host`)",
        &[
            "harness/tests/it/adversarial.rs::check_host_says_how_many_clauses_the_host_exercised",
            "harness/tests/it/adversarial.rs::a_stopped_host_campaign_says_so_and_has_no_verdict",
        ],
    ),
    (
        "A campaign a signal stopped says `stopped by SIGTERM after N of M runs` in every report and exits 2 without a finding.",
        &[
            "harness/tests/it/adversarial.rs::a_stopped_host_campaign_says_so_and_has_no_verdict",
            "harness/tests/it/adversarial.rs::a_host_that_terminates_gcl_stops_the_campaign_without_a_verdict",
        ],
    ),
    (
        "Ctrl-C or SIGTERM on `check-host` stops the host's process group (SIGTERM, then SIGKILL half a second later) and removes its run folder.",
        &["harness/tests/it/adversarial.rs::a_stopped_check_leaves_no_host_and_no_run_folder"],
    ),
    (
        "is the same hand as a context manager (`hand.verdict` after it)",
        &["python/tests/test_wheel.py::test_a_hand_grades_its_session"],
    ),
    ("Options come from a marker", &["python/tests/test_wheel.py::test_marker_options_reach_the_hand"]),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// README.md and the guides of `docs/src/`, one text.
fn documents() -> String {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("docs/src"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.sort();
    files.insert(0, root().join("README.md"));
    files.iter().map(|f| std::fs::read_to_string(f).unwrap()).collect::<Vec<_>>().join("\n")
}

fn collapse(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Whether `file` (a path from the repository root) holds a test function `name`: a Rust `fn`
/// under `#[test]`, a Python `def test_...` (in code, not inside a string), or for `.ci/run`
/// a check that prints the line `name` when it holds.
fn has_test(file: &str, name: &str) -> Result<(), String> {
    let text = std::fs::read_to_string(root().join(file)).map_err(|e| format!("{file}: {e}"))?;
    test_in(file, &text, name)
}

/// [`has_test`] over `text`, the contents of `file`.
fn test_in(file: &str, text: &str, name: &str) -> Result<(), String> {
    if file == ".ci/run" {
        let echo = format!("echo \"{name}\"");
        return if text.lines().any(|l| l.trim_start() == echo) {
            Ok(())
        } else {
            Err(format!("{file} prints no line {name:?}"))
        };
    }
    if file.ends_with(".py") {
        let def = format!("def {name}(");
        let defined = python_code_lines(text).any(|l| {
            let l = l.trim_start();
            l.strip_prefix("async ").unwrap_or(l).starts_with(&def)
        });
        return if name.starts_with("test_") && defined { Ok(()) } else { Err(format!("{file} has no test `{name}`")) };
    }
    let lines: Vec<&str> = text.lines().collect();
    let fun = format!("fn {name}(");
    let at = lines.iter().position(|l| l.trim_start().starts_with(&fun)).ok_or(format!("{file} has no `fn {name}`"))?;
    // The attributes and doc comments above it include `#[test]`.
    let above = lines[..at].iter().rev().map(|l| l.trim()).take_while(|l| l.starts_with("#[") || l.starts_with("//"));
    if above.clone().any(|l| l == "#[test]") { Ok(()) } else { Err(format!("{file}: `{name}` is not a #[test]")) }
}

/// The lines of a Python source that begin in code, not inside a string (a `def` in a
/// triple-quoted string is text): strings, their escapes and comments are followed.
fn python_code_lines(text: &str) -> impl Iterator<Item = &str> {
    // The quote of the string open at the start of each line, and whether it is triple.
    let mut open: Option<(char, bool)> = None;
    text.lines().filter(move |line| {
        let starts_in_code = open.is_none();
        let chars: Vec<char> = line.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            let c = chars[i];
            match open {
                None if c == '#' => break,
                None if c == '"' || c == '\'' => {
                    let triple = chars.get(i + 1) == Some(&c) && chars.get(i + 2) == Some(&c);
                    open = Some((c, triple));
                    i += if triple { 3 } else { 1 };
                    continue;
                }
                None => {}
                Some(_) if c == '\\' => i += 1,
                Some((q, true)) if c == q && chars.get(i + 1) == Some(&q) && chars.get(i + 2) == Some(&q) => {
                    open = None;
                    i += 3;
                    continue;
                }
                Some((q, false)) if c == q => open = None,
                Some(_) => {}
            }
            i += 1;
        }
        // A one-quote string ends with its line (an unterminated one is a syntax error).
        if matches!(open, Some((_, false))) && !line.ends_with('\\') {
            open = None;
        }
        starts_in_code
    })
}

#[test]
fn every_promise_is_quoted_as_written_and_held_by_a_test() {
    let readme = collapse(&documents());
    let mut wrong = Vec::new();
    for (fragment, tests) in PROMISES {
        if !readme.contains(&collapse(fragment)) {
            wrong.push(format!("neither README.md nor docs/src/ says {fragment:?} any more"));
        }
        if tests.is_empty() {
            wrong.push(format!("{fragment:?} names no test"));
        }
        for t in *tests {
            let Some((file, name)) = t.split_once("::") else {
                wrong.push(format!("{t}: not FILE::NAME"));
                continue;
            };
            if let Err(e) = has_test(file, name) {
                wrong.push(format!("{fragment:?}: {e}"));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The checker itself fails on what it must catch: a reworded promise, a test that is gone, a
/// helper that is not a test.
#[test]
fn the_table_check_catches_a_missing_test_and_a_non_test() {
    assert!(has_test(SELF, "every_promise_is_quoted_as_written_and_held_by_a_test").is_ok());
    assert!(has_test(SELF, "no_such_test").is_err());
    assert!(has_test(SELF, "has_test").is_err(), "a helper is not a test");
    assert!(has_test("python/tests/test_wheel.py", "test_no_such_test").is_err());
    // A `def test_...` inside a string is no test, wherever the string opened.
    let py = "X = '''\ndef test_in_a_string():\n    pass\n'''\ndef test_real():\n    s = \"it's \\\" def test_x():\"  # '''\n\n    t = \"\"\"a\n    def test_in_a_docstring():\n    \"\"\"\nasync def test_after():\n    pass\n";
    assert!(test_in("t.py", py, "test_real").is_ok(), "{py}");
    assert!(test_in("t.py", py, "test_after").is_ok(), "{py}");
    assert!(test_in("t.py", py, "test_in_a_string").is_err(), "{py}");
    assert!(test_in("t.py", py, "test_in_a_docstring").is_err(), "{py}");
    assert!(has_test(".ci/run", "the planted CR LF bug fails both gcl tests, as it should").is_ok());
    assert!(has_test(".ci/run", "the planted CR LF bug passes").is_err());
}

/// "`gcl sim --pty` and `--tcp` run in real time by default"; `--time fast` is "the default of
/// `--stdio`". Judged by the fuzzer's own real-time check (a close from home, timed against
/// the model): it passes the pty and TCP sims started without `--time` and refuses the stdio one.
#[test]
fn pty_and_tcp_sims_run_in_real_time_and_stdio_in_fast_time_by_default() {
    let profile = Profile::builtin("bh8-262").unwrap();
    for transport in [Transport::Pty, Transport::Tcp] {
        let sim = SimProcess::start_exact(transport, &[]);
        let o = FuzzOptions::new(sim.target().parse().unwrap(), profile.clone());
        assert!(o.allowed.motion && o.allowed.abort_timing);
        if let Err(e) = check_real_time(&o) {
            panic!("gcl sim {transport:?} without --time is not in real time: {e}");
        }
    }
    let stdio: Target = format!("exec:{GCL} sim --stdio").parse().unwrap();
    let o = FuzzOptions::new(stdio, profile);
    let r = check_real_time(&o);
    assert!(matches!(r, Err(FuzzError::NotRealTime { .. })), "gcl sim --stdio without --time: {r:?}");
}

/// "never past their size limit (4 MiB; 64 KiB for keys)": one byte past the limit is refused
/// as too large, a file at the limit is read (and then refused for what it holds).
#[test]
fn inputs_are_refused_one_byte_past_4_mib_and_keys_one_byte_past_64_kib() {
    let dir = tempfile::tempdir().unwrap();
    let sized = |name: &str, len: u64| {
        let p = dir.path().join(name);
        std::fs::File::create(&p).unwrap().set_len(len).unwrap();
        p
    };
    let gcl = |args: &[&std::ffi::OsStr]| {
        let out = Command::new(GCL).args(args).current_dir(dir.path()).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let too_large = "larger than the limit";
    let os = |s: &'static str| std::ffi::OsStr::new(s);
    for (len, refused) in [(4 << 20, false), ((4 << 20) + 1, true)] {
        let p = sized(&format!("t{len}.gcl"), len);
        let (code, err) = gcl(&[os("replay"), p.as_os_str(), os("--target"), os("sim")]);
        assert_eq!(code, Some(2), "{err}");
        assert_eq!(err.contains(too_large), refused, "a transcript of {len} bytes: {err}");
    }
    std::fs::create_dir(dir.path().join("cert")).unwrap();
    for (len, refused) in [(64 << 10, false), ((64 << 10) + 1, true)] {
        let p = sized(&format!("k{len}.pub"), len);
        let (code, err) = gcl(&[os("certify"), os("--verify"), os("cert"), os("--pubkey"), p.as_os_str()]);
        assert_eq!(code, Some(2), "{err}");
        assert_eq!(err.contains(too_large), refused, "a key of {len} bytes: {err}");
    }
}

fn sim_campaign(runs: u64) -> FuzzOptions {
    let mut o = FuzzOptions::new(Target::Sim { profile: None }, Profile::builtin("bh8-262").unwrap());
    o.budget = Budget::Runs(runs);
    o.seed = 1;
    o
}

/// "`--write-budget N` caps EEPROM writes (restores included) over the whole run": the same
/// campaign writes more than N times without a budget, and at most N with one.
#[test]
fn the_write_budget_caps_a_campaigns_eeprom_writes() {
    let free = run(&sim_campaign(300), &|_| {}).unwrap();
    assert!(free.eeprom_writes > 3, "the campaign must write for the cap to show: {}", free.eeprom_writes);
    let mut o = sim_campaign(300);
    o.write_budget = Some(3);
    let capped = run(&o, &|_| {}).unwrap();
    assert!(capped.eeprom_writes <= 3, "{} writes under --write-budget 3", capped.eeprom_writes);
}

/// "`serial:` targets are fuzzed conservatively by default: no FSAVE or PSAVE at all unless
/// `--write-budget N` allows N writes ..., and one worker": a campaign over a pty (a `serial:`
/// target) with the defaults writes nothing, and `--jobs 2` on a serial port is refused.
#[test]
fn serial_targets_are_fuzzed_without_eeprom_writes_and_by_one_worker() {
    let sim = SimProcess::start(Transport::Pty, &["--unpaced"]);
    let mut o = FuzzOptions::new(sim.target().parse().unwrap(), Profile::builtin("bh8-262").unwrap());
    o.budget = Budget::Runs(40);
    o.seed = 1;
    o.allowed.abort_timing = false; // the sim is in fast time
    let s = run(&o, &|_| {}).unwrap();
    assert_eq!(s.eeprom_writes, 0, "a serial: campaign wrote the EEPROM by default");
    let out = Command::new(GCL)
        .args(["fuzz", "device", "--target", &sim.target(), "--jobs", "2", "--runs", "1", "-q"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("one worker"), "{err}");
}

/// "`harness/tests/host_mutants/` has fourteen small buggy hosts (Python with pyserial, C with
/// AddressSanitizer, Rust)".
#[test]
fn there_are_fourteen_host_mutants() {
    let dir = root().join("harness/tests/host_mutants");
    let mut mutants: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| ["py_", "c_", "rs_"].iter().any(|p| n.starts_with(p)))
        .collect();
    mutants.sort();
    assert_eq!(mutants.len(), 14, "{mutants:?}");
    for lang in ["py_", "c_", "rs_"] {
        assert!(mutants.iter().any(|m| m.starts_with(lang)), "no {lang} mutant: {mutants:?}");
    }
}

/// "Profiles: `seed`, `bh8-262-4.3`, `bh8-262-4.4` (alias `bh8-262`)".
#[test]
fn the_built_in_profiles_and_the_alias_are_the_ones_named() {
    for id in ["seed", "bh8-262-4.3", "bh8-262-4.4"] {
        assert_eq!(Profile::builtin(id).unwrap().id, id);
    }
    assert_eq!(Profile::builtin("bh8-262").unwrap().id, "bh8-262-4.4");
}

/// "`certify`, `fuzz device`, `fuzz host` and `check-host` print the same" progress as
/// `conform` in a CI log (stderr a pipe): a line with done/total as the run starts and one
/// ending "(done)". `fuzz host`'s first line names the hand it runs: "time fast" by
/// default.
#[test]
fn certify_and_the_fuzzers_and_check_host_print_progress_as_conform_does() {
    let dir = tempfile::tempdir().unwrap();
    let runs: [(&str, &[&str]); 4] = [
        ("gcl certify: ", &["certify", "--target", "sim:seed", "--only", "framing-*", "--partial", "--out", "cert"]),
        ("gcl fuzz device: ", &["fuzz", "device", "--target", "sim", "--runs", "5"]),
        ("gcl fuzz host: ", &["fuzz", "host", "--runs", "2", "--timeout-hang", "3s", "--", "sh", "-c", TALKS]),
        ("gcl check-host: ", &["check-host", "--", "sh", "-c", TALKS]),
    ];
    for (prefix, args) in runs {
        let out = Command::new(GCL).args(args).current_dir(dir.path()).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with(prefix)).collect();
        let first = lines.iter().find(|l| l.contains("/")).unwrap_or_else(|| panic!("{args:?}: no progress: {err}"));
        assert!(first.starts_with(&format!("{prefix}1/")) && first.contains(" elapsed"), "{args:?}: {err}");
        assert!(lines.iter().any(|l| l.ends_with("(done)")), "{args:?}: no last line: {err}");
        if prefix == "gcl fuzz host: " {
            assert!(lines[0].contains("time fast"), "fuzz host's hand runs in fast time by default: {err}");
        }
    }
}

/// "`--no eeprom`, `--no motion`, `--no realtime` and `--no abort-timing` refuse what a case may
/// do": the same campaign reaches motion, RealTime, EEPROM writes and ^C mid-motion with
/// everything allowed, and none of them with each refused.
#[test]
fn no_motion_realtime_eeprom_or_abort_timing_keeps_a_campaign_from_them() {
    let moved = |f: &std::collections::BTreeSet<String>| f.contains("mode:Idle->Busy");
    let looped = |f: &std::collections::BTreeSet<String>| f.contains("mode:Idle->Loop");
    let all = run(&sim_campaign(300), &|_| {}).unwrap();
    assert!(moved(&all.features) && looped(&all.features), "{:?}", all.features);
    assert!(all.features.contains("abort:mid-motion") && all.eeprom_writes > 0, "{:?}", all.features);
    let mut o = sim_campaign(300);
    o.allowed.motion = false;
    o.allowed.realtime = false;
    o.allowed.eeprom = false;
    o.write_budget = Some(0);
    let s = run(&o, &|_| {}).unwrap();
    assert!(!moved(&s.features) && !looped(&s.features), "{:?}", s.features);
    assert_eq!(s.eeprom_writes, 0);
    let mut o = sim_campaign(300);
    o.allowed.abort_timing = false;
    let s = run(&o, &|_| {}).unwrap();
    assert!(!s.features.contains("abort:mid-motion"), "{:?}", s.features);
}

/// "A hang is then silence for twice the longest plus 2 s (at least 3 s, at most `--run-budget`,
/// default 60 s)"; "`--timeout-hang D` sets the hang timeout by hand and skips the measure".
/// A host that never waits measures no timeout: its hang timeout is the floor, and `fuzz.json`
/// keeps the calibration; with `--timeout-hang` there is none.
#[test]
fn fuzz_host_measures_its_hang_timeout_unless_given_one() {
    use gcl_harness::fuzz::host::hang_timeout;
    use std::time::Duration;
    let (floor, budget) = (Duration::from_secs(3), Duration::from_secs(60));
    assert_eq!(hang_timeout(Some(Duration::from_secs(10)), floor, budget), Duration::from_secs(22));
    assert_eq!(hang_timeout(Some(Duration::from_millis(200)), floor, budget), floor);
    assert_eq!(hang_timeout(Some(Duration::from_secs(40)), floor, budget), budget);
    let dir = tempfile::tempdir().unwrap();
    let campaign = |extra: &[&str], report: &str| -> serde_json::Value {
        let out = Command::new(GCL)
            .args(["fuzz", "host", "--runs", "1", "--report", report])
            .args(extra)
            .args(["--", "sh", "-c", TALKS])
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_str(&std::fs::read_to_string(dir.path().join(report).join("fuzz.json")).unwrap()).unwrap()
    };
    let measured = campaign(&[], "measured");
    let cal = &measured["calibration"];
    assert!(cal["runs"].as_u64().is_some_and(|n| n > 0), "the measure ran: {cal}");
    assert_eq!(cal["timeout_hang_ms"], 3000, "at least 3 s: {cal}");
    let given = campaign(&["--timeout-hang", "5s"], "given");
    assert!(given.get("calibration").is_none_or(|c| c.is_null()), "no measure with --timeout-hang: {given}");
}

/// "Without `--runs` or `--duration` a campaign lasts 5 minutes ... and it says how to run
/// longer": the help says so (the library's default is `a_default_campaign_is_a_time_budget_
/// under_ten_minutes`).
#[test]
fn fuzz_host_help_says_how_long_a_default_campaign_lasts() {
    let out = Command::new(GCL).args(["fuzz", "host", "--help"]).output().unwrap();
    let help = collapse(&String::from_utf8_lossy(&out.stdout));
    assert!(help.contains("Without --runs or --duration a campaign lasts 5 minutes"), "{help}");
    assert!(help.contains("Stop after this long (30s, 5m; default 5m unless --runs is given)"), "{help}");
}

/// "`--ops delay-above,truncate=5` restricts and weights the misbehaviours (`gcl fuzz host
/// --help` lists them)": every misbehaviour is in the help, with its default weight.
#[test]
fn fuzz_host_help_lists_every_misbehaviour() {
    use gcl_harness::sim::misbehave::Operator;
    let out = Command::new(GCL).args(["fuzz", "host", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for op in Operator::ALL {
        let listed = help.lines().any(|l| {
            let mut w = l.split_whitespace();
            l.starts_with("  ") && w.next() == Some(op.name()) && w.next() == Some(&op.default_weight().to_string())
        });
        assert!(listed, "`gcl fuzz host --help` does not list {} (weight {})", op.name(), op.default_weight());
    }
}

/// "after `--dead-after N` (default 5) timeouts in a row the hand is probed": the mechanism is
/// `conform_runner.rs`'s (with N = 2, to stay quick); the default is what `gcl conform --help`
/// gives the option (a run that waits out five timeouts costs some 16 s).
#[test]
fn conform_dead_after_defaults_to_5() {
    let out = Command::new(GCL).args(["conform", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    let option = help.split("--dead-after <N>").nth(1).expect("conform --help has --dead-after");
    // Its own lines only: up to the next option.
    let default =
        option.lines().skip(1).map(str::trim).take_while(|l| !l.starts_with('-')).find(|l| l.starts_with("[default: "));
    assert_eq!(default, Some("[default: 5]"), "{option}");
}

/// "a SIGTERM (a CI job's time limit) ends the campaign at once (the hosts in flight are
/// killed), bundles and reports still written": the host sleeps for ten minutes; the campaign
/// ends without waiting for it, the host is gone and the reports are there, saying it was
/// stopped ("exits 2 ... when a signal stopped it without a finding"). (The one minute
/// allowed is a guard against a hang, not a measure.)
#[test]
fn sigterm_ends_a_host_campaign_killing_its_hosts_and_writing_its_reports() {
    use nix::sys::signal::{Signal, kill};
    use nix::unistd::Pid;
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let mut child = Command::new(GCL)
        .args(["fuzz", "host", "--duration", "1h", "--timeout-hang", "3s", "--report", "rep", "--out", "out"])
        .args(["--", "sh", "-c", "echo $$ >> pids; exec sleep 600"])
        .current_dir(dir.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let pids = dir.path().join("pids");
    let start = Instant::now();
    while std::fs::read_to_string(&pids).map_or(true, |p| p.trim().is_empty()) {
        assert!(start.elapsed() < Duration::from_secs(60), "no host started");
        std::thread::sleep(Duration::from_millis(50));
    }
    kill(Pid::from_raw(child.id() as i32), Signal::SIGTERM).unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("gcl fuzz host did not end on SIGTERM: it waits for its host");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(status.code(), Some(2), "stopped without a finding: no verdict: {status}");
    for pid in std::fs::read_to_string(&pids).unwrap().split_whitespace() {
        let pid = Pid::from_raw(pid.parse().unwrap());
        assert!(kill(pid, None).is_err(), "host {pid} left running");
    }
    for f in ["fuzz.json", "junit.xml", "report.json", "report.html"] {
        assert!(dir.path().join("rep").join(f).is_file(), "{f} not written");
    }
    let report = std::fs::read_to_string(dir.path().join("rep/report.json")).unwrap();
    assert!(report.contains("stopped by SIGTERM after 0"), "{report}");
}

/// A host that talks to the hand (it opens the port and sends one ^C) and exits: the least a
/// host does for a run to judge anything of it (one that never talks is no test at all).
const TALKS: &str = "exec 3<>\"$GCL_PORT\"; printf '\\003' >&3";

/// The facts a host report (`report.json`'s `host.facts`) lists, by name.
fn host_facts(report: &Path) -> std::collections::BTreeMap<String, String> {
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    let facts = r["host"]["facts"].as_array().unwrap_or_else(|| panic!("no host facts: {r}"));
    facts.iter().map(|f| (f[0].as_str().unwrap().to_string(), f[1].as_str().unwrap().to_string())).collect()
}

/// "`gcl check-host`, whose hand never goes silent, calls a hang after 20 s by default": the
/// run's hang timeout, as its report states it, is 20 s without `--timeout-hang` and what
/// `--timeout-hang` says with it (a host that exits at once: nothing is waited for).
#[test]
fn check_host_calls_a_hang_after_20_s_unless_told_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    for (extra, want) in [(&[][..], "20 s (the default)"), (&["--timeout-hang", "7s"][..], "7 s (--timeout-hang)")] {
        let out = Command::new(GCL)
            .args(["check-host", "--report", "rep"])
            .args(extra)
            .args(["--", "sh", "-c", TALKS])
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
        let facts = host_facts(&dir.path().join("rep/report.json"));
        assert_eq!(facts.get("hang timeout").map(String::as_str), Some(want), "{extra:?}: {facts:?}");
    }
}

/// "The hand runs in fast time, unpaced, by default; `--time real` gives a hand paced at its
/// BAUD": what the campaign's hand was given, in the console's first line and the report's
/// facts; `--baud` paces it at a fixed rate. (That a paced hand offers each byte at its wire
/// time is the engine's tests'.)
#[test]
fn the_host_fuzzers_hand_is_unpaced_by_default_and_paced_at_its_baud_in_real_time() {
    let dir = tempfile::tempdir().unwrap();
    let runs: [(&[&str], &str, &str, &str); 3] = [
        (&[], "fast", "unpaced", "time fast, unpaced,"),
        (&["--time", "real"], "real", "the hand's BAUD", "time real, paced at the hand's BAUD,"),
        (&["--baud", "1200"], "fast", "1200 baud", "time fast, paced at 1200 baud,"),
    ];
    for (extra, time, pace, line) in runs {
        let out = Command::new(GCL)
            .args(["fuzz", "host", "--runs", "1", "--timeout-hang", "3s", "--report", "rep"])
            .args(extra)
            .args(["--", "sh", "-c", TALKS])
            .current_dir(dir.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{extra:?}: {err}");
        let first = err.lines().find(|l| l.starts_with("gcl fuzz host: seed")).unwrap_or_default();
        assert!(first.contains(line), "{extra:?}: {err}");
        let facts = host_facts(&dir.path().join("rep/report.json"));
        assert_eq!(facts.get("time").map(String::as_str), Some(time), "{extra:?}: {facts:?}");
        assert_eq!(facts.get("pace").map(String::as_str), Some(pace), "{extra:?}: {facts:?}");
    }
}

/// "A host that never gives up in 30 s is measured as having no timeout": calibration waits
/// at most [`CALIBRATION_CAP`] (30 s), or the run budget when that is shorter, for a host the
/// hand fell silent on; a host that sends one line and reads for ever is measured with no
/// timeout at all (its hang timeout is then the floor). The run budget of 1 s stands in for
/// the 30 s here.
#[test]
fn a_host_that_never_gives_up_is_measured_as_having_no_timeout() {
    use gcl_harness::fuzz::host::{CALIBRATION_CAP, HostRun, Transport as HostTransport, calibrate};
    use gcl_harness::sim::{Pace, TimeMode};
    use std::time::Duration;
    assert_eq!(CALIBRATION_CAP, Duration::from_secs(30));
    let run = HostRun {
        command: ["sh", "-c", "exec 3<>\"$GCL_PORT\"; printf '\\r' >&3; exec cat <&3 >/dev/null"]
            .map(String::from)
            .to_vec(),
        transport: HostTransport::Pty,
        profile: Profile::builtin("seed").unwrap(),
        time: TimeMode::Fast,
        pace: Pace::Unpaced,
        hand_seed: 0,
        timeout_hang: Duration::from_millis(500),
        budget: Duration::from_secs(1),
        link: None,
        coverage: Default::default(),
        env: Vec::new(),
    };
    let c = calibrate(&run, None, 1, &std::sync::atomic::AtomicBool::new(false)).unwrap();
    assert!(!c.points.is_empty(), "the hand never fell silent on the host: {c:?}");
    assert!(c.points.iter().all(|(_, waited)| waited.is_none()), "{c:?}");
    assert_eq!(c.host_timeout_ms, None, "{c:?}");
    assert_eq!(c.timeout_hang_ms, 500, "no timeout measured: the floor: {c:?}");
}

/// "Against hands outside this process, positions ... read after RealTime motion or a ^C
/// mid-motion are judged only by their ranges": the same case (a close stopped by ^C, then
/// FGET P) expects the finger positions anywhere in P's range on a hand outside this process,
/// and near the model's own in-process; after a close that ran to its end they are near the
/// model's on both.
#[test]
fn positions_read_after_a_mid_motion_abort_are_judged_by_their_range_outside_this_process() {
    use gcl_harness::fuzz::device::action::HostAction;
    use gcl_harness::fuzz::device::case::build_case;
    let p = Profile::builtin("seed").unwrap();
    let full = format!("{}..{}", p.param(p.param_id("P").unwrap()).min, p.param(p.param_id("P").unwrap()).max);
    let read = |first: HostAction, wide: bool| -> String {
        let built = build_case(&p, &[first, HostAction::Line("FGET P".into())], "t", "t", wide, true).unwrap();
        let step =
            built.transcript.steps.iter().rev().find(|s| s.send.as_ref().is_some_and(|h| h.bytes == b"FGET P\r"));
        step.expect("the FGET P step").expect.to_text()
    };
    let abort = || HostAction::LineThenAbort { line: "C".into(), after_ms: 300 };
    let outside = read(abort(), true);
    assert!(outside.matches(&full).count() >= 3, "the whole range {full} for each finger: {outside}");
    let inside = read(abort(), false);
    assert!(!inside.contains(&full), "in-process, near the model's: {inside}");
    let ended = read(HostAction::Line("C".into()), true);
    assert!(!ended.contains(&full), "after a motion that ended, near the model's: {ended}");
}
