"""Levels of detail in one Mesh call (MeshRequest.lod_deviation_rel, issue 15 item 4): the
stream carries the levels coarsest first, each opened by a LevelStarted event and closed by its
Summary, every event tagged with its level; each level is the mesh of a separate request at that
deviation, array for array; the remote CLI and rdmesh-py write the local CLI's level files."""

import os
import subprocess

import numpy as np
import pytest

from conftest import CLI, CYLINDER, EIGHT_CYL, NIST, RDMESH_PY
from rdmesh import RdmeshError

import grpc

LEVELS = [1e-3, 1e-2, 2e-4]  # in any order; streamed coarsest first
ORDERED = sorted(LEVELS, reverse=True)
TAGGED = ("progress", "face", "node_ids", "edge", "summary")


def test_stream_is_coarse_first_with_every_event_tagged(client):
    events = list(client.mesh_stream(str(EIGHT_CYL), lod=LEVELS, edges=True))
    kinds = [e.WhichOneof("event") for e in events]
    assert kinds[0] == "started" and kinds[-1] == "summary"
    starts = [i for i, k in enumerate(kinds) if k == "level_started"]
    summaries = [i for i, k in enumerate(kinds) if k == "summary"]
    assert len(starts) == len(summaries) == len(LEVELS)
    for level, (start, end) in enumerate(zip(starts, summaries)):
        info = events[start].level_started
        assert (info.level, info.levels) == (level, len(LEVELS))
        assert info.max_deviation_rel == ORDERED[level]
        assert info.max_deviation_abs == pytest.approx(
            ORDERED[level] * events[0].started.model.diagonal)
        assert start < end and (level == 0 or start == summaries[level - 1] + 1)
        inside = events[start + 1:end + 1]
        for event in inside:
            kind = event.WhichOneof("event")
            assert kind in TAGGED, kind
            assert getattr(event, kind).level == level, (kind, level)
        faces = {e.face.face_id for e in inside if e.WhichOneof("event") == "face"}
        assert faces == set(range(1, events[0].started.model.faces + 1))
        assert any(e.WhichOneof("event") == "edge" for e in inside)
        assert events[end].summary.requested_deviation == pytest.approx(info.max_deviation_abs)
    triangles = [events[i].summary.triangles for i in summaries]
    assert triangles == sorted(triangles) and triangles[0] < triangles[-1]
    # Started shows the finest level's options.
    assert events[0].started.options.options.max_deviation_rel == ORDERED[-1]


def same_mesh(level, single):
    """Level and separate request agree bit for bit: assembled mesh, faces, edges, summary."""
    assert level.xyz.tobytes() == single.xyz.tobytes()
    assert np.array_equal(level.triangles, single.triangles)
    assert np.array_equal(level.triangle_face, single.triangle_face)
    assert len(level.faces) == len(single.faces)
    for a, b in zip(level.faces, single.faces):
        assert (a.face_id, a.status, a.reason) == (b.face_id, b.status, b.reason)
        assert a.xyz.tobytes() == b.xyz.tobytes() and np.array_equal(a.triangles, b.triangles)
        assert np.array_equal(a.global_ids, b.global_ids)
        assert a.normals.tobytes() == b.normals.tobytes() and a.uv.tobytes() == b.uv.tobytes()
        assert a.max_deviation == b.max_deviation
    for field in ("edge_id", "offsets", "nodes", "face_ids", "seam", "degenerate", "sharp",
                  "dihedral"):
        assert np.array_equal(getattr(level.edges, field), getattr(single.edges, field)), field
    for field in ("triangles", "nodes", "faces_ok", "faces_failed", "requested_deviation",
                  "estimated_deviation", "mesh_area", "exact_area", "edges", "edge_segments"):
        assert getattr(level.summary, field) == getattr(single.summary, field), field


@pytest.mark.parametrize("model", [CYLINDER, NIST], ids=lambda p: p.stem)
def test_each_level_equals_a_single_request(client, model):
    seen = []
    levels = client.mesh_levels(str(model), LEVELS, uv=True, normals=True, edges=True,
                                level_done=lambda r: seen.append(r.level))
    assert seen == [0, 1, 2]  # each reported as soon as it was complete, coarsest first
    assert [r.level for r in levels] == [0, 1, 2]
    assert [r.max_deviation_rel for r in levels] == ORDERED
    for result, rel in zip(levels, ORDERED):
        single = client.mesh(str(model), max_deviation_rel=rel, uv=True, normals=True,
                             edges=True)
        same_mesh(result, single)
    assert levels[0].triangle_count < levels[-1].triangle_count


def test_levels_share_the_other_options(client):
    levels = client.mesh_levels(str(EIGHT_CYL), [5e-2, 5e-3], face_ids=[1, 2, 3, 7],
                                max_edge_length=3.0, edges=True, uv=True, normals=True)
    for result, rel in zip(levels, [5e-2, 5e-3]):
        single = client.mesh(str(EIGHT_CYL), max_deviation_rel=rel, face_ids=[1, 2, 3, 7],
                             max_edge_length=3.0, edges=True, uv=True, normals=True)
        same_mesh(result, single)
        assert {f.face_id for f in result.faces if f.status == "ok"} == {1, 2, 3, 7}


@pytest.mark.parametrize("options,lod,message", [
    ({"max_deviation_rel": 1e-3}, [1e-2, 1e-3], "max_deviation_rel"),
    ({"max_deviation": 0.5}, [1e-2, 1e-3], "max_deviation"),
    ({"max_triangles": 1000}, [1e-2, 1e-3], "max_triangles"),
    ({}, [1e-2, 1e-2], "equal"),
    ({}, [1e-2, 0.0], "(0, 0.5]"),
    ({}, [1e-2 / (k + 1) for k in range(9)], "at most 8"),
])
def test_bad_levels_are_refused(client, options, lod, message):
    with pytest.raises(RdmeshError) as error:
        client.mesh_levels(str(CYLINDER), lod, **options)
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert message in error.value.details


def run(command):
    result = subprocess.run([str(c) for c in command], capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    return result


@pytest.mark.skipif(not os.path.exists(CLI), reason="the rdmesh CLI is not built")
@pytest.mark.parametrize("ext", [".msh", ".glb"])
def test_remote_cli_writes_the_local_level_files(daemon, tmp_path, ext):
    lod = ",".join(str(v) for v in LEVELS)
    (tmp_path / "local").mkdir()
    (tmp_path / "remote").mkdir()
    run([CLI, "mesh", NIST, "-o", tmp_path / "local" / ("out" + ext), "-q", "--lod", lod])
    run([CLI, "mesh", NIST, "-o", tmp_path / "remote" / ("out" + ext), "-q", "--lod", lod,
         "--remote", daemon.address])
    written = sorted(p.name for p in (tmp_path / "local").iterdir())
    assert written == ["out.lod%d%s" % (i, ext) for i in range(len(LEVELS))]
    assert written == sorted(p.name for p in (tmp_path / "remote").iterdir())
    for name in written:
        assert (tmp_path / "local" / name).read_bytes() == \
            (tmp_path / "remote" / name).read_bytes(), name


def test_rdmesh_py_writes_one_file_per_level(daemon, tmp_path):
    lod = ",".join(str(v) for v in LEVELS)
    result = run(["/usr/bin/python3", RDMESH_PY, "--address", daemon.address, "mesh", CYLINDER,
                  "-o", tmp_path / "out.msh", "--no-progress", "--json", "--lod", lod])
    import json
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert [r["level"] for r in report["levels"]] == [0, 1, 2]
    assert [r["max_deviation_rel"] for r in report["levels"]] == ORDERED
    for level, rel in enumerate(ORDERED):
        assert report["levels"][level]["open_edges"] == 0
        single = tmp_path / ("single%d.msh" % level)
        run(["/usr/bin/python3", RDMESH_PY, "--address", daemon.address, "mesh", CYLINDER,
             "-o", single, "--no-progress", "--max-deviation-rel", str(rel)])
        assert (tmp_path / ("out.lod%d.msh" % level)).read_bytes() == single.read_bytes()
