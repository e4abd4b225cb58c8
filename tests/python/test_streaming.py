"""Streaming behaviour: cancellation, deadlines, concurrent clients and very large results."""

import subprocess
import threading
import time

import grpc
import numpy as np
import pytest

from conftest import CYLINDER, MAKE_INSTANCES, edge_use_counts, wait_until
from rdmesh import RdmeshError

MIB = 1 << 20


def _busy_cpu(daemon, seconds=0.5):
    """CPU seconds the daemon used over the next `seconds` of wall time."""
    before = daemon.cpu_seconds()
    time.sleep(seconds)
    return daemon.cpu_seconds() - before


def _start_heavy(client, heavy):
    model, options = heavy
    call = client.mesh_stream(client.upload(model), **options)
    first = next(call)
    assert first.HasField("started")
    return call


def _assert_goes_idle(daemon, client, since):
    """The engine run returns and the daemon's threads stop using CPU within 1 s of `since`."""
    took = wait_until(lambda: client.server_status().active_jobs == 0, 1.0)
    assert took is not None, "engine still running 1 s after the stop"
    assert time.monotonic() - since < 1.0 + 0.1
    idle = _busy_cpu(daemon, 0.5)
    assert idle < 0.05, "daemon still used %.2f CPU s in 0.5 s after the stop" % idle


def test_client_cancel_stops_the_workers_within_a_second(daemon, heavy):
    client = daemon.client()
    call = _start_heavy(client, heavy)
    assert wait_until(lambda: client.server_status().active_jobs == 1, 2.0) is not None
    # The job runs: its worker uses CPU (a share of it only on a loaded machine).
    busy = _busy_cpu(daemon, 1.0)
    assert busy > 0.05, "the job should keep the workers busy (%.2f CPU s in 1 s)" % busy
    call.cancel()
    cancelled_at = time.monotonic()
    with pytest.raises(grpc.RpcError) as error:
        for _ in call:
            pass
    assert error.value.code() == grpc.StatusCode.CANCELLED
    _assert_goes_idle(daemon, client, cancelled_at)
    assert "client cancelled" in daemon.log()
    assert client.mesh(CYLINDER).summary.faces_ok > 0  # and it serves the next job


def test_deadline_stops_the_workers_within_a_second(daemon, heavy):
    client = daemon.client()
    model = client.upload(heavy[0])
    start = time.monotonic()
    with pytest.raises(RdmeshError) as error:
        client.mesh(model, timeout=1.5, **heavy[1])
    assert error.value.code == grpc.StatusCode.DEADLINE_EXCEEDED
    assert 1.4 < time.monotonic() - start < 3.0
    _assert_goes_idle(daemon, client, start + 1.5)


def test_timeout_seconds_option_is_deadline_exceeded(daemon, heavy):
    client = daemon.client()
    model = client.upload(heavy[0])
    start = time.monotonic()
    with pytest.raises(RdmeshError) as error:
        client.mesh(model, timeout_seconds=0.5, **heavy[1])
    assert error.value.code == grpc.StatusCode.DEADLINE_EXCEEDED
    assert time.monotonic() - start < 2.5
    _assert_goes_idle(daemon, client, start + 0.5)


def test_eight_concurrent_clients_get_identical_results(start_daemon):
    d = start_daemon("--max-jobs", "2", "--max-queue", "8")
    results, errors = [None] * 8, []
    max_queued = [0]

    def run(i):
        try:
            results[i] = d.client(request_id="concurrent-%d" % i).mesh(
                CYLINDER, max_deviation_rel=5e-4)
        except Exception as error:  # noqa: BLE001 - reported below
            errors.append(error)

    def watch():
        watcher = d.client()
        while any(r is None for r in results) and not errors:
            max_queued[0] = max(max_queued[0], watcher.server_status().queued_jobs)
            time.sleep(0.01)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(8)]
    monitor = threading.Thread(target=watch)
    for t in threads:
        t.start()
    monitor.start()
    for t in threads:
        t.join(timeout=120)
    monitor.join(timeout=5)
    assert not errors, errors
    reference = results[0]
    assert len(reference.triangles) > 0
    for other in results[1:]:
        assert np.array_equal(other.xyz, reference.xyz)
        assert np.array_equal(other.triangles, reference.triangles)
        assert np.array_equal(other.triangle_face, reference.triangle_face)
    log = d.log()
    assert all("req=concurrent-%d" % i in log for i in range(8))
    assert d.client().server_status().jobs_completed >= 8


def test_more_than_five_million_triangles_stream_in_small_messages(start_daemon, tmp_path):
    # Many placed copies of one box: the engine meshes the box once and places the copies, so
    # millions of triangles cost seconds, and every one of them is streamed and welded.
    d = start_daemon("--max-jobs", "1")
    client = d.client()
    one = tmp_path / "one_box.brep"
    subprocess.run([MAKE_INSTANCES, str(one), "1"], check=True)
    per_box = len(client.mesh(one, max_edge_length=1.0).triangles)
    copies = int(np.ceil(5.3e6 / per_box))
    many = tmp_path / "boxes.brep"
    subprocess.run([MAKE_INSTANCES, str(many), str(copies)], check=True)
    start = time.monotonic()
    result = client.mesh(many, max_edge_length=1.0, timeout=300)
    seconds = time.monotonic() - start
    assert len(result.triangles) == copies * per_box > 5_000_000
    assert result.summary.triangles == len(result.triangles)
    assert len(result.faces) == 6 * copies
    assert result.largest_message <= MIB, result.largest_message
    assert (edge_use_counts(result.triangles) == 2).all()  # welded box by box, no cracks
    print("%d triangles, %d nodes, %d face messages in %.1f s"
          % (len(result.triangles), len(result.xyz), result.summary.face_messages, seconds))
