#!/usr/bin/env bash
# Findings per fault of `gcl fuzz device` outside this process (issue 31): for every fault of
# `gcl sim --help` (the list its refusal
# of an unknown fault gives), one campaign over `exec:gcl sim --stdio --fault F` and one over a pty at
# 38400 (`gcl sim --pty --time fast --baud 38400 --fault F`, fuzzed as `serial:PATH?baud=38400`),
# both with `--no abort-timing` (fast time ends a motion at once) and findings unminimized.
#
#   harness/benches/fuzz_device_sweep.sh [sim|exec|pty] [OUT] [FAULT...]
#
# `sim` is the same sweep in process (RUNS_SIM cases, default 2000), as issue 19 measured it.
# GCL (default target/release/gcl), RUNS (exec: cases per campaign, default 300), SECONDS_PTY
# (pty: seconds per campaign, default 20), PROFILE (default bh8-262) and SEED (default 1) set
# the rest. Each campaign writes its report into OUT/<way>/<fault>/ (fuzz-device.json) and one
# line `fault<TAB>findings<TAB>runs<TAB>key | key ...<TAB>not reproduced<TAB>signature (k/n) | ...`
# into OUT/<way>.tsv (a failure that did not fail again on every replay on a fresh connection is
# a note, not a finding: issue 37); the last line of the
# file is the distribution (how many faults gave 0, 1, 2, ... findings). The pty campaigns are
# timed, so their figures move with the machine's load: note `uptime` beside them.
set -u
way=${1:-exec}
out=${2:-target/fuzz-sweep}
shift 2 2>/dev/null || shift $#
GCL=${GCL:-target/release/gcl}
GCL=$(realpath "$GCL")
RUNS=${RUNS:-300}
RUNS_SIM=${RUNS_SIM:-2000}
SECONDS_PTY=${SECONDS_PTY:-20}
PROFILE=${PROFILE:-bh8-262}
SEED=${SEED:-1}
faults=("$@")
if [ ${#faults[@]} -eq 0 ]; then
    # Every fault the sim knows: its refusal of an unknown one lists them.
    mapfile -t faults < <("$GCL" sim --stdio --fault '?' 2>&1 | sed -n 's/.*known faults: //p' | tr -d ' ' | tr ',' '\n')
fi
mkdir -p "$out/$way"
tsv="$out/$way.tsv"
: >"$tsv"
echo "# $way, profile $PROFILE, seed $SEED, $(date -u +%FT%TZ), load: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$tsv"
for f in "${faults[@]}"; do
    dir="$out/$way/$f"
    rm -rf "$dir"
    mkdir -p "$dir"
    case "$way" in
    sim)
        "$GCL" fuzz device --target "sim:$PROFILE" --fault "$f" --seed "$SEED" --runs "$RUNS_SIM" --no-minimize -q \
            --report "$dir" >"$dir/console.txt" 2>&1
        ;;
    exec)
        "$GCL" fuzz device --target "exec:$GCL sim --stdio --profile $PROFILE --fault $f" --profile "$PROFILE" \
            --no abort-timing --seed "$SEED" --runs "$RUNS" --no-minimize -q --report "$dir" >"$dir/console.txt" 2>&1
        ;;
    pty)
        "$GCL" sim --pty --time fast --baud 38400 --profile "$PROFILE" --fault "$f" >"$dir/sim.txt" 2>/dev/null &
        sim=$!
        for _ in $(seq 50); do
            [ -s "$dir/sim.txt" ] && break
            sleep 0.1
        done
        path=$(head -1 "$dir/sim.txt")
        "$GCL" fuzz device --target "serial:$path?baud=38400" --profile "$PROFILE" --no abort-timing \
            --seed "$SEED" --duration "${SECONDS_PTY}s" --no-minimize -q --report "$dir" >"$dir/console.txt" 2>&1
        kill "$sim" 2>/dev/null
        wait "$sim" 2>/dev/null
        ;;
    *)
        echo "way: sim, exec or pty" >&2
        exit 2
        ;;
    esac
    json="$dir/fuzz-device.json"
    if [ -s "$json" ]; then
        jq -r --arg f "$f" '[$f, (.findings | length), .runs, ([.findings[] | .signature | (.command + " " + .kind + (if .detail then " (" + .detail + ")" else "" end) + (if .cause then " after " + .cause else "" end) + (if .explanation then ": " + .explanation else "" end))] | join(" | ")), ((.not_reproduced // []) | length), ([(.not_reproduced // [])[] | .signature + " (" + (.reproduced | tostring) + "/" + (.replays | tostring) + ")"] | join(" | "))] | @tsv' "$json" >>"$tsv"
    else
        printf '%s\tERROR\t\t%s\n' "$f" "$(tail -1 "$dir/console.txt")" >>"$tsv"
    fi
    tail -1 "$tsv"
done
echo "# distribution (findings: faults): $(grep -v '^#' "$tsv" | cut -f2 | sort | uniq -c | awk '{printf "%s: %s, ", $2, $1}')" >>"$tsv"
echo "# not reproduced (candidates: faults): $(grep -v '^#' "$tsv" | cut -f5 | sort | uniq -c | awk '{printf "%s: %s, ", $2, $1}')" >>"$tsv"
tail -1 "$tsv"
