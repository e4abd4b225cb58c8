"""MeshOptions.compress through the service (issue 37): the run leaves 1.5% of the deviation to a
compressed .glb's rounding, from the Python client and from `rdmesh mesh --remote --compress`,
whose file is the local run's to the byte."""

import subprocess

import grpc
import pytest

from conftest import CLI, CUBE, EIGHT_CYL
from rdmesh import RdmeshError

SHARE = 0.015  # kCompressRoundingShare (engine/include/rdmesh/options.h)


def test_compress_meshes_to_the_reduced_deviation(client):
    packed = client.mesh(CUBE, compress=True)
    plain = client.mesh(CUBE, max_deviation_rel=1e-3 * (1 - SHARE))
    default = client.mesh(CUBE)
    assert packed.options.options.compress
    assert len(packed.triangles) == len(plain.triangles) >= len(default.triangles)
    # The whole deviation is still the one asked for.
    assert packed.summary.requested_deviation == pytest.approx(
        default.summary.requested_deviation, rel=1e-12)
    assert packed.options.max_deviation_abs == default.options.max_deviation_abs


def test_compress_needs_a_deviation(client):
    with pytest.raises(RdmeshError) as error:
        client.mesh(CUBE, compress=True, max_triangles=100)
    assert error.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "compress" in error.value.details


def test_remote_cli_writes_the_same_compressed_file(daemon, tmp_path):
    local, remote = tmp_path / "local.glb", tmp_path / "remote.glb"
    for out, extra in ((local, []), (remote, ["--remote", daemon.address])):
        subprocess.run([CLI, "mesh", str(EIGHT_CYL), "-o", str(out), "-q", "--compress", *extra],
                       check=True, capture_output=True, timeout=300)
    assert b"EXT_meshopt_compression" in remote.read_bytes()[:20000]
    assert remote.read_bytes() == local.read_bytes()
