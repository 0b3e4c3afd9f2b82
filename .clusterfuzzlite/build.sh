#!/usr/bin/env bash
# Builds gcl's cargo-fuzz targets for ClusterFuzzLite / OSS-Fuzz: each target's binary, its
# seed corpus (fuzz/seeds/<target>, known crashes left out) and its dictionary go to $OUT.
# In the build image $SRC/gcl is the checkout; .ci/run sets GCL_SRC, SRC and OUT and runs this
# without Docker. The cargo-fuzz build is the one fuzz/run-ci.sh makes, so in .ci/run it is
# already up to date.
set -euo pipefail
src=${GCL_SRC:-$SRC/gcl}
out=${OUT:?OUT is where the fuzzers go}
sanitizer=${SANITIZER:-address}
cd "$src/fuzz"
# cargo-fuzz passes -Z flags to rustc; RUSTC_BOOTSTRAP lets a stable toolchain take them (the
# build image's nightly does not need it).
export RUSTC_BOOTSTRAP=1
if [[ "$sanitizer" == "none" ]]; then flags=(); else flags=(--sanitizer "$sanitizer"); fi
cargo fuzz build "${flags[@]}"
triple=$(rustc -vV | sed -n 's/^host: //p')
# fuzz/ is a member of the workspace: its binaries land in the workspace's target folder.
built="${CARGO_TARGET_DIR:-$src/target}/$triple/release"
targets=$(sed -n 's/^name = "\(.*\)"$/\1/p' Cargo.toml | grep -v '^gcl-fuzz$')
for t in $targets; do
    cp "$built/$t" "$out/$t"
    mapfile -t seeds < <(find "seeds/$t" -maxdepth 1 -type f ! -name 'crash-*' 2>/dev/null | sort)
    if ((${#seeds[@]})); then
        python3 -m zipfile -c "$out/${t}_seed_corpus.zip" "${seeds[@]}"
    fi
    if [[ -f "seeds/dicts/$t.dict" ]]; then cp "seeds/dicts/$t.dict" "$out/$t.dict"; fi
done
echo "build.sh: $(echo $targets | wc -w) fuzzers in $out"
