#!/usr/bin/env bash
# Issue 37's "Done means" table: `gcl fuzz device` against the *correct* simulated hand finds
# nothing, campaign after campaign (different seeds), on every transport a firmware team uses:
#
#   exec      `exec:gcl sim --stdio`, `--no abort-timing` (fast time ends a motion at once)
#   pty-real  `gcl sim --pty` in real time, paced at its BAUD (9600) as a real hand, fuzzed as
#             `serial:PTY?baud=9600`
#   pty-fast  `gcl sim --pty --time fast --baud 38400`, `serial:PTY?baud=38400 --no abort-timing`
#   ser9600   `gcl sim --pty --profile bh8-262-4.3`, `serial:PTY?baud=9600 --no motion`
#   ser38400  `gcl sim --pty --baud 38400 --profile bh8-262-4.3`, `serial:PTY?baud=38400 --no motion`
#
#   harness/benches/fuzz_device_table.sh [OUT] [WAY...]
#
# GCL (default target/release/gcl), SEEDS (campaigns per way, default 20: seeds 1..SEEDS),
# DURATION (per campaign, default 30s) and JOBS (campaigns at once, default 2, each under
# `nice`) set the rest. Seeds run in the outer loop, so a table cut short has about as many
# campaigns of each way. Each campaign writes OUT/<way>-<seed>/ (fuzz-device.json, console.txt)
# and one line `way<TAB>seed<TAB>exit<TAB>runs<TAB>findings<TAB>not reproduced<TAB>hand after`
# into OUT/table.tsv; the end of the file sums each way up (campaigns, those with 0 findings
# and 0 notes, runs). The campaigns are timed: their run counts move with the machine's load
# (note `uptime` beside them).
set -u
out=${1:-target/fuzz-table}
shift 1 2>/dev/null || true
GCL=${GCL:-target/release/gcl}
GCL=$(realpath "$GCL")
SEEDS=${SEEDS:-20}
DURATION=${DURATION:-30s}
JOBS=${JOBS:-2}
ways=("$@")
[ ${#ways[@]} -eq 0 ] && ways=(exec pty-real pty-fast ser9600 ser38400)
mkdir -p "$out"
tsv="$out/table.tsv"
: >"$tsv"
echo "# $(date -u +%FT%TZ), $DURATION per campaign, seeds 1..$SEEDS, $JOBS at once, load: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$tsv"

# One campaign: way, seed.
campaign() {
    local way=$1 seed=$2 dir="$out/$1-$2" sim="" target simargs=() fuzzargs=()
    rm -rf "$dir"
    mkdir -p "$dir"
    case "$way" in
    exec)
        target="exec:$GCL sim --stdio --profile bh8-262"
        fuzzargs=(--profile bh8-262 --no abort-timing)
        ;;
    pty-real)
        simargs=(--profile bh8-262)
        fuzzargs=(--profile bh8-262)
        target="serial:PTY?baud=9600"
        ;;
    pty-fast)
        simargs=(--time fast --baud 38400 --profile bh8-262)
        fuzzargs=(--profile bh8-262 --no abort-timing)
        target="serial:PTY?baud=38400"
        ;;
    ser9600)
        simargs=(--profile bh8-262-4.3)
        fuzzargs=(--profile bh8-262-4.3 --no motion)
        target="serial:PTY?baud=9600"
        ;;
    ser38400)
        simargs=(--baud 38400 --profile bh8-262-4.3)
        fuzzargs=(--profile bh8-262-4.3 --no motion)
        target="serial:PTY?baud=38400"
        ;;
    *)
        echo "way: exec, pty-real, pty-fast, ser9600 or ser38400" >&2
        return 2
        ;;
    esac
    if [ "$way" != exec ]; then
        nice -n 5 "$GCL" sim --pty "${simargs[@]}" >"$dir/sim.txt" 2>/dev/null &
        sim=$!
        for _ in $(seq 100); do
            [ -s "$dir/sim.txt" ] && break
            sleep 0.1
        done
        target=${target/PTY/$(head -1 "$dir/sim.txt")}
    fi
    nice -n 5 "$GCL" fuzz device --target "$target" "${fuzzargs[@]}" --seed "$seed" --duration "$DURATION" -q \
        --report "$dir" >"$dir/console.txt" 2>&1
    local rc=$?
    if [ -n "$sim" ]; then
        kill "$sim" 2>/dev/null
        wait "$sim" 2>/dev/null
    fi
    local json="$dir/fuzz-device.json"
    if [ -s "$json" ]; then
        jq -r --arg w "$way" --arg s "$seed" --arg rc "$rc" \
            '[$w, $s, $rc, .runs, (.findings | length), ((.not_reproduced // []) | length), ((.hand_after // []) | join(" / "))] | @tsv' \
            "$json" >>"$tsv"
    else
        printf '%s\t%s\t%s\t\t\t\t%s\n' "$way" "$seed" "$rc" "$(tail -1 "$dir/console.txt")" >>"$tsv"
    fi
}

for seed in $(seq "$SEEDS"); do
    for way in "${ways[@]}"; do
        while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do
            wait -n
        done
        campaign "$way" "$seed" &
    done
done
wait
for way in "${ways[@]}"; do
    grep -v '^#' "$tsv" | awk -F'\t' -v w="$way" '$1 == w {
        n++; if ($5 == "0" && $6 == "0" && $3 == "0") clean++
        if (min == "" || $4 + 0 < min) min = $4 + 0
        if ($4 + 0 > max) max = $4 + 0
        f += $5; r += $6
    } END { printf "# %s: %d campaigns, %d with 0 findings, 0 notes and exit 0; %d findings, %d notes in all; runs %s-%s\n", w, n, clean, f, r, min, max }' >>"$tsv"
done
grep '^# [a-z]' "$tsv" | tail -n "${#ways[@]}"
