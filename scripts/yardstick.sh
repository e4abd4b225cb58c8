#!/bin/sh
# Prints the directory of a built copy of the shared yardstick (meshbench, anchors.py, sweep.py).
# The shared yardstick may sit on a read-only mount, so it is copied to a writable directory,
# ${RDMESH_YARDSTICK_DIR:-build/yardstick}, and built there with its own build.sh. A copy that is
# already up to date is reused.
set -e
repo=$(cd "$(dirname "$0")/.." && pwd)
src=${RDMESH_SHARED:-$repo/../shared}/yardstick
dest=${RDMESH_YARDSTICK_DIR:-$repo/build/yardstick}
[ -f "$src/meshbench.cpp" ] || { echo "yardstick.sh: no yardstick at $src" >&2; exit 1; }
mkdir -p "$dest"
for f in "$src"/*; do
  name=$(basename "$f")
  # -p keeps the source's times, so build.sh rebuilds only when meshbench.cpp is newer.
  if [ ! -e "$dest/$name" ] || [ "$f" -nt "$dest/$name" ] || [ -d "$f" ]; then
    cp -pR "$f" "$dest/"
  fi
done
chmod -R u+w "$dest"
sh "$dest/build.sh" >"$dest/build.log" 2>&1 || { cat "$dest/build.log" >&2; exit 1; }
echo "$dest"
