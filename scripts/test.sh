#!/usr/bin/env bash
# The README's second command: installs the dependencies, builds everything and runs every test
# (GoogleTest suites, the CLI and service pytest suites, the format check).
#
#   scripts/test.sh [ctest arguments...]
#
# Environment: BUILD_DIR (default build), JOBS (parallel build jobs, default: all cores),
# RDMESH_SANITIZERS=0 skips the sanitizer builds (CI runs them), RDMESH_TSAN=0 skips only TSan,
# RDMESH_FUZZ_SMOKE=0 skips the bounded fuzz run (CI runs it).
#
# After the Release tests, sanitizer builds of the engine and server tests run (gcc's runtimes;
# options and suppressions in scripts/sanitizers/, see its README.md):
#   build-asan/  ASan + UBSan: engine_tests and server_tests, whole (always, unless skipped)
#   build-tsan/  TSan: the threaded tests (engine at 1 and 2 threads, its parallel loops, concurrent
#                loads and jobs); under TSan the engine's loops run on std::threads (README there)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build}
jobs=${JOBS:-$(nproc)}

scripts/install-deps.sh
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
ninja -C "$build" -j"$jobs"

# Style: the C++ sources follow .clang-format.
files=$(git ls-files '*.cpp' '*.h' 2> /dev/null || find engine server clients tests bench -name '*.cpp' -o -name '*.h')
if [ -n "$files" ]; then
  clang-format --dry-run --Werror $files
fi

ctest --test-dir "$build" --output-on-failure --timeout 1500 "$@"

# A bounded libFuzzer run on the model reader (clang, ASan+UBSan; fixed seeds, build-fuzz/):
# 2000 inputs, at most 150 s. Crashes inside OCCT that the CLI survives are counted, not failed.
if [ "${RDMESH_FUZZ_SMOKE:-1}" != 0 ]; then
  RDMESH_CLI="$PWD/$build/bin/rdmesh" bash scripts/fuzz_smoke.sh 2000 150
fi

if [ "${RDMESH_SANITIZERS:-1}" = 0 ]; then
  echo "test.sh: sanitizer builds skipped (RDMESH_SANITIZERS=0)"
  exit 0
fi
sanitizers=$PWD/scripts/sanitizers

# Builds the engine and server tests with -fsanitize=$2 in directory $1, at -O1 (the usual
# sanitizer level: it compiles much faster than -O3, CGAL's templates above all).
sanitizer_build() {
  cmake -S . -B "$1" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG" \
    -DRDMESH_SANITIZE="$2" -DRDMESH_BUILD_BENCH=OFF > /dev/null
  ninja -C "$1" -j"$jobs" engine_tests server_tests
}

# Runs one test binary with a time limit; any sanitizer report fails it (exitcode / halt).
run_sanitized() {
  local name=$1
  shift
  echo "test.sh: $name"
  timeout --signal=KILL 1800 "$@" --gtest_brief=1
}

# ASan + UBSan: every engine and server test. Leaks are checked; the suppressions name only
# libraries (OCCT, TBB, gRPC/protobuf), never rdmesh code.
sanitizer_build build-asan address
# fast_unwind_on_malloc=0: full allocation stacks through OCCT, for lsan.supp to match.
export ASAN_OPTIONS="detect_leaks=1:fast_unwind_on_malloc=0:strict_init_order=1:check_initialization_order=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$sanitizers/ubsan.supp"
export LSAN_OPTIONS="suppressions=$sanitizers/lsan.supp:print_suppressions=0"
# Not StepTranslateTest.CorpusMatchesOcct: the translator against OCCT's reader on all 51 corpus
# models takes over 2 minutes in Release and past the 30-minute limit under ASan; the Release run
# covers it, and StepTranslateTest.BundledFilesMatchOcct runs the same code on the bundled models.
run_sanitized "ASan+UBSan engine_tests" build-asan/bin/engine_tests \
  --gtest_filter='-StepTranslateTest.CorpusMatchesOcct'
run_sanitized "ASan+UBSan server_tests" build-asan/bin/server_tests
unset ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS

if [ "${RDMESH_TSAN:-1}" = 0 ]; then
  echo "test.sh: ASan+UBSan build passed (TSan skipped: RDMESH_TSAN=0)"
  exit 0
fi

# TSan: the tests that run threads. Engine: the corpus at 1 and 2 threads, the pipeline and
# deadline tests (default threads = all cores), concurrent model loads, the context.
sanitizer_build build-tsan thread
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$sanitizers/tsan.supp"
run_sanitized "TSan engine_tests (threaded)" build-tsan/bin/engine_tests \
  --gtest_filter='Data/CorpusTest.*:PipelineTest.*:Deadline/*:ModelTest.ConcurrentLoadsAgree:ContextTest.*:ParallelRunnerTest.*'
run_sanitized "TSan server_tests" build-tsan/bin/server_tests
unset TSAN_OPTIONS
echo "test.sh: sanitizer builds passed"
