"""Run inside FreeCADCmd by test_freecad.py: starts FreeCAD's GUI offscreen with the rdmesh
workbench linked into $HOME's Mod folder, selects one of two visible shapes and runs the
workbench command (its dialogs answered by a stand-in), then writes what happened as JSON to
RDMESH_FC_OUT. Environment as freecad_job.py's."""

import json
import os
import traceback

out_path = os.environ["RDMESH_FC_OUT"]
report = {"ok": False}
try:
    import FreeCAD
    import FreeCADGui
    import Part

    FreeCADGui.showMainWindow()  # QT_QPA_PLATFORM=offscreen: no display needed
    report["workbench"] = "RdmeshWorkbench" in FreeCADGui.listWorkbenches()
    FreeCADGui.activateWorkbench("RdmeshWorkbench")
    import rdmesh_freecad  # on sys.path through the Mod folder

    asked = []

    def answer(address, deviation_rel):
        asked.append([address, deviation_rel])
        return os.environ["RDMESH_ADDRESS"], float(os.environ["RDMESH_FC_DEVIATION_REL"])

    rdmesh_freecad._ask = answer  # the modal dialogs would wait for a person
    doc = FreeCAD.newDocument("rdmesh_gui_test")
    box = doc.addObject("Part::Box", "Box")
    ball = doc.addObject("Part::Sphere", "Ball")
    doc.recompute()
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(ball)
    FreeCADGui.runCommand("Rdmesh_Mesh")
    meshes = [o for o in doc.Objects if hasattr(o, "RdmeshSource")]
    with open(os.path.join(os.environ["RDMESH_FC_WORK"], "Ball.brep"), "wb") as file:
        file.write(rdmesh_freecad.shape_brep(ball))
    report.update({
        "asked": asked,
        "meshed_sources": [m.RdmeshSource.Name for m in meshes],
        "facets": [m.Mesh.CountFacets for m in meshes],
        "segments": [m.Mesh.countSegments() for m in meshes],
        "solid": [m.Mesh.isSolid() for m in meshes],
        "saved_address": FreeCAD.ParamGet(rdmesh_freecad.PARAMS).GetString("Address"),
        "ok": True,
    })
except Exception:  # noqa: BLE001 - reported to the test
    report["error"] = traceback.format_exc()
with open(out_path, "w") as file:
    json.dump(report, file)
# FreeCAD's GUI keeps running after a script; leave at once.
os._exit(0)
