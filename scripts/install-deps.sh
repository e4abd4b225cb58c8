#!/usr/bin/env bash
# Installs everything rdmesh needs to build, test and benchmark, from Debian 12 packages only.
# Used by the README's commands, by .ci/run and by docker/Dockerfile.
#
#   scripts/install-deps.sh            build + test + client dependencies (default)
#   scripts/install-deps.sh --runtime  only what a built rdmeshd and the Python client need to run
#   scripts/install-deps.sh --bench    also the benchmark peers (the gmsh program)
#
# The default set holds everything that scripts/test.sh builds, imports or runs: the Python
# modules the pytest suites import (gmsh, meshio, numpy, grpc, protobuf, matplotlib), the programs
# they call (openssl, nginx, protoc with the Python gRPC plugin, FreeCAD's freecadcmd, node and
# npm for the glTF validator and three.js, whose npm packages tests/cli installs under the build
# tree on first use, and chromium for the viewer page, whose npm packages (clients/web's
# package.json) tests/web installs under the build tree) and the sanitizer runtimes of the
# ASan/UBSan and TSan builds (gcc's, pulled in by build-essential).
set -euo pipefail

mode=${1:-build}

runtime_pkgs=(
  libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev
  libocct-foundation-dev libocct-ocaf-dev libocct-visualization-dev
  libgrpc++-dev libprotobuf-dev libspdlog-dev libtbb-dev libmimalloc-dev
  # meshoptimizer 0.18: the compressed .glb (rdmesh mesh --compress, engine/src/writers).
  libmeshoptimizer-dev
  python3-grpcio python3-protobuf python3-numpy python3-meshio python3-tqdm
)
build_pkgs=(
  build-essential cmake ninja-build ccache pkg-config git
  protobuf-compiler protobuf-compiler-grpc
  libcgal-dev libgmp-dev libmpfr-dev
  libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev python3-pytest
  clang-format
  # The bounded libFuzzer run of scripts/test.sh (scripts/fuzz_smoke.sh): clang and its runtimes,
  # gdb to read where a crash inside OCCT happened.
  clang libclang-rt-14-dev gdb
  # Test-time imports and programs (tests/cli, tests/python; python3-yaml reads docker/ and
  # deploy/ in test_deploy_env.py; nginx for test_routing.py, the
  # gRPC balancer in front of several rdmeshd, run as the current user).
  python3-gmsh python3-yaml openssl nginx
  # rdmesh-py view draws with matplotlib (Agg, no display); tests/python/test_freecad.py runs
  # the FreeCAD client (clients/freecad) in Debian's FreeCAD 0.20 (freecadcmd, headless).
  python3-matplotlib freecad
  # tests/web drives the viewer page (clients/web) in headless Chromium.
  chromium
)
# Programs the tests need that may come from elsewhere: the machine's own Node.js build ships
# npm and conflicts with Debian's npm package, so these are installed only when the command is
# missing (command:package).
build_cmds=(node:nodejs npm:npm)
bench_pkgs=(gmsh)

cmds=()
case "$mode" in
  --runtime) pkgs=("${runtime_pkgs[@]}") ;;
  --bench) pkgs=("${runtime_pkgs[@]}" "${build_pkgs[@]}" "${bench_pkgs[@]}"); cmds=("${build_cmds[@]}") ;;
  build|--build) pkgs=("${runtime_pkgs[@]}" "${build_pkgs[@]}"); cmds=("${build_cmds[@]}") ;;
  *) echo "usage: $0 [--build|--runtime|--bench]" >&2; exit 2 ;;
esac

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
for c in "${cmds[@]}"; do
  command -v "${c%%:*}" > /dev/null || missing+=("${c#*:}")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
