"""Replicas behind nginx (docs/ROUTING.md): three rdmeshd processes and an nginx that routes on
the x-rdmesh-model header with consistent hashing, all on loopback.

nginx runs the shipped deploy/nginx/rdmesh-grpc.conf with this test's own `server` and `listen`
lines, as the current user, with every path in a temporary directory. scripts/install-deps.sh
installs nginx; without it this test fails (it does not skip). RDMESH_NGINX names another nginx
binary.
"""

import hashlib
import os
import re
import shutil
import signal
import socket
import subprocess
import time

import grpc
import pytest

from conftest import CLI, CUBE, CYLINDER, EIGHT_CYL, NIST, REPO, Daemon
from nginx_ring import Ring
from rdmesh import Client, pb, pb_grpc

NGINX_CONF = REPO / "deploy" / "nginx" / "rdmesh-grpc.conf"
FIRST = {"max_deviation_rel": 2e-3}  # the first mesh of each model
SECOND = {"max_deviation_rel": 1e-3}  # then each model again at another tolerance


def _nginx_binary():
    found = os.environ.get("RDMESH_NGINX") or shutil.which("nginx") or "/usr/sbin/nginx"
    if not os.access(found, os.X_OK):
        pytest.fail("nginx is not installed (looked for %s): scripts/install-deps.sh installs "
                    "Debian's nginx package, or set RDMESH_NGINX" % found)
    return found


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Nginx:
    """nginx in the foreground on 127.0.0.1:<free port>, in front of `backends` (host:port)."""

    def __init__(self, tmp_path, backends):
        self.dir = tmp_path / "nginx"
        self.dir.mkdir()
        self.port = _free_port()
        self.address = "127.0.0.1:%d" % self.port
        shipped = NGINX_CONF.read_text()
        servers = "".join("    server %s max_fails=1 fail_timeout=10s;\n" % b for b in backends)
        routed, count = re.subn(r"(    server rdmeshd-\d+:50051[^\n]*\n)+", servers, shipped)
        assert count == 1, "the server lines of %s moved; update this test" % NGINX_CONF
        routed, count = re.subn(r"listen 50051 http2;", "listen %s http2;" % self.address,
                                routed)
        assert count == 1, "the listen line of %s moved; update this test" % NGINX_CONF
        (self.dir / "rdmesh-grpc.conf").write_text(routed)
        temp = self.dir / "temp"
        temp.mkdir()
        # Started by root, nginx would run its worker as nobody, which cannot enter pytest's
        # private temporary directories.
        user = "user root root;\n" if os.geteuid() == 0 else ""
        (self.dir / "nginx.conf").write_text(
            user +
            "worker_processes 1;\n"
            "events { worker_connections 256; }\n"
            "http {\n"
            "    access_log %(d)s/access.log;\n"
            "    client_body_temp_path %(t)s/body;\n"
            "    proxy_temp_path %(t)s/proxy;\n"
            "    fastcgi_temp_path %(t)s/fastcgi;\n"
            "    uwsgi_temp_path %(t)s/uwsgi;\n"
            "    scgi_temp_path %(t)s/scgi;\n"
            "    include %(d)s/rdmesh-grpc.conf;\n"
            "}\n" % {"d": self.dir, "t": temp})
        self.error_log = self.dir / "error.log"
        self.proc = subprocess.Popen(
            [_nginx_binary(), "-p", str(self.dir), "-c", str(self.dir / "nginx.conf"),
             "-e", str(self.error_log),
             "-g", "daemon off; pid %s/nginx.pid; error_log %s info;" % (self.dir,
                                                                         self.error_log)],
            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        self._wait_for_port()

    def _wait_for_port(self, timeout=10.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.proc.poll() is not None:
                raise RuntimeError("nginx exited with %s:\n%s" % (self.proc.returncode,
                                                                 self.log()))
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", self.port)) == 0:
                    return
            time.sleep(0.05)
        raise RuntimeError("nginx did not listen on %s:\n%s" % (self.address, self.log()))

    def log(self):
        return self.error_log.read_text() if self.error_log.exists() else ""

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGQUIT)  # graceful shutdown
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def _models(tmp_path):
    """Six models: the four bundled STEP files and two byte-level variants (comments in the
    header), which are other models to the content-addressed cache and to the hash ring. The
    second variant is 1.5 MiB, more than nginx's default client_max_body_size, and goes up in
    two chunks."""
    models = [CUBE, CYLINDER, NIST, EIGHT_CYL]
    for source, lines in ((CUBE, 1), (CYLINDER, 25000)):
        variant = tmp_path / ("variant_" + source.name)
        comments = b"/* rdmesh routing test variant, padding to pass 1 MiB ...... */\n" * lines
        variant.write_bytes(source.read_bytes().replace(b"HEADER;", b"HEADER;\n" + comments, 1))
        models.append(variant)
    assert models[-1].stat().st_size > 1.5 * (1 << 20)
    ids = [hashlib.sha256(m.read_bytes()).hexdigest() for m in models]
    assert len(set(ids)) == len(models)
    return models, ids


def _mesh_bytes(result):
    """Everything a result's geometry is made of, as bytes (byte-identical comparison)."""
    parts = [result.xyz.tobytes(), result.triangles.tobytes(), result.triangle_face.tobytes()]
    for face in result.faces:
        parts += [face.xyz.tobytes(), face.triangles.tobytes(), face.global_ids.tobytes()]
    return b"".join(parts)


def _holder(daemons, model_id):
    """Indices of the daemons whose log says they parsed `model_id`."""
    return [i for i, d in enumerate(daemons)
            if re.search(r"model %s '[^']*' parsed:" % model_id[:12], d.log())]


def _served_by(daemons, job_id):
    """The index of the one daemon whose log holds the Mesh call `job_id`."""
    found = [i for i, d in enumerate(daemons) if "req=%s Mesh from" % job_id in d.log()]
    assert len(found) == 1, "job %s in the logs of %s" % (job_id, found)
    return found[0]


def _count(daemon, text):
    return daemon.log().count(text)


@pytest.fixture
def single_daemon_results(tmp_path):
    """The reference: every model at both tolerances on one daemon, no balancer."""
    _nginx_binary()  # fail at once, before the reference runs, when nginx is missing
    models, _ = _models(tmp_path)
    daemon = Daemon(tmp_path / "single.log")
    try:
        daemon.wait_serving()
        client = daemon.client()
        return {(str(m), i): _mesh_bytes(client.mesh(m, **opts))
                for m in models for i, opts in enumerate((FIRST, SECOND))}
    finally:
        assert daemon.stop() == 0, daemon.log()[-3000:]


def test_nginx_routes_each_model_to_one_replica_and_fails_over(tmp_path,
                                                               single_daemon_results):
    _nginx_binary()
    models, ids = _models(tmp_path)
    daemons = []
    nginx = None
    try:
        # Three replicas on free ports. Where nginx puts a model depends on the replicas'
        # addresses (the ring is built from them): start again on other ports in the rare case
        # (about 0.4%) where all six models would land on one replica.
        for attempt in range(10):
            # One parsed-model store for the fleet (docs/SCALE.md), as the shared volume of
            # docker/compose.yaml and deploy/k8s.
            daemons = [Daemon(tmp_path / ("replica-%d-%d.log" % (attempt, i)),
                              ["--cache-dir", str(tmp_path / "store")]) for i in range(3)]
            addresses = [d.address for d in daemons]
            ring = Ring(addresses)
            predicted = [addresses.index(ring.owner(model_id)) for model_id in ids]
            if len(set(predicted)) > 1:
                break
            for d in daemons:
                assert d.stop() == 0
        for d in daemons:
            d.wait_serving()
        nginx = Nginx(tmp_path, [d.address for d in daemons])
        client = Client(nginx.address)
        assert client.health() == "SERVING"  # grpc.health.v1 passes through nginx

        # 1. Each model, the first time: the client asks by id, gets NOT_FOUND, uploads, meshes.
        #    Then each model again at another tolerance: the replica that parsed it serves it.
        first = [client.mesh(m, **FIRST) for m in models]
        second = [client.mesh(m, **SECOND) for m in models]
        holders = []
        for m, model_id, a, b in zip(models, ids, first, second):
            holder = _holder(daemons, model_id)
            assert len(holder) == 1, "%s parsed on replicas %s" % (m.name, holder)
            holders.append(holder[0])
            assert _served_by(daemons, a.job_id) == holder[0]
            assert _served_by(daemons, b.job_id) == holder[0]
            assert b.model.cached and b.model.load_seconds == 0, m.name
            assert _mesh_bytes(a) == single_daemon_results[(str(m), 0)], m.name
            assert _mesh_bytes(b) == single_daemon_results[(str(m), 1)], m.name
        # One NOT_FOUND and one upload per model in the whole fleet, on its replica: the second
        # mesh found the model by id.
        assert [_count(d, "is not in the cache") for d in daemons] == [
            holders.count(i) for i in range(3)]
        assert [_count(d, "UploadModel from") for d in daemons] == [
            holders.count(i) for i in range(3)]
        assert len(set(holders)) > 1, "every model went to replica %d" % holders[0]
        # ... and each one where consistent hashing on its header puts it.
        assert holders == predicted
        # GetModelInfo carries the header too.
        infos_before = [_count(d, "GetModelInfo from") for d in daemons]
        assert client.info(models[0]).cached
        assert [_count(d, "GetModelInfo from") - n for d, n in zip(daemons, infos_before)] == [
            int(i == holders[0]) for i in range(3)]
        print("models per replica:", [holders.count(i) for i in range(3)])

        # The header is what keeps a model on its replica: the same calls without it are spread
        # over the replicas (nginx hashes a random request id), most of which lack the model.
        channel = grpc.insecure_channel(nginx.address)
        stub = pb_grpc.RdmeshStub(channel)
        meshes_before = [_count(d, "Mesh from") for d in daemons]
        codes = []
        for model_id in ids * 2:
            request = pb.MeshRequest(model=pb.ModelRef(model_id=model_id),
                                     options=pb.MeshOptions(max_deviation_rel=2e-3))
            try:
                for _ in stub.Mesh(request, timeout=60):
                    pass
                codes.append(grpc.StatusCode.OK)
            except grpc.RpcError as error:
                codes.append(error.code())
        channel.close()
        assert set(codes) <= {grpc.StatusCode.OK, grpc.StatusCode.NOT_FOUND}, codes
        assert grpc.StatusCode.NOT_FOUND in codes, codes
        spread = [_count(d, "Mesh from") - b for d, b in zip(daemons, meshes_before)]
        assert sum(spread) == len(codes) and sum(n > 0 for n in spread) > 1, spread
        print("calls without the header per replica:", spread)

        # `rdmesh mesh --remote` sends the header too: it lands on the model's replica, which
        # meshes it without an upload.
        cli_model = models[2]
        holder = daemons[holders[2]]
        meshes_before = [_count(d, "Mesh from") for d in daemons]
        uploads_before = sum(_count(d, "UploadModel from") for d in daemons)
        out = tmp_path / "cli.msh"
        run = subprocess.run([CLI, "mesh", str(cli_model), "-o", str(out), "--remote",
                              nginx.address, "--max-deviation-rel", "1e-3"],
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stderr
        meshes_after = [_count(d, "Mesh from") for d in daemons]
        assert [b - a for a, b in zip(meshes_before, meshes_after)] == [
            int(d is holder) for d in daemons]
        assert sum(_count(d, "UploadModel from") for d in daemons) == uploads_before

        # 2. Kill the replica that holds the most models. Its models re-mesh on the others (the
        #    client gets NOT_FOUND there and uploads again); the other models stay where they
        #    were; every result is byte-identical to the single daemon's.
        victim = max(range(3), key=holders.count)
        daemons[victim].proc.kill()
        daemons[victim].proc.wait()
        moved = [k for k, h in enumerate(holders) if h == victim]
        print("killed replica %d; models moved: %d of %d" % (victim, len(moved), len(models)))
        parsed_before = {k: len(re.findall("model %s '[^']*' parsed:" % ids[k][:12],
                                           "".join(d.log() for d in daemons)))
                         for k in range(len(models))}
        # A model asked for by the id this client uploaded it under: uploaded again from its
        # file.
        by_id = client.mesh(first[moved[0]].model, **FIRST)
        assert _served_by(daemons, by_id.job_id) != victim
        assert _mesh_bytes(by_id) == single_daemon_results[(str(models[moved[0]]), 0)]
        # `rdmesh mesh --remote` on a moved model: NOT_FOUND on its new replica, upload, mesh;
        # the file is the one a local run writes.
        cli_moved = models[moved[-1]]
        remote, local = tmp_path / "remote.msh", tmp_path / "local.msh"
        for args in (["--remote", nginx.address], []):
            run = subprocess.run([CLI, "mesh", str(cli_moved), "-o", str(remote if args else local),
                                  "--max-deviation-rel", "1e-3", *args],
                                 capture_output=True, text=True, timeout=120)
            assert run.returncode == 0, run.stderr
        assert remote.read_bytes() == local.read_bytes()
        for k, m in enumerate(models):
            for i, opts in enumerate((FIRST, SECOND)):
                result = client.mesh(m, **opts)
                served = _served_by(daemons, result.job_id)
                assert served != victim
                if k not in moved:
                    assert served == holders[k], m.name
                    assert result.model.cached, m.name
                else:  # the next replica on the ring
                    assert addresses[served] == ring.owner(ids[k], dead=[addresses[victim]])
                assert _mesh_bytes(result) == single_daemon_results[(str(m), i)], m.name
        logs = "".join(d.log() for d in daemons)
        for k in range(len(models)):
            parsed = len(re.findall("model %s '[^']*' parsed:" % ids[k][:12], logs))
            # A moved model is indexed once more, on one survivor; the others not at all.
            assert parsed - parsed_before[k] == (1 if k in moved else 0), models[k].name
            # ... and its worker reads it from the shared store: no second STEP parse anywhere.
            step_parses = len(re.findall("model %s '[^']*' parsed in" % ids[k][:12], logs))
            from_store = len(re.findall("model %s '[^']*' read from the store in" % ids[k][:12],
                                        logs))
            assert step_parses == 1, models[k].name
            assert from_store == (1 if k in moved else 0), models[k].name
        assert "connect() failed" in nginx.log()  # nginx did try the dead replica
        client.close()
    finally:
        if nginx is not None:
            nginx.stop()
        codes = [d.stop() for d in daemons]
        # Each replica but the killed one exits cleanly on SIGTERM.
        assert all(code in (0, -signal.SIGKILL) for code in codes), codes


def _directives(path):
    """The config's directives, comments and blank lines left out, `server host:port` lines
    apart."""
    lines = [line.split("#", 1)[0].strip() for line in path.read_text().splitlines()]
    lines = [line for line in lines if line]
    servers = [line for line in lines if re.match(r"server \S+:\d+", line)]
    return [line for line in lines if line not in servers], servers


def test_the_kubernetes_nginx_config_routes_like_the_tested_one():
    tested, tested_servers = _directives(NGINX_CONF)
    k8s, k8s_servers = _directives(REPO / "deploy" / "k8s" / "rdmesh-grpc.conf")
    assert k8s == tested
    assert len(tested_servers) == 3 and len(k8s_servers) == 3
    # One line per StatefulSet pod, by its name under the headless Service.
    statefulset = (REPO / "deploy" / "k8s" / "rdmeshd.yaml").read_text()
    replicas = int(re.search(r"^  replicas: (\d+)", statefulset, re.M).group(1))
    assert k8s_servers == ["server rdmeshd-%d.rdmeshd:50051 max_fails=1 fail_timeout=10s;" % i
                           for i in range(replicas)]
