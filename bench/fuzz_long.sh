#!/usr/bin/env bash
# A long libFuzzer run of the STEP reader: scripts/fuzz_smoke.sh's build and seeds plus the corpus
# models up to 64 KiB, no run limit, and it goes on after a crash, hang or out-of-memory
# (libFuzzer -fork=1 -ignore_*), then counts what it found. The inputs are in
# build-fuzz/artifacts/ (crash-*, timeout-*, oom-*, leak-*); minimise one with
#   build-fuzz/bin/step_fuzzer -minimize_crash=1 -runs=2000 FILE
#   bench/fuzz_long.sh [MINUTES]      default 30
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
minutes="${1:-30}"
build="${RDMESH_FUZZ_BUILD_DIR:-$top/build-fuzz}"
mkdir -p "$build/artifacts"
stamp="$build/artifacts/.long_run_start"
touch "$stamp"

RDMESH_FUZZ_CORPUS_SEEDS=1 RDMESH_FUZZ_ARGS="-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1" \
  "$top/scripts/fuzz_smoke.sh" -1 "$((minutes * 60))" 2>&1 |
  tee "$build/fuzz_long.log" | grep -E '^#[0-9]+.*(pulse|DONE)|^INFO: fuzzed|^fuzz_smoke' || true

echo "fuzz_long: $minutes min; new inputs in $build/artifacts/:"
for kind in crash timeout oom leak; do
  printf '  %-8s %d\n' "$kind" "$(find "$build/artifacts" -name "$kind-*" -newer "$stamp" | wc -l)"
done
found=$(find "$build/artifacts" -name '*-*' -newer "$stamp" | wc -l)
grep -E 'stat::number_of_executed_units|exec/s' "$build/fuzz_long.log" | tail -n 2 || true
[ "$found" -eq 0 ]
