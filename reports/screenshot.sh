#!/usr/bin/env bash
# Renders every kind of report page with headless Chromium into PNGs, so a person can look at
# them (and so a change to the pages is looked at, not only generated).
#
#   reports/screenshot.sh [OUT_DIR]        (default: target/screenshots)
#
# It builds gcl, makes one report of each kind against the simulator (conform against the
# fget-reversed, lfap-little-endian and prompt-no-space bugs, certify, fuzz device against fget-reversed, fuzz
# host and check-host with a small Python host that breaks the protocol), and renders each
# page twice: as it opens (the verdict, options and root causes) and with every <details>
# open (a copy of the page with every <details> open), and prints its height as it opens. It also renders the mcv-ignored conform
# page (a motion effect's window plot), a fuzz device run against the first one's findings as
# its --baseline (known apart from new), and the RealTime example program's --plot page.
# Chromium is installed with apt when missing. Environment: GCL_SHOT_HEIGHT (viewport height,
# default 2200), GCL_SHOT_BUILD (release, the default: the release build that is there, built
# only when there is none; rebuild: built anew, as cargo sees fit; or debug: no release build
# needed).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/screenshots}"
height="${GCL_SHOT_HEIGHT:-2200}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

browser=""
for b in chromium chromium-browser google-chrome; do
    if command -v "$b" >/dev/null 2>&1; then browser="$b"; break; fi
done
if [ -z "$browser" ]; then
    echo "installing chromium with apt"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium fonts-dejavu-core >/dev/null
    browser=chromium
fi

build="${GCL_SHOT_BUILD:-release}"
if [ "$build" = release ] && [ -x target/release/gcl ] && [ -x target/release/examples/realtime ]; then
    # A release build takes minutes: the one that is there is used, and said.
    echo "using the release build that is there: target/release/gcl ($(target/release/gcl --version)); GCL_SHOT_BUILD=rebuild builds it anew"
elif [ "$build" = release ] || [ "$build" = rebuild ]; then
    cargo build --release -q -p gcl-harness --bin gcl --example realtime
    build=release
else
    cargo build -q -p gcl-harness --bin gcl --example realtime
    build=debug
fi
gcl="$PWD/target/$build/gcl"
example="$PWD/target/$build/examples/realtime"
work="$out/reports"
rm -rf "$work"
mkdir -p "$work"

# A host that reads a few answers, then sends an LF-terminated line and never enters RealTime.
cat >"$work/host.py" <<'EOF'
import os, sys, time
fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY)
def ask(line, end=b"\r"):
    os.write(fd, line + end)
    buf = b""
    deadline = time.time() + 2
    while not buf.endswith(b"=> ") and time.time() < deadline:
        buf += os.read(fd, 256)
    return buf
ask(b"\x03", b"")
answer = ask(b"FGET DP")
values = answer.split(b"\n\r")[1].split()
print("positions", [int(v) for v in values])
os.write(fd, b"HI\n")
time.sleep(0.2)
EOF

set +e
"$gcl" conform --target sim --fault fget-reversed --quiet --report "$work/conform-fget-reversed" >/dev/null
"$gcl" conform --target sim --fault lfap-little-endian --quiet --report "$work/conform-lfap-little-endian" >/dev/null
"$gcl" conform --target sim --fault prompt-no-space --quiet --report "$work/conform-prompt-no-space" >/dev/null
"$gcl" conform --target sim --quiet --report "$work/conform-pass" >/dev/null
"$gcl" conform --target sim --fault mcv-ignored --quiet --report "$work/conform-mcv-ignored" >/dev/null
"$gcl" certify --target sim:seed --out "$work/certify" >/dev/null
"$gcl" fuzz device --target sim --fault fget-reversed --runs 300 --out "$work/fuzz-device-findings" \
    --report "$work/fuzz-device" >/dev/null 2>&1
"$gcl" fuzz device --target sim --fault fget-reversed --fault too-many-args-silent --runs 300 \
    --baseline "$work/fuzz-device-findings" --report "$work/fuzz-device-baseline" >/dev/null 2>&1
"$example" --target sim:seed --plot "$work/example-realtime/realtime.html" >/dev/null
"$gcl" fuzz host --runs 30 --timeout-hang 1s --out "$work/fuzz-host-findings" --report "$work/fuzz-host" \
    -- python3 "$work/host.py" '{port}' >/dev/null 2>&1
"$gcl" check-host --timeout-hang 1s --report "$work/check-host" -- python3 "$work/host.py" '{port}' >/dev/null 2>&1
set -e

shot() { # page.html name
    local page="$1" name="$2" profile
    for mode in closed open; do
        local url="file://$page"
        if [ "$mode" = open ]; then
            # Every <details> open: a copy of the page with the attribute set.
            sed 's/<details\([ >]\)/<details open\1/g' "$page" >"${page%.html}.open.html"
            url="file://${page%.html}.open.html"
        fi
        profile="$(mktemp -d)"
        "$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
            --disable-background-networking --disable-component-update --disable-sync \
            --user-data-dir="$profile" --hide-scrollbars --window-size="1280,$height" \
            --screenshot="$out/$name-$mode.png" "$url" >/dev/null 2>&1 || echo "chromium failed on $page" >&2
        rm -rf "$profile"
    done
    echo "$out/$name-{closed,open}.png  ($(wc -c <"$page") bytes of HTML, $(height "$page") px tall as it opens)"
}

height() { # page.html: its height in CSS pixels at 1280 px wide, <details> as they open
    local page="$1" copy profile
    copy="${page%.html}.height.html"
    sed 's#</body>#<script>document.body.dataset.height = document.documentElement.scrollHeight</script></body>#' \
        "$page" >"$copy"
    profile="$(mktemp -d)"
    "$browser" --headless --no-sandbox --disable-gpu --no-first-run --user-data-dir="$profile" \
        --window-size=1280,1000 --dump-dom "file://$copy" 2>/dev/null | grep -o 'data-height="[0-9]*"' | tr -dc 0-9
    rm -rf "$profile" "$copy"
}

shot "$work/conform-fget-reversed/report.html" conform-fget-reversed
shot "$work/conform-lfap-little-endian/report.html" conform-lfap-little-endian
shot "$work/conform-prompt-no-space/report.html" conform-prompt-no-space
shot "$work/conform-pass/report.html" conform-pass
shot "$work/conform-mcv-ignored/report.html" conform-mcv-ignored
shot "$work/certify/report.html" certify
shot "$work/fuzz-device/fuzz-device.html" fuzz-device
shot "$work/fuzz-device-baseline/fuzz-device.html" fuzz-device-baseline
shot "$work/example-realtime/realtime.html" example-realtime
shot "$work/fuzz-host/report.html" fuzz-host
shot "$work/check-host/report.html" check-host
