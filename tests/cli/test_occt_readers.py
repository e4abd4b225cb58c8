"""OCCT's STEP and IGES readers and OCCT's document framework in the rdmesh CLI: not linked in,
but loaded from the modules rdmesh_occt_readers.so and rdmesh_occt_xcaf.so beside the binary when
a run needs them (engine/src/model/occt_readers.h, xcaf_api.h).
"""

import json
import os
import shutil
import subprocess

import pytest

MODEL = "cq_red_cube_blue_cylinder.step"


def _mesh(binary, model, out, env_extra=None):
    env = dict(os.environ)
    env.pop("RDMESH_STEP_READER", None)
    env.update(env_extra or {})
    return subprocess.run([str(binary), "mesh", str(model), "-o", str(out), "--json", "-q"],
                          capture_output=True, text=True, timeout=300, env=env)


def _last_json(stdout):
    lines = [line for line in stdout.splitlines() if line.strip()]
    return json.loads(lines[-1])


def test_the_cli_does_not_load_occts_readers_at_start(cli):
    needed = subprocess.run(["readelf", "-d", str(cli)], capture_output=True, text=True,
                            check=True).stdout
    for toolkit in ("TKSTEP", "TKXDESTEP", "TKIGES", "TKXDEIGES"):
        assert f"lib{toolkit}.so" not in needed
    assert (cli.parent / "rdmesh_occt_readers.so").is_file()


def test_occts_step_reader_comes_from_the_module(cli, data_dir, tmp_path):
    own = _mesh(cli, data_dir / MODEL, tmp_path / "own.msh")
    occt = _mesh(cli, data_dir / MODEL, tmp_path / "occt.msh", {"RDMESH_STEP_READER": "occt"})
    assert own.returncode == 0, own.stderr
    assert occt.returncode == 0, occt.stderr
    own_report, occt_report = _last_json(own.stdout), _last_json(occt.stdout)
    assert own_report["reader"] == "rdmesh"
    assert occt_report["reader"] == "occt"
    assert "occt_transfer" in occt_report["load_stages"]
    # The same B-rep either way (the bench's step_equivalence checks this file): the same mesh.
    assert occt_report["triangles"] == own_report["triangles"] > 0


def test_a_binary_without_its_module_says_so(cli, data_dir, tmp_path):
    alone = tmp_path / "alone" / "rdmesh"
    alone.parent.mkdir()
    shutil.copy2(cli, alone)
    shutil.copy2(cli.parent / "rdmesh-local", alone.parent)
    # rdmesh's own reader needs no module.
    assert _mesh(alone, data_dir / MODEL, tmp_path / "own.msh").returncode == 0
    run = _mesh(alone, data_dir / MODEL, tmp_path / "occt.msh", {"RDMESH_STEP_READER": "occt"})
    assert run.returncode == 3
    assert "rdmesh_occt_readers.so" in run.stderr
    assert _last_json(run.stdout)["error"]["code"] == "internal"


@pytest.mark.skipif(not os.path.isfile("/usr/share/opencascade/data/iges/bearing.iges"),
                    reason="OCCT's sample IGES files are not installed")
def test_iges_through_the_module(cli, tmp_path):
    run = _mesh(cli, "/usr/share/opencascade/data/iges/bearing.iges", tmp_path / "b.msh")
    assert run.returncode == 0, run.stderr
    assert _last_json(run.stdout)["triangles"] > 0


def test_the_cli_does_not_load_the_document_framework_at_start(cli):
    needed = subprocess.run(["readelf", "-d", str(cli.parent / "rdmesh-local")],
                            capture_output=True, text=True, check=True).stdout
    for toolkit in ("TKXCAF", "TKLCAF", "TKBinXCAF", "TKV3d", "TKService", "TKRWMesh"):
        assert f"lib{toolkit}.so" not in needed
    assert (cli.parent / "rdmesh_occt_xcaf.so").is_file()


@pytest.mark.parametrize("name", ["kicad/LED_D3.0mm_Horizontal_O1.27mm_Z2.0mm.step",
                                  "pyocc_eight_cyl.stp"])
def test_a_part_or_an_assembly_meshes_without_the_document_module(cli, data_dir, tmp_path, name):
    # Only the readers' module beside it: a .msh of a part or of an assembly (eight_cyl: a
    # compound of products) needs no document; a .glb keeps the names and colours, so it needs
    # the module and says which.
    alone = tmp_path / "alone" / "rdmesh"
    alone.parent.mkdir()
    shutil.copy2(cli, alone)
    shutil.copy2(cli.parent / "rdmesh-local", alone.parent)
    shutil.copy2(cli.parent / "rdmesh_occt_readers.so", alone.parent)
    model = data_dir / name
    lean = _mesh(alone, model, tmp_path / "lean.msh")
    assert lean.returncode == 0, lean.stderr
    full = _mesh(cli, model, tmp_path / "full.msh", {"RDMESH_CACHE_DIR": str(tmp_path / "c")})
    assert full.returncode == 0, full.stderr
    # The same mesh as a load that keeps the document (the store's).
    assert (tmp_path / "lean.msh").read_bytes() == (tmp_path / "full.msh").read_bytes()
    glb = _mesh(alone, model, tmp_path / "x.glb")
    assert glb.returncode == 3
    assert "rdmesh_occt_xcaf.so" in glb.stderr
    assert _last_json(glb.stdout)["error"]["code"] == "internal"
