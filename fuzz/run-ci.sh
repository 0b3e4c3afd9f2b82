#!/usr/bin/env bash
# Runs every cargo-fuzz target of gcl for a while on the stable toolchain and exits non-zero
# if any of them finds a crash (a panic in the model or a failed property check).
#
#   GCL_FUZZ_SECONDS    seconds per target (default 30)
#   GCL_FUZZ_TARGETS    space-separated targets (default: grammar device realtime spec wire transcript client)
#   GCL_FUZZ_JOBS       targets fuzzed at once (default: one per core)
#   GCL_FUZZ_SANITIZER  address (default) or none (faster; the model is forbid(unsafe_code),
#                       so ASan mostly watches its dependencies)
#   --build-only        install cargo-fuzz when missing and build every target, run none
#                       (.ci/run builds while the tests run, and fuzzes after them)
#
# Dictionaries come from fuzz/seeds/dicts/<target>.dict when there is one.
# Reproducers of crashes land in fuzz/artifacts/<target>/; replay one on stable with
#   cargo run -p gcl-fuzz --bin <target> -- fuzz/artifacts/<target>/crash-...
# New corpus entries go to fuzz/corpus/<target>/ (ignored by git); the committed seeds in
# fuzz/seeds/<target>/ are read, never written.
set -euo pipefail
cd "$(dirname "$0")"

seconds=${GCL_FUZZ_SECONDS:-30}
targets=${GCL_FUZZ_TARGETS:-grammar device realtime spec wire transcript client}
sanitizer=${GCL_FUZZ_SANITIZER:-address}

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "run-ci: installing cargo-fuzz"
    cargo install cargo-fuzz --locked
fi

# cargo-fuzz passes -Z flags to rustc; RUSTC_BOOTSTRAP lets the stable toolchain take them.
export RUSTC_BOOTSTRAP=1

# One build for every target; each `cargo fuzz run` below then finds it up to date.
cargo fuzz build --sanitizer "$sanitizer"
if [[ "${1:-}" == --build-only ]]; then
    echo "run-ci: built ${targets}"
    exit 0
fi

scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

# One target, its log in $scratch/<t>.log; non-zero when it found a crash.
fuzz_one() {
    local t=$1
    mkdir -p "corpus/$t" "$scratch/$t"
    # seeds/<t>/crash-* reproduce model bugs already reported (tests/seeds.rs lists them);
    # leaving them out lets the run look for new ones instead of stopping on a known one.
    for f in "seeds/$t"/*; do
        case "$(basename "$f")" in
            crash-*) echo "run-ci: known crash, not fuzzed: $f" ;;
            *) cp "$f" "$scratch/$t/" ;;
        esac
    done
    local dict=()
    if [[ -f "seeds/dicts/$t.dict" ]]; then dict=(-dict="seeds/dicts/$t.dict"); fi
    echo "run-ci: fuzzing $t for ${seconds}s"
    # -timeout: an input that takes this long is a finding (a hang), not a slow test.
    cargo fuzz run --sanitizer "$sanitizer" "$t" "corpus/$t" "$scratch/$t" -- \
        "${dict[@]}" -max_total_time="$seconds" -timeout=20 -print_final_stats=1
}

# Each target runs on one core; GCL_FUZZ_JOBS of them at once (default: one per core), each
# for its full ${seconds}s, its log printed whole when it ends.
jobs=${GCL_FUZZ_JOBS:-$(nproc)}
declare -A running=()
failed=()
finish_one() {
    local pid rc=0
    wait -n -p pid "${!running[@]}" || rc=$?
    local t=${running[$pid]}
    unset "running[$pid]"
    cat "$scratch/$t.log"
    if ((rc != 0)); then
        echo "run-ci: $t found a crash; reproducer in fuzz/artifacts/$t/" >&2
        failed+=("$t")
    fi
}
for t in $targets; do
    while ((${#running[@]} >= jobs)); do finish_one; done
    fuzz_one "$t" >"$scratch/$t.log" 2>&1 &
    running[$!]=$t
done
while ((${#running[@]} > 0)); do finish_one; done

if ((${#failed[@]})); then
    echo "run-ci: crashes in: ${failed[*]}" >&2
    exit 1
fi
echo "run-ci: ${targets} ran ${seconds}s each without a crash"
