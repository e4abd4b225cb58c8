"""Per-triangle estimated deviation: in the stream (ReturnFields.triangle_deviation), in the
Python client's arrays, in the VTU and PLY files of both CLIs, and the picture of
`rdmesh-py view`."""

import json
import os
import struct
import subprocess

import meshio
import numpy as np
import pytest

from conftest import CLI, CYLINDER, EIGHT_CYL, NIST, RDMESH_PY


def run(command, expect=0):
    result = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert result.returncode == expect, result.stderr
    return result


def test_stream_carries_each_triangles_deviation_when_asked(client):
    plain = client.mesh(CYLINDER, max_deviation_rel=5e-4)
    assert plain.triangle_deviation is None
    assert all(f.triangle_deviation is None for f in plain.faces)
    result = client.mesh(CYLINDER, max_deviation_rel=5e-4, triangle_deviation=True)
    assert np.array_equal(result.triangles, plain.triangles)  # the same mesh
    for face in result.faces:
        assert face.status == "ok"
        assert face.triangle_deviation.shape == (len(face.triangles),)
        assert face.triangle_deviation.dtype == np.float64
        assert (face.triangle_deviation >= 0).all()
        assert face.triangle_deviation.max() == face.max_deviation
    deviation = result.triangle_deviation
    assert deviation.shape == (len(result.triangles),)
    assert deviation.max() == result.summary.estimated_deviation
    assert deviation.max() <= result.summary.requested_deviation * (1 + 1e-9)
    assert (deviation > 0).sum() > len(deviation) // 4  # a cylinder's curved faces deviate
    # The assembled array follows the faces' triangles in face order.
    assert np.array_equal(deviation, np.concatenate([f.triangle_deviation for f in result.faces]))


@pytest.mark.parametrize("ext", [".vtu", ".ply"])
def test_both_clis_write_the_deviation_cell_data(daemon, client, tmp_path, ext):
    local, python = tmp_path / ("local" + ext), tmp_path / ("python" + ext)
    run([CLI, "mesh", str(EIGHT_CYL), "-o", str(local), "-q", "--max-deviation", "0.5"])
    run(["/usr/bin/python3", str(RDMESH_PY), "--address", daemon.address, "mesh", str(EIGHT_CYL),
         "-o", str(python), "--no-progress", "--max-deviation", "0.5"])
    expected = client.mesh(EIGHT_CYL, max_deviation=0.5, triangle_deviation=True)
    for path in (local, python):
        mesh = meshio.read(path)
        assert set(mesh.cell_data) == {"face_id", "deviation"}
        deviation = np.concatenate(mesh.cell_data["deviation"])
        face_id = np.concatenate(mesh.cell_data["face_id"])
        # Triangles in the same order, deviations to the bit (shortest round-trip text).
        assert np.array_equal(face_id, expected.triangle_face)
        assert np.array_equal(deviation, expected.triangle_deviation), path


def png_size(path):
    data = open(path, "rb").read(32)
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


@pytest.mark.parametrize("ext", [".vtu", ".ply"])
def test_view_draws_the_deviation_with_colour_bar_and_worst_faces(tmp_path, ext):
    mesh_path, picture = tmp_path / ("nist" + ext), tmp_path / "nist.png"
    run([CLI, "mesh", str(NIST), "-o", str(mesh_path), "-q", "--max-deviation-rel", "2e-3"])
    shown = json.loads(run(["/usr/bin/python3", str(RDMESH_PY), "view", str(mesh_path), "-o",
                            str(picture), "--size", "640x480", "--labels", "4",
                            "--json"]).stdout)
    assert png_size(picture) == (640, 480)
    mesh = meshio.read(mesh_path)
    deviation = np.concatenate(mesh.cell_data["deviation"])
    face_id = np.concatenate(mesh.cell_data["face_id"])
    assert shown["triangles"] == len(deviation)
    assert shown["clim"] == [0.0, float(deviation.max())]
    # The labels name the 4 faces whose worst triangle deviates most, worst first.
    per_face = {int(f): float(deviation[face_id == f].max()) for f in np.unique(face_id)}
    ranked = sorted(per_face, key=lambda f: (-per_face[f], f))[:4]
    assert [label["face_id"] for label in shown["labels"]] == ranked
    assert [label["deviation"] for label in shown["labels"]] == [per_face[f] for f in ranked]
    assert all(label["text"].startswith("%d. face %d: " % (k + 1, f))
               for k, (label, f) in enumerate(zip(shown["labels"], ranked)))
    # The picture holds the colour map's colours: the colour bar's ends, at least. A pixel row
    # of the bar spans ~1.4 of the map's 256 entries, and the row at each end shows one of the
    # last three entries (which one depends on where the bar's edge falls in the row).
    import matplotlib.image
    import matplotlib
    pixels = (matplotlib.image.imread(str(picture))[:, :, :3] * 255).round().astype(int)
    colours = np.array(sorted({tuple(p) for p in pixels.reshape(-1, 3)}))
    viridis = matplotlib.colormaps["viridis"]
    for entries in ((0, 1, 2), (253, 254, 255)):
        targets = np.array([viridis(i)[:3] for i in entries]) * 255
        nearest = np.abs(colours[:, None, :] - targets[None, :, :]).max(axis=2).min()
        assert nearest <= 2, entries
    assert len(colours) > 200  # a shaded mesh, not a blank page


def test_view_refuses_files_without_deviation(tmp_path):
    stl = tmp_path / "cyl.stl"
    run([CLI, "mesh", str(CYLINDER), "-o", str(stl), "-q"])
    refused = run(["/usr/bin/python3", str(RDMESH_PY), "view", str(stl), "-o",
                   str(tmp_path / "x.png")], expect=1)
    assert "view reads .vtu and .ply files" in refused.stderr
    bare = tmp_path / "bare.vtu"
    mesh = meshio.read(run([CLI, "mesh", str(CYLINDER), "-o", str(tmp_path / "c.vtu"), "-q"])
                       and str(tmp_path / "c.vtu"))
    meshio.write(bare, meshio.Mesh(mesh.points, mesh.cells))
    refused = run(["/usr/bin/python3", str(RDMESH_PY), "view", str(bare), "-o",
                   str(tmp_path / "y.png")], expect=1)
    assert "no cell data 'deviation'" in refused.stderr
    assert not os.path.exists(tmp_path / "x.png") and not os.path.exists(tmp_path / "y.png")
