"""Fixtures for the rdmesh CLI tests: the binary, models, and the independent checkers."""

import json
import os
import pathlib
import subprocess

import pytest

GLTF_VALIDATE_JS = r"""
const validator = require('gltf-validator');
const fs = require('fs');
const bytes = new Uint8Array(fs.readFileSync(process.argv[2]));
validator.validateBytes(bytes, {maxIssues: 100}).then((report) => {
  console.log(JSON.stringify({
    errors: report.issues.numErrors,
    warnings: report.issues.numWarnings,
    triangles: report.info.totalTriangleCount,
    messages: report.issues.messages.slice(0, 10),
  }));
}).catch((error) => { console.error(String(error)); process.exit(1); });
"""


def _env_path(name):
    value = os.environ.get(name)
    assert value, f"{name} is not set (run these tests through ctest)"
    return pathlib.Path(value)


@pytest.fixture(scope="session")
def cli():
    path = _env_path("RDMESH_CLI")
    assert path.is_file(), f"no rdmesh binary at {path}"
    return path


@pytest.fixture(scope="session")
def data_dir():
    return _env_path("RDMESH_TEST_DATA")


@pytest.fixture(scope="session")
def shared_dir():
    return _env_path("RDMESH_SHARED_DIR")


class Run:
    """The outcome of one rdmesh invocation."""

    def __init__(self, completed):
        self.code = completed.returncode
        self.stdout = completed.stdout
        self.stderr = completed.stderr

    @property
    def json(self):
        lines = [line for line in self.stdout.splitlines() if line.strip()]
        assert lines, f"no stdout; stderr: {self.stderr}"
        return json.loads(lines[-1])


@pytest.fixture(scope="session")
def run(cli):
    def run_cli(*args, timeout=600):
        completed = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True,
                                   timeout=timeout)
        return Run(completed)

    return run_cli


def _node_script(package, name, source):
    """A function running the node script `source` (saved as `name` in the build tree's
    node_tools directory, where the npm `package` is installed on first use) on a path and
    returning its JSON output."""
    node_dir = _env_path("RDMESH_NODE_DIR")
    if not (node_dir / "node_modules" / package).is_dir():
        node_dir.mkdir(parents=True, exist_ok=True)
        subprocess.run(["npm", "install", "--prefix", str(node_dir), "--no-audit", "--no-fund",
                        package], check=True, capture_output=True, timeout=600)
    script = node_dir / name
    script.write_text(source)

    def run_script(path):
        completed = subprocess.run(["node", str(script), str(path)], capture_output=True,
                                   text=True, timeout=300, cwd=node_dir)
        assert completed.returncode == 0, completed.stderr
        return json.loads(completed.stdout)

    return run_script


@pytest.fixture(scope="session")
def gltf_validate():
    """Validates a .glb with the Khronos glTF validator (npm gltf-validator, installed on first
    use under the build tree)."""
    return _node_script("gltf-validator", "validate_gltf.js", GLTF_VALIDATE_JS)


@pytest.fixture(scope="session")
def meshbench(shared_dir):
    """The independent yardstick scorer: `meshbench eval MODEL MESH.msh` -> dict."""
    # scripts/yardstick.sh builds a copy in a writable place: the shared one may be read-only.
    env = dict(os.environ, RDMESH_SHARED=str(shared_dir))
    script = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "yardstick.sh"
    built = subprocess.run(["sh", str(script)], env=env, capture_output=True, text=True,
                           timeout=900)
    assert built.returncode == 0, built.stderr
    yardstick = pathlib.Path(built.stdout.strip().splitlines()[-1])

    def evaluate(model, mesh, both_ways=False):
        # both_ways: also from points of each face to the mesh (surface_to_mesh_rel,
        # hausdorff_sym_rel).
        env = dict(os.environ, MESHBENCH_BOTH_WAYS="1" if both_ways else "0")
        completed = subprocess.run([str(yardstick / "meshbench"), "eval", str(model), str(mesh)],
                                   capture_output=True, text=True, timeout=600, env=env)
        assert completed.returncode == 0, completed.stderr
        return json.loads(completed.stdout.strip().splitlines()[-1])

    return evaluate


THREE_LOAD_MJS = r"""
import fs from 'fs';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
const bytes = fs.readFileSync(process.argv[2]);
const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
new GLTFLoader().parse(buffer, '', (gltf) => {
  gltf.scene.updateMatrixWorld(true);
  const objects = [];
  gltf.scene.traverse((o) => {
    if (!o.isMesh && !o.isLineSegments) return;
    const g = o.geometry;
    const item = {kind: o.isMesh ? 'triangles' : 'lines', name: o.name,
                  attributes: Object.keys(g.attributes),
                  position: Array.from(g.attributes.position.clone().applyMatrix4(o.matrixWorld).array),
                  index: g.index ? Array.from(g.index.array) : null};
    if (g.attributes.normal) {
      const matrix = new THREE.Matrix3().getNormalMatrix(o.matrixWorld);
      item.normal = Array.from(g.attributes.normal.clone().applyNormalMatrix(matrix).array);
    }
    // GLTFLoader names a custom attribute _FOO as the lower-case _foo.
    if (g.attributes._face_id) item.face_id = Array.from(g.attributes._face_id.array);
    // A node drawing an instanced part's mesh at another instance maps the ids (node extras
    // become userData, on the mesh or on the group of its primitives).
    for (let p = o; p; p = p.parent) {
      if (p.userData && p.userData.rdmesh && p.userData.rdmesh.face_ids) {
        item.face_map = p.userData.rdmesh.face_ids;
        break;
      }
    }
    if (g.attributes._edge_id) item.edge_id = Array.from(g.attributes._edge_id.array);
    objects.push(item);
  });
  console.log(JSON.stringify({extras: gltf.parser.json.extras || null,
                              primitives: gltf.parser.json.meshes.map((m) => m.primitives.map(
                                  (p) => ({mode: p.mode === undefined ? 4 : p.mode,
                                           extras: p.extras || null}))),
                              objects}));
}, (error) => { console.error(String(error)); process.exit(1); });
"""


@pytest.fixture(scope="session")
def three_load():
    """Loads a .glb with three.js's GLTFLoader in node (npm three, installed on first use under
    the build tree): -> dict with the file's root `extras`, every mesh's primitives (mode,
    extras) and every drawn object (`triangles` or `lines`) with world-space positions (metres,
    +Y up), normals, index, the _face_id / _edge_id attributes as three.js reads them and the
    instance's `face_map` (extras.rdmesh.face_ids of its node) when there is one."""
    return _node_script("three", "three_load.mjs", THREE_LOAD_MJS)
