#!/usr/bin/env bash
# A bounded libFuzzer run of the STEP reader (fuzz/step_fuzzer), for CI: configures a clang
# ASan+UBSan+libFuzzer build in build-fuzz/, builds only the fuzz target, and runs it with fixed
# seeds (1, 2, ...) from the tests/data models.
#   scripts/fuzz_smoke.sh [RUNS] [MAX_SECONDS]      defaults: 600 runs, at most 120 s
#
# Crashes inside OCCT. The engine installs OCCT's signal handlers (OSD::SetSignal, so that
# OCC_CATCH_SIGNALS turns faults into exceptions). They replace libFuzzer's, so a fault that OCCT
# cannot turn into an exception (a stack overflow in its STEP reader) kills the fuzzer with no
# report and no saved input. The target writes each input to a file first
# (RDMESH_FUZZ_LAST_INPUT), and when the fuzzer dies by a signal this script replays that input
# under gdb and reads the faulting frame:
#   - inside OCCT's libraries (libTK*): a crash that rdmesh isolates (the CLI's child process, the
#     daemon's workers). The script checks that the CLI survives it (`rdmesh info` ends with a
#     documented exit code, 3 and "the STEP reader crashed" where the crash reproduces), keeps the input as build-fuzz/artifacts/occt-crash-<sha1>.step, and restarts the
#     fuzzer with the next seed and the corpus found so far. Add such finds to tests/data/fuzz.
#   - anywhere else: the run fails.
# It also fails on every libFuzzer report (ASan/UBSan error, leak, -timeout, out-of-memory, a
# trap in the target); the input is left in build-fuzz/artifacts/.
#
# The CLI is ${RDMESH_CLI:-build/bin/rdmesh} (scripts/test.sh builds it first).
# RDMESH_FUZZ_ARGS adds libFuzzer flags; RDMESH_FUZZ_CORPUS_SEEDS=1 adds the corpus models
# (bench/robustness/fuzz_long.sh); RDMESH_FUZZ_BUILD_DIR moves the build.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
build="${RDMESH_FUZZ_BUILD_DIR:-$top/build-fuzz}"
runs="${1:-600}"
seconds="${2:-120}"
cli="${RDMESH_CLI:-$top/build/bin/rdmesh}"
max_rounds="${RDMESH_FUZZ_MAX_ROUNDS:-40}"

if [ ! -x "$cli" ]; then
  echo "fuzz_smoke: $cli is missing: build the project first (scripts/test.sh does)" >&2
  exit 2
fi
command -v gdb > /dev/null || { echo "fuzz_smoke: gdb is missing (scripts/install-deps.sh)" >&2; exit 2; }

cmake -S "$top" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DRDMESH_FUZZ=ON -DRDMESH_BUILD_TESTS=OFF \
  -DRDMESH_BUILD_SERVER=OFF -DRDMESH_BUILD_BENCH=OFF > /dev/null
ninja -C "$build" -j2 step_fuzzer

# The seeds: the bundled models and the regression cases that end quickly (not the hangs); with
# RDMESH_FUZZ_CORPUS_SEEDS=1 also the corpus models (../shared/corpus) no longer than -max_len.
max_len=65536
work="$build/fuzz_work"
artifacts="$build/artifacts"
rm -rf "$work"
mkdir -p "$work/corpus" "$work/seeds" "$artifacts"
cp "$top"/tests/data/*.step "$top"/tests/data/*.stp "$work/seeds/"
cp "$top"/tests/data/fuzz/crash_*.step "$work/seeds/" 2> /dev/null || true
if [ "${RDMESH_FUZZ_CORPUS_SEEDS:-0}" = 1 ] && [ -d "$top/../shared/corpus" ]; then
  find "$top/../shared/corpus" -name '*.st*p' -size -"$((max_len + 1))"c -exec cp {} "$work/seeds/" \;
fi

# "occt" when the innermost frame of the fatal signal is in one of OCCT's libraries, else the
# frame (or "none" when the input does not crash on its own).
fault_frame() {
  local gdb_args=() i attempt out frame
  for i in $(seq 40); do gdb_args+=(-ex 'bt 1' -ex continue); done
  for attempt in 1 2 3; do
    out=$(timeout 300 gdb -q -batch -ex 'set pagination off' -ex run "${gdb_args[@]}" \
      --args "$build/bin/step_fuzzer" -runs=1 "$1" 2>&1 || true)
    grep -qE 'Program terminated with signal|received signal SIG' <<< "$out" && break
  done
  frame=$(grep -E '^#0 ' <<< "$out" | tail -n 1 || true)
  if [ -z "$frame" ]; then
    echo none
  elif grep -qE 'from (/usr)?/lib/x86_64-linux-gnu/libTK[A-Za-z0-9]*\.so' <<< "$frame"; then
    echo "occt ${frame#*in }"
  else
    echo "$frame"
  fi
}

export LSAN_OPTIONS="suppressions=$top/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
start=$(date +%s)
done_runs=0
occt_crashes=0
round=0
status=0
while :; do
  round=$((round + 1))
  left_s=$((seconds - ($(date +%s) - start)))
  left_runs=-1
  [ "$runs" -ge 0 ] && left_runs=$((runs - done_runs))
  if [ "$left_s" -le 0 ] || [ "$left_runs" -eq 0 ]; then break; fi
  log="$work/round_$round.log"
  rc=0
  RDMESH_FUZZ_LAST_INPUT="$work/last_input" "$build/bin/step_fuzzer" -seed="$round" \
    -runs="$left_runs" -max_total_time="$left_s" -max_len="$max_len" -timeout=30 \
    -rss_limit_mb=4096 -print_final_stats=1 -dict="$top/fuzz/step.dict" \
    -artifact_prefix="$artifacts/" ${RDMESH_FUZZ_ARGS:-} "$work/corpus" "$work/seeds" \
    > "$log" 2>&1 || rc=$?
  n=$(grep -aoE '^#[0-9]+' "$log" | tail -n 1 | tr -d '#' || true)
  done_runs=$((done_runs + ${n:-0}))
  if [ "$rc" -eq 0 ]; then break; fi
  if [ "$rc" -le 128 ] || grep -aqE '==ERROR|deadly signal|ALARM|out-of-memory' "$log"; then
    echo "fuzz_smoke: the fuzzer reported a problem (exit $rc), round $round, seed $round:" >&2
    grep -aE -A40 '==ERROR|deadly signal|ALARM|out-of-memory' "$log" | head -n 60 >&2 || tail -n 40 "$log" >&2
    status=1
    break
  fi
  # Died by a signal without a report: the input is in last_input.
  sha=$(sha1sum "$work/last_input" | cut -c1-40)
  kept="$artifacts/occt-crash-$sha.step"
  cp "$work/last_input" "$kept"
  rm -f "$work/corpus/$sha"  # never start the next round on it
  frame=$(fault_frame "$kept")
  if [[ "$frame" != occt* ]]; then
    echo "fuzz_smoke: the fuzzer died by signal $((rc - 128)) outside OCCT, round $round:" >&2
    echo "  input $kept; faulting frame: $frame" >&2
    mv "$kept" "$artifacts/crash-$sha.step"
    status=1
    break
  fi
  cli_rc=0
  cli_err=$("$cli" info "$kept" 2>&1 > /dev/null) || cli_rc=$?
  if [ "$cli_rc" -ge 128 ] || [ "$cli_rc" -eq 2 ] || [ "$cli_rc" -gt 5 ]; then
    echo "fuzz_smoke: OCCT crashed (${frame#occt }) on $kept, and the CLI did not end with a" \
      "documented exit code (got $cli_rc): $cli_err" >&2
    status=1
    break
  fi
  occt_crashes=$((occt_crashes + 1))
  echo "fuzz_smoke: round $round: OCCT crashed in ${frame#occt } (kept $kept);" \
    "rdmesh info: exit $cli_rc, ${cli_err:-no message}"
  if [ "$round" -ge "$max_rounds" ]; then
    echo "fuzz_smoke: stopping after $round rounds" >&2
    break
  fi
done
echo "fuzz_smoke: $done_runs runs in $round round(s), $(($(date +%s) - start)) s;" \
  "$occt_crashes crash(es) inside OCCT, each survived by the CLI"
exit "$status"
