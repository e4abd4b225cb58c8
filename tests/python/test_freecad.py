"""The FreeCAD client (clients/freecad) run headless in FreeCADCmd against rdmeshd on loopback:
every visible shape of a document becomes a watertight Mesh::Feature with one segment per B-rep
face, with the same triangles as a direct Python-client mesh of the same BREP."""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np

from conftest import NIST, REPO

FREECADCMD = shutil.which("freecadcmd") or shutil.which("FreeCADCmd")
DEVIATION_REL = 1e-3


def run_freecad(daemon, tmp_path, job="freecad_job.py"):
    """Runs `job` (beside this file) in FreeCADCmd; returns its JSON report. The rdmesh
    workbench (clients/freecad) is linked into the Mod folder of a $HOME of its own."""
    assert FREECADCMD, "freecadcmd is missing (scripts/install-deps.sh installs Debian's freecad)"
    out = tmp_path / "report.json"
    home = tmp_path / "home"  # FreeCAD writes its user settings under $HOME
    mods = home / ".local" / "share" / "FreeCAD" / "Mod"
    mods.mkdir(parents=True)
    (mods / "rdmesh").symlink_to(REPO / "clients" / "freecad")
    env = dict(os.environ, HOME=str(home), QT_QPA_PLATFORM="offscreen",
               RDMESH_ADDRESS=daemon.address, RDMESH_FC_OUT=str(out), RDMESH_FC_WORK=str(tmp_path),
               RDMESH_FC_STEP=str(NIST), RDMESH_FC_DEVIATION_REL=repr(DEVIATION_REL),
               RDMESH_FREECAD_DIR=str(REPO / "clients" / "freecad"),
               RDMESH_CLIENT_DIR=str(REPO / "clients" / "python"))
    env.pop("DISPLAY", None)  # headless, as on CI
    proc = subprocess.run([FREECADCMD, str(pathlib.Path(__file__).with_name(job))], capture_output=True, text=True, timeout=600,
                          env=env, stdin=subprocess.DEVNULL)
    assert out.exists(), "FreeCADCmd exited %d without a report:\n%s\n%s" % (
        proc.returncode, proc.stdout[-3000:], proc.stderr[-3000:])
    report = json.loads(out.read_text())
    assert report["ok"], report.get("error")
    report["log"] = proc.stdout[-3000:] + proc.stderr[-3000:]
    return report


def test_freecad_client_meshes_visible_shapes_watertight_in_face_groups(daemon, client, tmp_path):
    report = run_freecad(daemon, tmp_path)
    # The hidden box is left alone; the STEP part and the tube are meshed.
    assert report["meshed_sources"] == ["StepPart", "Tube"], report["log"]
    for mesh in report["meshes"]:
        name = mesh["source"]
        # The triangle count of a direct Python-client mesh of the BREP that FreeCAD sent.
        direct = client.mesh(mesh["brep"], max_deviation_rel=DEVIATION_REL)
        assert direct.summary.faces_failed == 0, name
        assert mesh["facets"] == len(direct.triangles) > 0, name
        assert mesh["points"] == len(direct.xyz), name
        # FreeCAD holds the very triangles, in order (its points are single precision).
        assert np.array_equal(np.array(mesh["facet_list"]), direct.triangles), name
        assert np.allclose(np.array(mesh["point_list"]), direct.xyz, rtol=1e-6, atol=1e-6), name
        # Watertight: every edge is used by exactly two facets, and FreeCAD agrees.
        assert mesh["open_edges"] == 0 and mesh["overused_edges"] == 0, name
        assert mesh["is_solid"] and not mesh["non_manifolds"], name
        # One segment per B-rep face, in face order, sized as the direct mesh's faces.
        expected = [(f.face_id, len(f.triangles)) for f in direct.faces if len(f.triangles)]
        assert mesh["segments"] == len(expected) == mesh["faces"], name
        assert list(zip(mesh["segment_faces"], mesh["segment_sizes"])) == expected, name
        # Segment k's facets lie on FreeCAD's Face<id> (within the deviation).
        assert mesh["worst_off_face"] <= 1.01 * mesh["requested_deviation"], name
        assert mesh["deviations"] == mesh["facets"], name
        assert mesh["largest_facet_deviation"] == mesh["max_deviation"], name
        assert 0 < mesh["max_deviation"] <= mesh["requested_deviation"] * (1 + 1e-9), name
        assert np.isclose(direct.summary.requested_deviation, mesh["requested_deviation"]), name
    # Segments are not saved by FreeCAD 0.20; the face ids saved with the feature restore them.
    assert report["segments_after_reload"] == 0
    assert report["segments_restored"] == report["meshes"][1]["segments"]


def test_freecad_workbench_command_meshes_the_selection(daemon, client, tmp_path):
    # FreeCAD's GUI, offscreen: the workbench loads from the Mod folder, and its command meshes
    # the selected sphere only (not the box beside it), at the deviation the dialog gave.
    report = run_freecad(daemon, tmp_path, "freecad_gui_job.py")
    assert report["workbench"]
    assert len(report["asked"]) == 1
    assert report["meshed_sources"] == ["Ball"], report["log"]
    assert report["segments"] == [1] and report["solid"] == [True]
    assert report["saved_address"] == daemon.address  # remembered for the next time
    direct = client.mesh(tmp_path / "Ball.brep", max_deviation_rel=DEVIATION_REL)
    assert report["facets"] == [len(direct.triangles)] and len(direct.triangles) > 0
