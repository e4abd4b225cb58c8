#!/usr/bin/env bash
# A long libFuzzer run of the STEP reader: scripts/fuzz_smoke.sh's build, loop and checks, plus the
# corpus models up to 64 KiB as seeds, with no run limit. Crashes inside OCCT are kept in
# build-fuzz/artifacts/occt-crash-*.step and the run goes on (next seed); it stops at the first
# other finding (a crash in rdmesh code, a sanitizer report, a leak, a -timeout hang, an OOM),
# whose input is in build-fuzz/artifacts/. Minimise a find with
#   build-fuzz/bin/step_fuzzer -minimize_crash=1 -runs=2000 FILE
# (for OCCT's stack overflows, which kill the process before libFuzzer sees them, remove lines by
# hand while `RDMESH_NO_FORK=1 build/bin/rdmesh info FILE` still dies).
#   bench/robustness/fuzz_long.sh [MINUTES]      default 30
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
minutes="${1:-30}"
build="${RDMESH_FUZZ_BUILD_DIR:-$top/build-fuzz}"
mkdir -p "$build/artifacts"
stamp="$build/artifacts/.long_run_start"
touch "$stamp"

status=0
RDMESH_FUZZ_CORPUS_SEEDS=1 RDMESH_FUZZ_MAX_ROUNDS=100000 \
  "$top/scripts/fuzz_smoke.sh" -1 "$((minutes * 60))" > "$build/fuzz_long.log" 2>&1 || status=$?
grep -aE '^fuzz_smoke' "$build/fuzz_long.log" | sed 's/(kept [^)]*)//' || true

echo "fuzz_long: $minutes min; new inputs in $build/artifacts/:"
printf '  %-11s %d\n' "occt-crash" "$(find "$build/artifacts" -name 'occt-crash-*' -newer "$stamp" | wc -l)"
for kind in crash timeout oom leak; do
  printf '  %-11s %d\n' "$kind" "$(find "$build/artifacts" -name "$kind-*" -newer "$stamp" | wc -l)"
done
exit "$status"
