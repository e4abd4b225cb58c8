"""The service gives the same meshes as the local CLI for the same options: through the Python
client (rdmesh-py, its own writers) and through `rdmesh mesh --remote` (the engine's writers)."""

import os
import subprocess

import meshio
import numpy as np
import pytest

from conftest import CLI, CUBE, CYLINDER, EIGHT_CYL, RDMESH_PY

pytestmark = pytest.mark.skipif(not os.path.exists(CLI), reason="the rdmesh CLI is not built")

CASES = [
    (CUBE, []),
    (CYLINDER, ["--max-deviation-rel", "2e-4"]),
    (EIGHT_CYL, ["--max-deviation", "0.5", "--faces", "1,2,3,7"]),
]


def read_msh41(path):
    """Nodes (N, 3) and triangles (T, 3) rows of an MSH 4.1 ASCII file, parametric or not."""
    lines = open(path).read().split("\n")
    i = lines.index("$Nodes") + 1
    blocks = int(lines[i].split()[0])
    i += 1
    tags, points = [], []
    for _ in range(blocks):
        dim, _, parametric, count = (int(v) for v in lines[i].split())
        i += 1
        tags += [int(lines[i + k]) for k in range(count)]
        points += [[float(v) for v in lines[i + count + k].split()[:3]] for k in range(count)]
        i += 2 * count
    row = {tag: r for r, tag in enumerate(tags)}
    i = lines.index("$Elements") + 1
    blocks = int(lines[i].split()[0])
    i += 1
    triangles = []
    for _ in range(blocks):
        _, _, kind, count = (int(v) for v in lines[i].split())
        i += 1
        if kind == 2:
            triangles += [[row[int(v)] for v in lines[i + k].split()[1:4]] for k in range(count)]
        i += count
    return np.array(points), np.array(triangles, dtype=np.int64)


def read_mesh(path):
    if str(path).endswith(".msh"):
        return read_msh41(path)
    mesh = meshio.read(path)
    return mesh.points, np.concatenate([c.data for c in mesh.cells if c.type == "triangle"])


def canonical_triangles(points, triangles):
    """Each triangle as its 9 coordinates, corners rotated to start at the smallest; sorted."""
    corners = points[triangles]  # (T, 3, 3)
    keyed = []
    for tri in corners:
        k = min(range(3), key=lambda j: tuple(tri[j]))
        keyed.append(np.roll(tri, -k, axis=0).ravel())
    keyed = np.array(keyed)
    return keyed[np.lexsort(keyed.T[::-1])]


def run(command):
    result = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return result


@pytest.mark.parametrize("model,options", CASES, ids=lambda v: getattr(v, "stem", None))
@pytest.mark.parametrize("ext", [".msh", ".stl"])
def test_python_client_writes_the_local_cli_mesh(daemon, tmp_path, model, options, ext):
    local, remote = tmp_path / ("local" + ext), tmp_path / ("python" + ext)
    run([CLI, "mesh", str(model), "-o", str(local), "-q", *options])
    run(["/usr/bin/python3", str(RDMESH_PY), "--address", daemon.address, "mesh", str(model),
         "-o", str(remote), "--no-progress", *options])
    local_points, local_triangles = read_mesh(local)
    remote_points, remote_triangles = read_mesh(remote)
    assert len(remote_triangles) == len(local_triangles) > 0
    used = lambda points, tris: np.unique(points[np.unique(tris)], axis=0)  # noqa: E731
    assert np.array_equal(used(remote_points, remote_triangles),
                          used(local_points, local_triangles))
    assert np.array_equal(canonical_triangles(remote_points, remote_triangles),
                          canonical_triangles(local_points, local_triangles))


@pytest.mark.parametrize("model,options", CASES, ids=lambda v: getattr(v, "stem", None))
@pytest.mark.parametrize("ext", [".msh", ".stl", ".obj", ".ply", ".vtu", ".glb"])
def test_remote_cli_writes_the_same_file(daemon, tmp_path, model, options, ext):
    # Same file name in two folders: OBJ names its .mtl sidecar after itself.
    (tmp_path / "local").mkdir()
    (tmp_path / "remote").mkdir()
    local, remote = tmp_path / "local" / ("out" + ext), tmp_path / "remote" / ("out" + ext)
    run([CLI, "mesh", str(model), "-o", str(local), "-q", *options])
    run([CLI, "mesh", str(model), "-o", str(remote), "-q", "--remote", daemon.address, *options])
    written = sorted(p.name for p in local.parent.iterdir())
    assert written == sorted(p.name for p in remote.parent.iterdir())
    for name in written:
        assert (local.parent / name).read_bytes() == (remote.parent / name).read_bytes(), name


@pytest.mark.parametrize("flags", [["--msh-parametric"], ["--no-edges"]])
def test_remote_cli_honours_the_write_options(daemon, tmp_path, flags):
    local, remote = tmp_path / "local.msh", tmp_path / "remote.msh"
    run([CLI, "mesh", str(CYLINDER), "-o", str(local), "-q", *flags])
    run([CLI, "mesh", str(CYLINDER), "-o", str(remote), "-q", "--remote", daemon.address, *flags])
    assert remote.read_bytes() == local.read_bytes()
    lines = local.read_text().split("\n")
    i = lines.index("$Nodes") + 1
    parametric = False
    for _ in range(int(lines[i].split()[0])):
        _, _, param, count = (int(v) for v in lines[i + 1].split())
        parametric = parametric or param == 1
        i += 1 + 2 * count
    assert parametric == ("--msh-parametric" in flags)
    i = lines.index("$Elements") + 1
    types = set()
    for _ in range(int(lines[i].split()[0])):
        _, _, kind, count = (int(v) for v in lines[i + 1].split())
        types.add(kind)
        i += 1 + count
    assert types == ({2} if "--no-edges" in flags else {1, 2})


def test_remote_cli_errors(daemon, tmp_path):
    out = tmp_path / "out.msh"
    down = subprocess.run([CLI, "mesh", str(CUBE), "-o", str(out), "--remote", "127.0.0.1:1"],
                          capture_output=True, text=True, timeout=60)
    assert down.returncode != 0 and "unavailable" in down.stderr
    budget = subprocess.run([CLI, "mesh", str(CUBE), "-o", str(out), "--remote", daemon.address,
                             "--max-triangles", str(10 ** 12)],
                            capture_output=True, text=True, timeout=60)
    assert budget.returncode == 2 and "max_triangles" in budget.stderr
    assert not out.exists()
