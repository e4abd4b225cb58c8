#!/usr/bin/env bash
# The README's second command: installs the dependencies, builds everything and runs every test
# (GoogleTest suites, the CLI and service pytest suites, the format check).
#
#   scripts/test.sh [ctest arguments...]
#
# Environment: BUILD_DIR (default build), JOBS (parallel build jobs, default: all cores).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build}

scripts/install-deps.sh
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
ninja -C "$build" -j"${JOBS:-$(nproc)}"

# Style: the C++ sources follow .clang-format.
files=$(git ls-files '*.cpp' '*.h' 2> /dev/null || find engine server clients tests bench -name '*.cpp' -o -name '*.h')
if [ -n "$files" ]; then
  clang-format --dry-run --Werror $files
fi

ctest --test-dir "$build" --output-on-failure --timeout 1500 "$@"
