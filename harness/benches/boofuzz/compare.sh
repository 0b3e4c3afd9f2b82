#!/usr/bin/env bash
# gcl fuzz device and boofuzz side by side (issue 11): the same `gcl sim --pty --time fast
# --baud 38400`, the same time each, first on the unmutated sim (cases/s, wire bytes/s, and
# gcl's cases/s ÷ boofuzz's), then on three faulty sims (what each finds).
#
# Usage: harness/benches/boofuzz/compare.sh [SECONDS]   (default 30 s a run; 8 runs)
# GCL=path/to/gcl picks the binary (default: target/release/gcl, built if missing).
# boofuzz 0.4.2 is installed from PyPI into target/boofuzz-venv (nothing global changes).
# Not run in CI.
set -euo pipefail
T=${1:-30}
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
cd "$ROOT"
GCL=${GCL:-target/release/gcl}
if [ ! -x "$GCL" ]; then cargo build -q --release --bin gcl; fi
VENV=target/boofuzz-venv
if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c "import boofuzz" 2>/dev/null; then
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q "boofuzz==0.4.2"
fi
WORK=target/boofuzz-work
mkdir -p "$WORK"
FAULTS=(fget-reversed read-only-status lfap-little-endian)

SIM=
stop_sim() { if [ -n "$SIM" ]; then kill "$SIM" 2>/dev/null || true; wait "$SIM" 2>/dev/null || true; SIM=; fi; }
trap stop_sim EXIT
# start_sim [FAULT]: a fresh sim on a pty; sets SIM and PTY.
start_sim() {
    local args=(sim --pty --time fast --baud 38400)
    if [ -n "${1:-}" ]; then args+=(--fault "$1"); fi
    rm -f "$WORK/sim.out"
    "$GCL" "${args[@]}" > "$WORK/sim.out" 2> "$WORK/sim.err" &
    SIM=$!
    for _ in $(seq 100); do [ -s "$WORK/sim.out" ] && break; sleep 0.05; done
    PTY=$(head -n 1 "$WORK/sim.out")
}
run_gcl() { # FAULT-LABEL
    rm -rf "$WORK/gcl-$1"
    # --no abort-timing: under --time fast a motion ends at once, so ^C cannot land mid-motion.
    "$GCL" fuzz device --target "serial:$PTY?baud=38400" --duration "${T}s" --seed 1 \
        --no abort-timing -q --out "$WORK/gcl-$1" || true
}
run_boofuzz() {
    (cd "$WORK" && rm -f boofuzz-results.db && "../../$VENV/bin/python" "../../harness/benches/boofuzz/gcl_request.py" "$PTY" 38400 "$T")
}
cases_per_s() { grep -o '[0-9.]* cases/s' | head -n 1 | cut -d' ' -f1; }

echo "== unmutated sim, ${T} s each"
start_sim; G=$(run_gcl none); stop_sim
start_sim; B=$(run_boofuzz); stop_sim
echo "gcl:     $G"
echo "$B"
awk -v g="$(echo "$G" | cases_per_s)" -v b="$(echo "$B" | cases_per_s)" \
    'BEGIN { printf "gcl cases/s / boofuzz cases/s = %.2f (aim: at least 5)\n", g / b }'
for F in "${FAULTS[@]}"; do
    echo "== --fault $F, ${T} s each"
    start_sim "$F"; G=$(run_gcl "$F"); stop_sim
    start_sim "$F"; B=$(run_boofuzz); stop_sim
    echo "gcl:     $G"
    echo "$B"
done
