"""Every RPC of rdmesh.v1.Rdmesh, bad inputs and the daemon's limits, against a live rdmeshd."""

import hashlib
import json
import signal
import subprocess
import threading
import time

import grpc
import numpy as np
import pytest

from conftest import (CUBE, CYLINDER, DATA, NIST, RDMESH_PY, Daemon, edge_use_counts,
                      wait_until)
from rdmesh import Client, RdmeshError, pb

EMPTY_STEP = b"""ISO-10303-21;
HEADER;
FILE_DESCRIPTION((''),'2;1');
FILE_NAME('empty.step','2024-01-01T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));
ENDSEC;
DATA;
#1=CARTESIAN_POINT('origin',(0.,0.,0.));
ENDSEC;
END-ISO-10303-21;
"""


def test_health_and_server_status(daemon, client):
    assert client.health() == "SERVING"
    assert client.health("rdmesh.v1.Rdmesh") == "SERVING"
    status = client.server_status()
    assert status.serving
    assert status.max_jobs == 2
    assert status.threads == 2
    assert status.version
    assert status.max_model_bytes == 256 << 20
    assert status.uptime_seconds > 0


def test_upload_is_content_addressed_and_cached(client):
    data = CYLINDER.read_bytes()
    first = client.upload(CYLINDER)
    assert first.model_id == hashlib.sha256(data).hexdigest()
    assert first.name == CYLINDER.name
    assert first.format == "step"
    assert first.faces > 0 and first.edges > 0
    assert first.file_bytes == len(data)
    assert len(first.bbox) == 6 and first.diagonal > 0
    assert sum(t.faces for t in first.surface_types) == first.faces
    # The same bytes in small chunks, under another name: same id, not parsed again.
    again = client.upload(data, name="renamed.step", chunk_bytes=4096)
    assert again.model_id == first.model_id
    assert again.cached and again.load_seconds == 0


def test_get_model_info_by_id_inline_and_unknown(client):
    uploaded = client.upload(CUBE)
    by_id = client.info(uploaded.model_id)
    assert by_id.model_id == uploaded.model_id and by_id.faces == uploaded.faces
    inline = client.info(pb.ModelRef(inline_model=pb.InlineModel(data=CUBE.read_bytes(),
                                                                 name="cube.step")))
    assert inline.model_id == uploaded.model_id
    with pytest.raises(RdmeshError) as missing:
        client.info("0" * 64)
    assert missing.value.code == grpc.StatusCode.NOT_FOUND
    assert "upload it again" in missing.value.details
    with pytest.raises(RdmeshError) as malformed:
        client.info(pb.ModelRef(model_id="not-a-sha"))
    assert malformed.value.code == grpc.StatusCode.INVALID_ARGUMENT
    with pytest.raises(RdmeshError) as nothing:
        client.info(pb.ModelRef())
    assert nothing.value.code == grpc.StatusCode.INVALID_ARGUMENT


def test_mesh_stream_events_in_order(client):
    model = client.upload(CUBE)
    events = list(client.mesh_stream(model, uv=True))
    kinds = [e.WhichOneof("event") for e in events]
    assert kinds[0] == "started" and kinds[-1] == "summary"
    assert kinds.count("started") == 1 and kinds.count("summary") == 1
    first_ids = kinds.index("node_ids")
    assert "face" not in kinds[first_ids:], "all FaceMesh events come before the node ids"
    assert "progress" in kinds
    started, summary = events[0].started, events[-1].summary
    assert started.model.model_id == model.model_id
    assert started.faces_requested == model.faces
    assert started.options.threads == 2
    assert started.options.max_deviation_abs == pytest.approx(1e-3 * model.diagonal)
    faces = [e.face for e in events if e.HasField("face")]
    ids = [e.node_ids for e in events if e.HasField("node_ids")]
    assert sorted({f.face_id for f in faces}) == list(range(1, model.faces + 1))
    assert summary.faces_ok == model.faces
    assert sum(f.triangle_count for f in faces if f.chunk_index == 0) >= summary.triangles
    assert all(len(f.uv) == 2 * len(f.xyz) // 3 for f in faces)
    assert {i.face_id for i in ids} == {f.face_id for f in faces}
    assert summary.face_messages == len(faces)
    all_ids = np.concatenate([np.array(i.global_ids) for i in ids])
    assert all_ids.min() == 0 and all_ids.max() == summary.nodes - 1


def test_mesh_assembles_a_watertight_mesh(client):
    result = client.mesh(CUBE, normals=True)
    info = result.model
    assert len(result.faces) == info.faces
    assert result.summary.faces_ok == info.faces
    assert len(result.triangles) == result.summary.triangles
    assert len(result.xyz) == result.summary.nodes
    assert result.triangle_face.min() >= 1 and result.triangle_face.max() <= info.faces
    # Welded: each face's nodes are the assembled nodes with the same global id, bit for bit.
    for face in result.faces:
        assert np.array_equal(result.xyz[face.global_ids], face.xyz)
        lengths = np.linalg.norm(face.normals, axis=1)
        assert np.allclose(lengths, 1.0, atol=1e-6)
    # Every edge of the closed solids bounds exactly two triangles: no cracks between faces.
    counts = edge_use_counts(result.triangles)
    assert info.closed
    assert (counts == 2).all(), "free or non-manifold edges: %s" % np.bincount(counts)


def test_mesh_edges_as_numpy_polylines(client):
    """edges=True: EdgePolyline events after the node ids and before the summary, one per edge
    in edge id order, that the client turns into numpy arrays: each polyline runs along sides
    of triangles of every face it names, the cube's edges are sharp at 90 degrees, the
    cylinder's seam is flagged; sharp_edge_angle moves the sharp flags and nothing else."""
    model = client.upload(CUBE)
    plain = [e.WhichOneof("event") for e in client.mesh_stream(model)]
    assert "edge" not in plain
    events = list(client.mesh_stream(model, edges=True))
    kinds = [e.WhichOneof("event") for e in events]
    first_edge = kinds.index("edge")
    assert "node_ids" not in kinds[first_edge:] and kinds[-1] == "summary"
    assert set(kinds[first_edge:-1]) == {"edge"}

    result = client.mesh(model, edges=True)
    edges = result.edges
    assert len(edges) == model.edges == 15
    assert edges.edge_id.tolist() == list(range(1, model.edges + 1))
    assert len(edges.offsets) == len(edges) + 1 and edges.offsets[-1] == len(edges.nodes)
    assert edges.nodes.min() >= 0 and edges.nodes.max() < len(result.xyz)
    sides = {}
    for (a, b, c), f in zip(result.triangles.tolist(), result.triangle_face.tolist()):
        for side in ((a, b), (b, c), (c, a)):
            sides.setdefault(frozenset(side), set()).add(f)
    for i in range(len(edges)):
        line, faces = edges.polyline(i), edges.faces(i)
        assert len(line) >= 2 and len(faces) >= 1
        for a, b in zip(line[:-1], line[1:]):
            assert sides[frozenset((int(a), int(b)))] == set(faces.tolist())
        assert edges.sharp[i] == (edges.dihedral[i] > 30.0 or (len(faces) == 1
                                                                 and not edges.seam[i]))
    cube = [i for i in range(len(edges)) if edges.faces(i).min() >= 4]
    assert len(cube) == 12
    assert np.allclose(edges.dihedral[cube], 90.0) and edges.sharp[cube].all()
    assert edges.seam.sum() == 1 and edges.dihedral[edges.seam][0] == -1.0
    blunt = client.mesh(model, edges=True, sharp_edge_angle=95.0)
    assert not blunt.edges.sharp[cube].any()
    assert np.array_equal(blunt.triangles, result.triangles)
    assert np.array_equal(blunt.edges.nodes, edges.nodes)
    assert client.mesh(model).edges is None


def test_mesh_options_change_the_mesh(client):
    model = client.upload(CYLINDER)
    coarse = client.mesh(model, max_deviation_rel=2e-3)
    fine = client.mesh(model, max_deviation_rel=2e-4)
    assert fine.options.options.max_deviation_rel == pytest.approx(2e-4)
    assert len(fine.triangles) > len(coarse.triangles)
    assert fine.summary.estimated_deviation <= fine.summary.requested_deviation * 1.0001
    assert fine.model.cached  # the second run did not parse the model again
    subset = client.mesh(model, face_ids=[1, 2], max_deviation_rel=2e-3)
    assert [f.face_id for f in subset.faces] == [1, 2]
    assert subset.summary.faces_skipped == model.faces - 2
    assert set(np.unique(subset.triangle_face)) <= {1, 2}
    budget = client.mesh(model, max_triangles=60)
    assert 0 < len(budget.triangles) <= 60


def test_mesh_inline_model(client):
    ref = pb.ModelRef(inline_model=pb.InlineModel(data=CUBE.read_bytes(), name="cube.step"))
    result = client.mesh(ref)
    assert result.summary.faces_ok == result.model.faces > 0


@pytest.mark.parametrize("name,data", [
    ("garbage.step", bytes(range(256)) * 40),
    ("truncated.stp", NIST.read_bytes()[:len(NIST.read_bytes()) // 2]),
    ("empty.step", EMPTY_STEP),
    ("nothing.step", b""),
])
def test_bad_models_are_invalid_argument_and_the_daemon_stays_up(daemon, client, name, data):
    with pytest.raises(RdmeshError) as upload:
        client.upload(data, name=name)
    assert upload.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert len(upload.value.details) > 10
    if data:
        assert name in upload.value.details
    with pytest.raises(RdmeshError) as inline:
        client.mesh(pb.ModelRef(inline_model=pb.InlineModel(data=data, name=name)))
    assert inline.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert daemon.alive()
    assert client.health() == "SERVING"
    assert client.mesh(CUBE).summary.faces_ok > 0


@pytest.mark.parametrize("options,field", [
    ({"max_deviation": -1.0}, "max_deviation"),
    ({"max_deviation_rel": float("nan")}, "max_deviation_rel"),
    ({"min_edge_length": -0.5}, "min_edge_length"),
    ({"max_edge_length": float("inf")}, "max_edge_length"),
    ({"rd_tolerance": -1e-3}, "rd_tolerance"),
    ({"max_triangles": -3}, "max_triangles"),
    ({"max_triangles": 10 ** 12}, "max_triangles"),
    ({"threads": -2}, "threads"),
    ({"face_ids": [0]}, "face"),
    ({"face_ids": [1, 10000]}, "10000"),
    ({"sharp_edge_angle": 200.0}, "sharp_edge_angle"),
])
def test_out_of_range_options_are_invalid_argument(daemon, client, options, field):
    with pytest.raises(RdmeshError) as error:
        client.mesh(CUBE, **options)
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert field in error.value.details
    assert daemon.alive()


def test_oversize_models_are_resource_exhausted(start_daemon):
    d = start_daemon("--max-model-bytes", "30000")
    client = d.client()
    assert NIST.stat().st_size > 30000 > CUBE.stat().st_size
    with pytest.raises(RdmeshError) as hinted:
        client.upload(NIST)  # the first chunk says how big the file is
    assert hinted.value.code == grpc.StatusCode.RESOURCE_EXHAUSTED
    assert "max-model-bytes" in hinted.value.details
    data = NIST.read_bytes()
    chunks = iter([pb.ModelChunk(data=data[i:i + 8192], name="nist.stp" if i == 0 else "")
                   for i in range(0, len(data), 8192)])  # no size hint
    with pytest.raises(grpc.RpcError) as streamed:
        client._stub.UploadModel(chunks)
    assert streamed.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
    with pytest.raises(RdmeshError) as inline:
        client.mesh(pb.ModelRef(inline_model=pb.InlineModel(data=data, name="nist.stp")))
    assert inline.value.code == grpc.StatusCode.RESOURCE_EXHAUSTED
    assert d.alive()
    assert client.mesh(CUBE).summary.faces_ok > 0


def test_results_over_max_triangles_are_resource_exhausted(start_daemon):
    d = start_daemon("--max-triangles", "100")
    client = d.client()
    with pytest.raises(RdmeshError) as error:
        client.mesh(CUBE, max_deviation_rel=1e-4)
    assert error.value.code == grpc.StatusCode.RESOURCE_EXHAUSTED
    assert "max-triangles" in error.value.details
    assert wait_until(lambda: client.server_status().active_jobs == 0, 1.0) is not None


def test_full_job_queue_is_resource_exhausted(start_daemon, heavy):
    d = start_daemon("--max-jobs", "1", "--max-queue", "0")
    client = d.client()
    model = client.upload(heavy[0])
    long_call = client.mesh_stream(model, **heavy[1])
    next(long_call)  # Started: the job holds the only slot
    with pytest.raises(RdmeshError) as error:
        client.mesh(model)
    assert error.value.code == grpc.StatusCode.RESOURCE_EXHAUSTED
    assert "queue is full" in error.value.details
    long_call.cancel()
    assert wait_until(lambda: client.server_status().active_jobs == 0, 1.0) is not None
    cube = client.upload(CUBE)
    assert wait_until(lambda: _mesh_ok(client, cube), 5.0) is not None


def _mesh_ok(client, model):
    try:
        return client.mesh(model).summary.faces_ok > 0
    except RdmeshError:
        return False


def test_bearer_token(start_daemon, tmp_path):
    token_file = tmp_path / "token"
    token_file.write_text("s3cret\n")
    d = start_daemon("--token-file", str(token_file))
    assert d.client().health() == "SERVING"  # health needs no token
    for token in (None, "wrong"):
        with pytest.raises(RdmeshError) as error:
            d.client(token=token).upload(CUBE)
        assert error.value.code == grpc.StatusCode.UNAUTHENTICATED
    assert d.client(token="s3cret").mesh(CUBE).summary.faces_ok > 0


def test_tls(tmp_path):
    key, cert = tmp_path / "key.pem", tmp_path / "cert.pem"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
                    "-subj", "/CN=localhost", "-addext", "subjectAltName=DNS:localhost",
                    "-keyout", str(key), "-out", str(cert)], check=True, capture_output=True)
    # Started by hand: the fixture's readiness probe speaks plain text.
    d = Daemon(tmp_path / "tls.log", ["--tls-cert", str(cert), "--tls-key", str(key)])
    try:
        port = d.address.rsplit(":", 1)[1]
        secure = Client("localhost:" + port, root_certificates=cert.read_bytes())
        assert secure.health() == "SERVING"
        assert secure.mesh(CUBE).summary.faces_ok > 0
        secure.close()
        plain = Client("localhost:" + port)
        with pytest.raises(RdmeshError):
            plain.health(timeout=2.0)
        plain.close()
    finally:
        assert d.stop() == 0


def test_server_side_files_only_under_the_data_root(daemon, client, start_daemon):
    with pytest.raises(RdmeshError) as off:
        client.info(pb.ModelRef(server_path=str(CUBE)))
    assert off.value.code == grpc.StatusCode.PERMISSION_DENIED
    assert "--data-root" in off.value.details
    rooted = start_daemon("--data-root", str(DATA)).client()
    info = rooted.info(pb.ModelRef(server_path=CUBE.name))
    assert info.model_id == hashlib.sha256(CUBE.read_bytes()).hexdigest()
    assert rooted.mesh(pb.ModelRef(server_path=str(CUBE))).summary.faces_ok > 0
    for outside in ("../CMakeLists.txt", "/etc/passwd", "../data/../../CMakeLists.txt"):
        with pytest.raises(RdmeshError) as error:
            rooted.info(pb.ModelRef(server_path=outside))
        assert error.value.code == grpc.StatusCode.PERMISSION_DENIED, outside
    with pytest.raises(RdmeshError) as missing:
        rooted.info(pb.ModelRef(server_path="no-such-model.step"))
    assert missing.value.code == grpc.StatusCode.NOT_FOUND


def test_every_log_line_carries_a_request_id(start_daemon):
    d = start_daemon("--log-format", "json")
    client = d.client(request_id="test-req-42")
    client.mesh(CUBE)
    lines = [json.loads(line) for line in d.log().splitlines() if line.strip()]
    assert lines and all("request_id" in line and "msg" in line for line in lines)
    mine = [line for line in lines if line["request_id"] == "test-req-42"]
    assert any("Mesh" in line["msg"] for line in mine)
    assert any("UploadModel" in line["msg"] for line in mine)


def test_text_log_lines_carry_request_ids(daemon, client):
    client.mesh(CUBE)
    lines = [line for line in daemon.log().splitlines() if line.strip()]
    assert lines and all(" req=" in line for line in lines)


def test_graceful_shutdown(tmp_path, heavy):
    d = Daemon(tmp_path / "shutdown.log", ["--grace-seconds", "1"])
    d.wait_serving()
    client = d.client()
    model = client.upload(heavy[0])
    long_call = client.mesh_stream(model, **heavy[1])
    next(long_call)
    outcome = {}

    def drain():
        try:
            for _ in long_call:
                pass
            outcome["code"] = grpc.StatusCode.OK
        except grpc.RpcError as error:
            outcome["code"] = error.code()

    reader = threading.Thread(target=drain)
    reader.start()
    start = time.monotonic()
    d.proc.send_signal(signal.SIGTERM)
    other = d.client()
    assert wait_until(lambda: _health(other) == "NOT_SERVING", 1.0) is not None
    with pytest.raises(RdmeshError) as refused:
        other.mesh(model)
    assert refused.value.code == grpc.StatusCode.UNAVAILABLE
    assert d.proc.wait(timeout=10) == 0
    elapsed = time.monotonic() - start
    assert 0.9 < elapsed < 4.0, elapsed  # drained for the 1 s grace period, then stopped
    reader.join(timeout=5)
    assert outcome.get("code") in (grpc.StatusCode.CANCELLED, grpc.StatusCode.UNAVAILABLE)
    assert "grace period over" in d.log()
    d.stop()


def _health(client):
    try:
        return client.health(timeout=0.5)
    except RdmeshError:
        return None


def test_rdmesh_py_health_info_and_status(daemon):
    run = lambda *args: subprocess.run(["/usr/bin/python3", str(RDMESH_PY), "--address",  # noqa
                                        daemon.address, *args], capture_output=True, text=True,
                                       timeout=60)
    health = run("health")
    assert health.returncode == 0 and health.stdout.strip() == "SERVING"
    info = run("info", str(CUBE))
    assert info.returncode == 0, info.stderr
    assert json.loads(info.stdout)["faces"] == 9
    status = run("status")
    assert status.returncode == 0 and json.loads(status.stdout)["max_jobs"] == 2
    out = daemon.log_path.parent / "cube.stl"
    meshed = run("mesh", str(CUBE), "-o", str(out), "--json", "--no-progress")
    assert meshed.returncode == 0, meshed.stderr
    summary = json.loads(meshed.stdout)
    assert summary["triangles"] > 0 and summary["open_edges"] == 0
    assert summary["faces_ok"] == summary["faces"] == 9
    assert out.stat().st_size == 84 + 50 * summary["triangles"]  # binary STL
    bad = run("info", str(DATA / "SOURCES.md"))
    assert bad.returncode == 1 and "INVALID_ARGUMENT" in bad.stderr
    down = subprocess.run(["/usr/bin/python3", str(RDMESH_PY), "--address", "127.0.0.1:1",
                           "health"], capture_output=True, text=True, timeout=30)
    assert down.returncode == 2
