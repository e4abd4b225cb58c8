#!/usr/bin/env bash
# The README's first command: installs the dependencies, builds, starts rdmeshd on a free
# loopback port, meshes the bundled sample model through the Python client, writes the mesh and
# prints a summary, then stops the daemon.
#
#   scripts/demo.sh [MODEL] [rdmesh-py mesh options...]
#
# Environment: BUILD_DIR (default build), JOBS (parallel build jobs, default: all cores),
# OUT (default out/sample.msh).
set -euo pipefail
cd "$(dirname "$0")/.."

model=${1:-tests/data/nist_mbe_pmi_11.stp}
shift || true
build=${BUILD_DIR:-build}
out=${OUT:-out/sample.msh}
python=/usr/bin/python3

scripts/install-deps.sh
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
ninja -C "$build" -j"${JOBS:-$(nproc)}" rdmeshd rdmesh_python_stubs

port=$($python -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
mkdir -p "$(dirname "$out")"
log="$(dirname "$out")/rdmeshd.log"
"$build/bin/rdmeshd" --listen "127.0.0.1:$port" > "$log" 2>&1 &
daemon=$!
stop_daemon() {
  if kill -0 "$daemon" 2> /dev/null; then
    kill -TERM "$daemon"
    wait "$daemon" || true
  fi
}
trap stop_daemon EXIT

client=(clients/python/rdmesh-py --address "127.0.0.1:$port")
for _ in $(seq 100); do
  if [ "$("${client[@]}" health 2> /dev/null)" = SERVING ]; then break; fi
  if ! kill -0 "$daemon" 2> /dev/null; then cat "$log" >&2; exit 1; fi
  sleep 0.1
done
[ "$("${client[@]}" health)" = SERVING ]

summary=$("${client[@]}" mesh "$model" -o "$out" --json "$@")
$python - "$summary" "$port" << 'PY'
import json, sys
s = json.loads(sys.argv[1])
print()
print("rdmesh demo: rdmeshd on 127.0.0.1:%s, meshed through the Python client" % sys.argv[2])
print("  model       %s (%d faces: %d ok, %d failed)" % (s["model"], s["faces"], s["faces_ok"],
                                                         s["faces_failed"]))
print("  mesh        %d triangles, %d nodes, assembled through global node ids: %s"
      % (s["triangles"], s["nodes"], "watertight" if s["open_edges"] == 0
         else "%d open edges" % s["open_edges"]))
print("  deviation   %.4g estimated, %.4g asked (model units)" % (s["estimated_deviation"],
                                                                  s["requested_deviation"]))
print("  area        %.6g mesh vs %.6g exact" % (s["mesh_area"], s["exact_area"]))
print("  output      %s" % s["output"])
print("  seconds     %.2f (server %.2f)" % (s["seconds"], s["server_seconds"]))
PY
