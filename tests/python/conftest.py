"""Fixtures: an rdmeshd daemon on a free loopback port, clients, paths.

Environment (set by tests/python/CMakeLists.txt; the defaults fit a build in <repo>/build):
  RDMESH_RDMESHD      the rdmeshd binary
  RDMESH_CLI          the local rdmesh CLI binary
  RDMESH_PY_GEN_DIR   where the Python stubs were generated (read by the rdmesh package)
  RDMESH_TEST_DATA    tests/data
  RDMESH_PROTOC       protoc, for the reflection test's own stubs
  RDMESH_MAKE_INSTANCES  tests/server's make_instanced_brep (test data of many instances)
"""

import os
import pathlib
import re
import signal
import subprocess
import sys
import threading
import time

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
BUILD = REPO / "build"
RDMESHD = os.environ.get("RDMESH_RDMESHD", str(BUILD / "bin" / "rdmeshd"))
CLI = os.environ.get("RDMESH_CLI", str(BUILD / "bin" / "rdmesh"))
DATA = pathlib.Path(os.environ.get("RDMESH_TEST_DATA", str(REPO / "tests" / "data")))
PROTOC = os.environ.get("RDMESH_PROTOC", "protoc")
MAKE_INSTANCES = os.environ.get("RDMESH_MAKE_INSTANCES") or str(BUILD / "bin" /
                                                                 "make_instanced_brep")
RDMESH_PY = REPO / "clients" / "python" / "rdmesh-py"
sys.path.insert(0, str(REPO / "clients" / "python"))

from rdmesh import Client  # noqa: E402

CUBE = DATA / "cq_red_cube_blue_cylinder.step"
NIST = DATA / "nist_mbe_pmi_11.stp"
CYLINDER = DATA / "axom_sliced_cylinder.step"
EIGHT_CYL = DATA / "pyocc_eight_cyl.stp"
CLK_TCK = os.sysconf("SC_CLK_TCK")


class Daemon:
    """One rdmeshd process listening on 127.0.0.1:<free port>, logging to a file."""

    def __init__(self, log_path, args=(), env=None):
        self.log_path = log_path
        self.args = ["--listen", "127.0.0.1:0", "--threads", "2", *args]
        self._log = open(log_path, "w")
        full_env = dict(os.environ)
        full_env.update(env or {})
        self.proc = subprocess.Popen([RDMESHD, *self.args], stdout=self._log,
                                     stderr=subprocess.STDOUT, env=full_env)
        self.address = self._wait_for_port()
        self._clients = []

    def _wait_for_port(self, timeout=20.0):
        end = time.monotonic() + timeout
        pattern = re.compile(r"listening on (\S+):(\d+) ")
        while time.monotonic() < end:
            match = pattern.search(self.log())
            if match:
                return "%s:%s" % (match.group(1), match.group(2))
            if self.proc.poll() is not None:
                raise RuntimeError("rdmeshd exited with %s:\n%s" % (self.proc.returncode,
                                                                    self.log()))
            time.sleep(0.02)
        raise RuntimeError("rdmeshd did not start listening:\n" + self.log())

    def log(self):
        return self.log_path.read_text()

    def client(self, **kwargs):
        client = Client(self.address, **kwargs)
        self._clients.append(client)
        return client

    def wait_serving(self, timeout=10.0):
        client = self.client()
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                if client.health(timeout=1.0) == "SERVING":
                    return
            except Exception:  # noqa: BLE001 - not up yet
                pass
            time.sleep(0.05)
        raise RuntimeError("rdmeshd never became SERVING")

    def alive(self):
        return self.proc.poll() is None

    def worker_pids(self):
        """Process ids of the daemon's worker processes (its children)."""
        pids = []
        for task in pathlib.Path("/proc/%d/task" % self.proc.pid).iterdir():
            try:
                pids += [int(p) for p in (task / "children").read_text().split()]
            except OSError:
                pass
        return pids

    def cpu_seconds(self):
        """User + system CPU time of the daemon and its live worker processes (all threads),
        seconds."""
        total = 0.0
        for pid in [self.proc.pid] + self.worker_pids():
            try:
                fields = pathlib.Path("/proc/%d/stat" % pid).read_text().rsplit(")", 1)[1]
            except OSError:
                continue  # a worker that just ended
            values = fields.split()
            total += (int(values[11]) + int(values[12])) / CLK_TCK  # utime, stime
        return total

    def stop(self, sig=signal.SIGTERM, timeout=20.0):
        """Sends `sig` and returns the exit code."""
        for client in self._clients:
            client.close()
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
                raise
        self._log.close()
        return self.proc.returncode


@pytest.fixture
def start_daemon(tmp_path):
    """Starts daemons with extra flags; each one must exit cleanly (code 0) on SIGTERM."""
    daemons = []

    def start(*args, env=None):
        daemon = Daemon(tmp_path / ("rdmeshd-%d.log" % len(daemons)), args, env)
        daemons.append(daemon)
        daemon.wait_serving()
        return daemon

    yield start
    for daemon in daemons:
        code = daemon.stop()
        assert code == 0, "rdmeshd exited with %s:\n%s" % (code, daemon.log()[-3000:])


@pytest.fixture(scope="module")
def daemon(tmp_path_factory):
    """A daemon shared by a module's tests (default limits, 2 threads per job)."""
    d = Daemon(tmp_path_factory.mktemp("rdmeshd") / "rdmeshd.log", ["--max-jobs", "2"])
    d.wait_serving()
    yield d
    code = d.stop()
    assert code == 0, d.log()[-3000:]


@pytest.fixture
def client(daemon):
    return daemon.client()


# Workloads that keep the engine busy, lightest first. How long each takes depends on the engine
# of the day, so the suite picks the first that still runs after HEAVY_SECONDS (see `heavy`).
HEAVY_CANDIDATES = [
    (CUBE, {"max_edge_length": 0.2}),
    (CYLINDER, {"max_edge_length": 2.0}),
    (CUBE, {"max_edge_length": 0.1}),
    (NIST, {}),
    (CYLINDER, {"max_edge_length": 0.5}),
    (CUBE, {"max_edge_length": 0.02}),
]
HEAVY_SECONDS = 4.0


@pytest.fixture(scope="session")
def heavy(tmp_path_factory):
    """(model, options) of a Mesh job that runs for more than HEAVY_SECONDS on this engine; the
    tests cancel it (or let a deadline stop it) long before it ends."""
    import grpc
    d = Daemon(tmp_path_factory.mktemp("calibrate") / "rdmeshd.log")
    try:
        d.wait_serving()
        client = d.client()
        for model, options in HEAVY_CANDIDATES:
            call = client.mesh_stream(model, **options)
            finished = threading.Event()

            def drain(call=call, finished=finished):
                try:
                    for _ in call:
                        pass
                except grpc.RpcError:
                    pass
                finished.set()

            thread = threading.Thread(target=drain)
            thread.start()
            still_running = not finished.wait(HEAVY_SECONDS)
            call.cancel()
            thread.join()
            wait_until(lambda: client.server_status().active_jobs == 0, 5.0)
            if still_running:
                return model, options
        pytest.fail("no workload in HEAVY_CANDIDATES keeps this engine busy for %.0f s"
                    % HEAVY_SECONDS)
    finally:
        d.stop()


def wait_until(predicate, timeout, interval=0.02):
    """Polls `predicate` until it is true; returns the seconds it took, or None on timeout."""
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        if predicate():
            return time.monotonic() - start
        time.sleep(interval)
    return None


def edge_use_counts(triangles):
    """How many triangles use each undirected edge of a (T, 3) array."""
    import numpy as np
    t = np.asarray(triangles, dtype=np.int64)
    a = np.concatenate([t[:, 0], t[:, 1], t[:, 2]])
    b = np.concatenate([t[:, 1], t[:, 2], t[:, 0]])
    keys = np.minimum(a, b) * (int(t.max()) + 1) + np.maximum(a, b)
    return np.unique(keys, return_counts=True)[1]
