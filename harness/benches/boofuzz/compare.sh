#!/usr/bin/env bash
# gcl fuzz device and boofuzz side by side (issue 11): the same `gcl sim --pty --time fast
# --baud 38400`, the same time each. First the unmutated sim: for each tool cases/s, bytes/s
# each way and both ways ÷ the line rate, mean bytes per case, lines sent per second; then
# the ceiling the line puts on gcl's cases/s ÷ boofuzz's; then boofuzz in two other setups
# (see gcl_request.py); then three faulty sims (what each finds in the same time).
#
# Usage: harness/benches/boofuzz/compare.sh [SECONDS]   (default 30 s a run; 12 runs)
# GCL=path/to/gcl picks the binary (default: a release build of this tree, built first).
# boofuzz 0.4.2 is installed from PyPI into target/boofuzz-venv (nothing global changes).
# Not run in CI.
set -euo pipefail
T=${1:-30}
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
cd "$ROOT"
if [ -z "${GCL:-}" ]; then
    cargo build -q --release --bin gcl
    GCL=target/release/gcl
fi
VENV=target/boofuzz-venv
if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c "import boofuzz" 2>/dev/null; then
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q "boofuzz==0.4.2"
fi
WORK=target/boofuzz-work
mkdir -p "$WORK"
FAULTS=(fget-reversed read-only-status lfap-little-endian)
BAUD=38400
LINE=$((BAUD / 10)) # bytes per second each way (8N1: 10 bits a byte)

SIM=
stop_sim() { if [ -n "$SIM" ]; then kill "$SIM" 2>/dev/null || true; wait "$SIM" 2>/dev/null || true; SIM=; fi; }
trap stop_sim EXIT
# start_sim TIME [FAULT]: a fresh sim on a pty; sets SIM and PTY.
start_sim() {
    local args=(sim --pty --time "$1" --baud "$BAUD")
    if [ -n "${2:-}" ]; then args+=(--fault "$2"); fi
    rm -f "$WORK/sim.out"
    "$GCL" "${args[@]}" > "$WORK/sim.out" 2> "$WORK/sim.err" &
    SIM=$!
    for _ in $(seq 100); do [ -s "$WORK/sim.out" ] && break; sleep 0.05; done
    PTY=$(head -n 1 "$WORK/sim.out")
}
run_gcl() { # FAULT-LABEL
    rm -rf "$WORK/gcl-$1"
    # --no abort-timing: under --time fast a motion ends at once, so ^C cannot land mid-motion.
    "$GCL" fuzz device --target "serial:$PTY?baud=$BAUD" --duration "${T}s" --seed 1 \
        --no abort-timing -q --out "$WORK/gcl-$1" || true
}
run_boofuzz() { # SETUP
    (cd "$WORK" && rm -f boofuzz-results.db && "../../$VENV/bin/python" "../../harness/benches/boofuzz/gcl_request.py" "$PTY" "$BAUD" "$T" "$1")
}
# The figures of one run as `cases_per_s sent_per_s received_per_s lines_per_s`.
gcl_figures() {
    sed -n 's/.* \([0-9.]*\) cases\/s, [0-9]* wire bytes\/s (\([0-9]*\) sent, \([0-9]*\) received), \([0-9.]*\) lines sent\/s.*/\1 \2 \3 \4/p' | head -n 1
}
boofuzz_figures() {
    awk '/^boofuzz/ { for (i = 2; i <= NF; i++) { split($i, kv, "="); f[kv[1]] = kv[2] }
        s = f["seconds"]; printf "%s %.0f %.0f %.1f\n", f["cases_per_s"], f["sent"] / s, f["received"] / s, f["lines"] / s }'
}
# row NAME FIGURES: one line of the table.
row() {
    echo "$2" | awk -v name="$1" -v line="$LINE" '{ c = $1; s = $2; r = $3
        printf "%-22s %8.2f %7.0f = %4.2f %7.0f = %4.2f %6.2f %9.1f %9.1f %8.1f\n",
            name, c, s, s / line, r, r / line, (s + r) / line, (c > 0 ? s / c : 0), (c > 0 ? r / c : 0), $4 }'
    echo "$2" | awk -v line="$LINE" -v name="$1" '$2 > line { printf "  (%s wrote faster than the line carries: the excess waits in the pty, so its receives end at earlier prompts)\n", name }'
}
header() {
    printf "%-22s %8s %14s %14s %6s %9s %9s %8s\n" "" "cases/s" "sent B/s ÷line" "recv B/s ÷line" \
        "both÷" "B/case ->" "B/case <-" "lines/s"
}
findings_of() { grep -o '^  .* ([0-9]* actions)' | sed 's/^  //; s/ ([0-9]* actions)//' | paste -sd ';' - | sed 's/^$/none/'; }

echo "== unmutated sim (gcl sim --pty --time fast --baud $BAUD), ${T} s each; line rate $LINE B/s each way"
start_sim fast; G=$(run_gcl none); stop_sim
start_sim fast; B=$(run_boofuzz best); stop_sim
echo "gcl:     $G"
echo "$B"
GF=$(echo "$G" | gcl_figures)
BF=$(echo "$B" | boofuzz_figures)
header
row "gcl fuzz device" "$GF"
row "boofuzz (best setup)" "$BF"
echo "$GF $BF" | awk -v line="$LINE" '{ gc = $1; gs = $2 / gc; gr = $3 / gc; bc = $5
    busiest = (gs > gr ? gs : gr)
    printf "gcl cases/s / boofuzz cases/s = %.2f (aim: at least 5)\n", gc / bc
    printf "ceiling from the line: a gcl case moves %.0f B to the hand and %.0f B back; each way carries at most %d B/s,\n", gs, gr, line
    printf "  so gcl cases/s <= %d / %.0f = %.1f, and gcl/boofuzz <= %.1f / %.2f = %.3f", line, busiest, line / busiest, line / busiest, bc, line / busiest / bc
    printf " (%.3f if both ways shared the %d B/s of one direction)\n", line / (gs + gr) / bc, line
    need = 5 * bc
    printf "  aim of 5 with boofuzz at %.1f cases/s needs %.0f gcl cases/s: at most %.0f B a case each way; %s\n",
        bc, need, line / need, (line / busiest >= need ? "reachable" : "NOT reachable at this case size")
}'

echo "== boofuzz in other setups on the unmutated sim (see gcl_request.py), ${T} s each"
for S in reset fresh plain; do
    start_sim fast; B=$(run_boofuzz "$S"); stop_sim
    echo "$B"
    row "boofuzz ($S)" "$(echo "$B" | boofuzz_figures)"
done
start_sim real; B=$(run_boofuzz best); stop_sim
echo "$B (sim --time real)"
row "boofuzz (best, real)" "$(echo "$B" | boofuzz_figures)"

for F in "${FAULTS[@]}"; do
    echo "== --fault $F, ${T} s each"
    start_sim fast "$F"; G=$(run_gcl "$F"); stop_sim
    start_sim fast "$F"; B=$(run_boofuzz best); stop_sim
    echo "gcl:     $G"
    echo "$B"
    echo "found: gcl: $(echo "$G" | findings_of); boofuzz: $(echo "$B" | sed -n 's/.*failures=\([^ ]*\).*/\1/p')"
done
