"""Crash isolation: every model is read and meshed in a worker process, so a model that crashes or
hangs OCCT, or a job that passes a limit, costs its own call and one worker, never the daemon."""

import os
import re
import signal
import threading
import time

import grpc
import pytest

from conftest import CUBE, CYLINDER, DATA, NIST, wait_until
from rdmesh import RdmeshError


def _oriented_edge_chain(links=200000):
    """CYLINDER whose ORIENTED_EDGE #29 reaches its EDGE_CURVE through a chain of `links`
    ORIENTED_EDGEs: no cycle (the STEP pre-checks refuse cycles), but OCCT's reader recurses once
    per link in StepShape_OrientedEdge::EdgeStart and overflows its stack (SIGSEGV)."""
    text = CYLINDER.read_text()
    line = "#29=ORIENTED_EDGE('',*,*,#50,.T.);"
    assert line in text and "ENDSEC;\nEND-ISO" in text
    first = 900000
    chain = ["#%d=ORIENTED_EDGE('',*,*,#%d,.T.);" % (first + i, first + i + 1)
             for i in range(links - 1)]
    chain.append("#%d=ORIENTED_EDGE('',*,*,#50,.T.);" % (first + links - 1))
    text = text.replace(line, "#29=ORIENTED_EDGE('',*,*,#%d,.T.);" % first)
    return text.replace("ENDSEC;\nEND-ISO", "\n".join(chain) + "\nENDSEC;\nEND-ISO", 1).encode()


def _repeated_edge_loop(times):
    """CYLINDER with one EDGE_LOOP listing its edges `times` times: healing the wire
    (ShapeFix_IntersectionTool::FixSelfIntersectWire) then runs for seconds to minutes."""
    text = CYLINDER.read_text()
    line = "#24=EDGE_LOOP('',(#29,#30,#31,#32));"
    assert line in text
    return text.replace(line, "#24=EDGE_LOOP('',(%s));" % ",".join(["#29,#30,#31,#32"] * times)
                        ).encode()


def _busy_worker(daemon, min_cpu=0.1, timeout=20.0):
    """The pid of a worker that is using CPU (the one running a call)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        before = {pid: _cpu(pid) for pid in daemon.worker_pids()}
        time.sleep(0.5)
        for pid, cpu in before.items():
            if _cpu(pid) - cpu >= min_cpu:
                return pid
    raise AssertionError("no worker became busy")


def _cpu(pid):
    try:
        with open("/proc/%d/stat" % pid) as stat:
            values = stat.read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(values[11]) + int(values[12])) / os.sysconf("SC_CLK_TCK")


def test_reader_crash_fails_its_call_only(start_daemon):
    daemon = start_daemon()
    client = daemon.client()
    # A well-formed job runs beside the crash and completes.
    done = {}
    good = threading.Thread(target=lambda: done.update(r=client.mesh(CYLINDER, max_edge_length=4)))
    good.start()
    with pytest.raises(RdmeshError) as error:
        client.upload(_oriented_edge_chain(), name="chain.step")
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "the STEP reader crashed (SIGSEGV) on this model" in error.value.details
    assert "chain.step" in error.value.details
    good.join()
    assert done["r"].summary.faces_ok == 5 and done["r"].summary.faces_failed == 0
    assert daemon.alive()
    status = client.server_status()
    assert status.workers_lost == 1
    assert status.refused_models == 1
    # The same bytes again: refused without a worker parsing them (the time is the upload's).
    start = time.monotonic()
    with pytest.raises(RdmeshError) as again:
        client.upload(_oriented_edge_chain(), name="chain.step")
    assert time.monotonic() - start < 3.0
    assert again.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "crashed (SIGSEGV) on this model before; refused without parsing it again" in \
        again.value.details
    assert client.server_status().workers_lost == 1
    # And the service goes on.
    assert client.mesh(CUBE).summary.faces_ok == 9


def test_former_mesher_crash_fails_its_faces_only(start_daemon):
    daemon = start_daemon()
    client = daemon.client()
    # LINE #235 lost its CARTESIAN_POINT: OCCT reads the model; rdmesh's constrained
    # triangulation crashed on its faces until their boundary loops were checked (the loops now
    # cross, and those faces fail with the reason: tests/data/fuzz/README.md). A mesher crash
    # itself is test_worker_killed_mid_mesh_fails_that_job_only's.
    info = client.upload(DATA / "fuzz" / "crash_mesher_missing_point.step")
    summary = client.mesh(info).summary
    assert summary.faces_failed == 3 and summary.faces_ok == 6
    assert daemon.alive()
    assert client.server_status().workers_lost == 0
    assert client.mesh(CUBE).summary.faces_ok == 9


def test_worker_killed_mid_mesh_fails_that_job_only(start_daemon, heavy):
    daemon = start_daemon()
    client = daemon.client()
    model = client.upload(heavy[0])
    errors = []

    def run():
        try:
            client.mesh(model, **heavy[1])
        except RdmeshError as e:
            errors.append(e)

    job = threading.Thread(target=run)
    job.start()
    os.kill(_busy_worker(daemon), signal.SIGSEGV)
    job.join(10)
    assert not job.is_alive()
    assert errors and errors[0].code == grpc.StatusCode.INVALID_ARGUMENT
    assert "the mesher crashed (SIGSEGV) on this model" in errors[0].details
    assert client.server_status().workers_lost == 1
    # A crash while meshing does not blacklist the model: it meshes again at other options.
    assert client.mesh(model).summary.faces_ok == model.faces


def test_cpu_limit_ends_a_hanging_read_and_other_uploads_go_on(start_daemon):
    daemon = start_daemon("--worker-cpu-seconds", "2")
    client = daemon.client()
    errors = []

    def upload_slow():
        try:
            client.upload(_repeated_edge_loop(1000), name="loop1000.step")
        except RdmeshError as e:
            errors.append((e, time.monotonic()))

    start = time.monotonic()
    slow = threading.Thread(target=upload_slow)
    slow.start()
    # The busy read is visible in the server's status.
    assert wait_until(lambda: client.server_status().active_parses == 1, 2.0) is not None
    # Another client's upload does not wait for the busy reader.
    other = daemon.client()
    t0 = time.monotonic()
    info = other.upload(CUBE)
    assert info.faces == 9
    assert time.monotonic() - t0 < 2.0
    slow.join(60)
    assert errors, "the 1000-fold edge loop should pass a 2 s CPU limit"
    error, at = errors[0]
    assert error.code == grpc.StatusCode.RESOURCE_EXHAUSTED
    assert "CPU time limit of 2 s (--worker-cpu-seconds) while reading the model" in error.details
    # Reading it takes about a minute of CPU; the limit ends it after 2 s of CPU (longer in wall
    # time on a busy machine).
    assert at - start < 30.0
    status = client.server_status()
    assert status.workers_lost == 1 and status.refused_models == 0
    assert daemon.alive()


@pytest.mark.parametrize("options", [{"max_deviation": 1e-12}, {"rd_tolerance": 1e-12},
                                     {"max_edge_length": 1e-6}])
def test_absurd_options_free_the_slot_within_a_second_of_the_deadline(start_daemon, options):
    daemon = start_daemon("--max-triangles", "0")
    client = daemon.client()
    model = client.upload(CYLINDER)
    start = time.monotonic()
    with pytest.raises(RdmeshError) as error:
        client.mesh(model, timeout=2.0, **options)
    assert error.value.code == grpc.StatusCode.DEADLINE_EXCEEDED
    took = wait_until(lambda: client.server_status().active_jobs == 0, 5.0)
    assert took is not None
    assert time.monotonic() - start < 2.0 + 1.2, "the job slot stayed busy past the deadline"
    # The slot is free for the next client: a cube meshes at once.
    t0 = time.monotonic()
    assert client.mesh(CUBE).summary.faces_ok == 9
    assert time.monotonic() - t0 < 3.0


def test_timeout_seconds_is_enforced_on_absurd_options(start_daemon):
    daemon = start_daemon("--max-triangles", "0")
    client = daemon.client()
    info = client.upload(CYLINDER)
    start = time.monotonic()
    with pytest.raises(RdmeshError) as error:
        client.mesh(info, max_deviation=1e-12, timeout_seconds=2)
    assert error.value.code == grpc.StatusCode.DEADLINE_EXCEEDED
    assert time.monotonic() - start < 2.0 + 1.5
    assert wait_until(lambda: client.server_status().active_jobs == 0, 1.0) is not None


def test_a_model_is_parsed_once_then_meshed_at_other_tolerances(start_daemon):
    daemon = start_daemon()
    client = daemon.client()
    info = client.upload(CYLINDER)
    assert not info.cached and info.load_seconds > 0
    for rel in (1e-2, 1e-3, 3e-4):
        call = client.mesh_stream(info, max_deviation_rel=rel)
        started = next(call).started
        assert started.model.cached and started.model.load_seconds == 0
        for _ in call:
            pass
    log = daemon.log()
    assert log.count("model %s 'axom_sliced_cylinder.step' parsed in" % info.model_id[:12]) == 1


def test_workers_are_limited_and_counted(start_daemon):
    daemon = start_daemon("--max-jobs", "1", "--workers", "2")
    client = daemon.client()
    status = client.server_status()
    assert status.max_workers == 2
    assert 1 <= status.workers <= 2
    assert sorted(status.worker_pids) == sorted(daemon.worker_pids())


def test_memory_limit_fails_the_call_not_the_daemon(start_daemon):
    # 130 MiB of address space is about 20 MiB more than an idle worker maps: the parse or the
    # mesh of a 10-face model at 1e-4 passes it. Under memory pressure glibc's malloc can also
    # crawl instead of failing, which the CPU limit then ends: either way RESOURCE_EXHAUSTED.
    daemon = start_daemon("--worker-memory", "130MiB", "--worker-cpu-seconds", "10")
    client = daemon.client()
    with pytest.raises(RdmeshError) as error:
        client.mesh(NIST, max_deviation_rel=1e-4, timeout=60)
    assert error.value.code == grpc.StatusCode.RESOURCE_EXHAUSTED
    assert ("memory limit of 130 MiB (--worker-memory)" in error.value.details or
            "CPU time limit of 10 s" in error.value.details)
    assert daemon.alive()
    assert client.health() == "SERVING"


def test_fuzz_regressions_end_as_documented_in_one_daemon(start_daemon):
    """Every file of tests/data/fuzz through one daemon: the status matches the CLI's documented
    exit code (3: the upload fails, 1: the mesh call fails, 4: the deadline, 0: the mesh
    comes back with failed faces), with the same message, and the daemon serves a well-formed
    model at the end."""
    table = (DATA / "fuzz" / "README.md").read_text()
    cases = re.findall(r"^\| `(\w+\.step)` \|.*\| ([0134]) \| ([^|]+?) \|$", table, re.M)
    assert len(cases) == len(list((DATA / "fuzz").glob("*.step")))
    daemon = start_daemon()
    client = daemon.client()
    for name, exit_code, message in cases:
        if exit_code == "0":
            result = client.mesh(client.upload(DATA / "fuzz" / name), timeout_seconds=2)
            assert result.summary.faces_failed > 0, name
            continue
        with pytest.raises(RdmeshError) as error:
            info = client.upload(DATA / "fuzz" / name)
            assert exit_code != "3", name
            client.mesh(info, timeout_seconds=2)
        expected = grpc.StatusCode.DEADLINE_EXCEEDED if exit_code == "4" else \
            grpc.StatusCode.INVALID_ARGUMENT
        assert error.value.code == expected, (name, error.value.details)
        if exit_code != "4":
            assert message in error.value.details, name
    assert daemon.alive()
    assert client.mesh(CUBE).summary.faces_ok == 9
