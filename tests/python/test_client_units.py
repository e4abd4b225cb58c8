"""Unit tests of the Python client's own pieces (no daemon): assembly, options, MSH output."""

import meshio
import numpy as np
import pytest

from rdmesh import FaceResult, assemble
from rdmesh.cli import write_mesh
from rdmesh.client import MeshResult, mesh_options
from rdmesh.msh import write_msh41


def _face(face_id, xyz, triangles, ids, status="ok"):
    return FaceResult(face_id=face_id, surface_type="plane", status=status, reason="",
                      xyz=np.array(xyz, dtype=float).reshape(-1, 3),
                      triangles=np.array(triangles, dtype=np.int32).reshape(-1, 3),
                      global_ids=np.array(ids, dtype=np.int64))


def _two_faces():
    a = _face(1, [0, 0, 0, 1, 0, 0, 0, 1, 0], [0, 1, 2], [0, 1, 2])
    # Face 3 shares nodes 1 and 2; its node 3 repeats global node 3 (a pole): the second
    # triangle collapses and is left out, as the engine does.
    b = _face(3, [1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0], [0, 1, 2, 1, 3, 2], [1, 3, 2, 3])
    return a, b


def test_assemble_welds_through_global_ids_in_face_order():
    a, b = _two_faces()
    failed = _face(2, [], [], [], status="failed")
    xyz, triangles, triangle_face = assemble([b, failed, a], node_count=4)
    assert xyz.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
    assert triangles.tolist() == [[0, 1, 2], [1, 3, 2]]
    assert triangle_face.tolist() == [1, 3]


def test_assemble_compacts_unused_ids_and_keeps_faces_without_ids_apart():
    a, _ = _two_faces()
    a.global_ids = np.array([5, 7, 9])
    lone = _face(4, [2, 2, 2, 3, 2, 2, 2, 3, 2], [0, 1, 2], [])
    xyz, triangles, triangle_face = assemble([a, lone], node_count=10)
    assert len(xyz) == 6
    assert triangles.tolist() == [[0, 1, 2], [3, 4, 5]]
    assert np.array_equal(xyz[3:], lone.xyz)


def test_mesh_options_rejects_unknown_names():
    message = mesh_options(max_deviation=0.5, face_ids=[3, 4], nurbs=None)
    assert message.max_deviation == 0.5 and list(message.face_ids) == [3, 4]
    assert not message.HasField("max_deviation_rel")
    with pytest.raises(TypeError, match="max_deviaton"):
        mesh_options(max_deviaton=1.0)


def test_msh41_has_one_surface_per_face_and_reads_back(tmp_path):
    a, b = _two_faces()
    xyz, triangles, triangle_face = assemble([a, b], node_count=4)
    path = tmp_path / "two.msh"
    write_msh41(path, xyz, triangles, triangle_face)
    text = path.read_text()
    assert "$Entities\n0 0 2 0\n" in text
    mesh = meshio.read(path)
    assert sum(len(c.data) for c in mesh.cells) == 2
    tags = np.concatenate(mesh.cell_data["gmsh:geometrical"])
    assert sorted(tags.tolist()) == [1, 3]
    assert np.allclose(np.sort(mesh.points, axis=0), np.sort(xyz, axis=0))


@pytest.mark.parametrize("ext", [".stl", ".obj", ".vtu", ".ply", ".msh"])
def test_every_output_format_writes_the_triangles(tmp_path, ext):
    a, b = _two_faces()
    xyz, triangles, triangle_face = assemble([a, b], node_count=4)
    result = MeshResult(model=None, options=None, summary=None, faces=[a, b], xyz=xyz,
                        triangles=triangles, triangle_face=triangle_face)
    path = tmp_path / ("out" + ext)
    write_mesh(str(path), result)
    mesh = meshio.read(path)
    assert sum(len(c.data) for c in mesh.cells) == 2
    with pytest.raises(ValueError, match="unsupported"):
        write_mesh(str(tmp_path / "out.xyz"), result)


def test_edge_parts_join_chunks_into_flat_arrays():
    from rdmesh import RdmeshError, pb
    from rdmesh.client import _EdgeParts

    def part(edge_id, index, count, nodes, faces=(1, 2), **flags):
        return pb.EdgePolyline(edge_id=edge_id, chunk_index=index, chunk_count=count,
                               nodes=nodes, faces=faces, **flags)

    parts = _EdgeParts()
    parts.add(part(2, 0, 2, [0, 1], sharp=True, dihedral=90.0))
    parts.add(part(2, 1, 2, [2, 3], sharp=True, dihedral=90.0))
    parts.add(part(5, 0, 1, [4, 4], faces=[3], seam=True, dihedral=-1.0))
    edges = parts.result()
    assert len(edges) == 2 and edges.edge_id.tolist() == [2, 5]
    assert edges.polyline(0).tolist() == [0, 1, 2, 3] and edges.polyline(1).tolist() == [4, 4]
    assert edges.faces(0).tolist() == [1, 2] and edges.faces(1).tolist() == [3]
    assert edges.sharp.tolist() == [True, False] and edges.seam.tolist() == [False, True]
    assert edges.dihedral.tolist() == [90.0, -1.0]
    assert edges.nodes.dtype == np.int64 and edges.offsets.tolist() == [0, 4, 6]

    broken = _EdgeParts()
    broken.add(part(2, 0, 3, [0]))
    with pytest.raises(RdmeshError):
        broken.add(part(3, 0, 1, [1]))  # edge 2 still misses parts
    unfinished = _EdgeParts()
    unfinished.add(part(2, 0, 2, [0]))
    with pytest.raises(RdmeshError):
        unfinished.result()
    backwards = _EdgeParts()
    backwards.add(part(4, 0, 1, [0]))
    with pytest.raises(RdmeshError):
        backwards.add(part(3, 0, 1, [1]))
    assert len(_EdgeParts().result()) == 0
