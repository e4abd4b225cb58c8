"""Run inside FreeCADCmd by test_freecad.py: builds a document, meshes it through the rdmesh
FreeCAD client against the daemon at RDMESH_ADDRESS, and writes what FreeCAD holds afterwards as
JSON to RDMESH_FC_OUT.

Environment: RDMESH_FREECAD_DIR (clients/freecad), RDMESH_CLIENT_DIR (clients/python),
RDMESH_FC_STEP (a STEP file to place in the document), RDMESH_FC_OUT (the JSON to write),
RDMESH_FC_WORK (a folder for the BREP files sent and the saved document), RDMESH_FC_DEVIATION_REL.
"""

import json
import os
import sys
import traceback

out_path = os.environ["RDMESH_FC_OUT"]
try:
    import FreeCAD
    import Part

    sys.path.insert(0, os.environ["RDMESH_FREECAD_DIR"])
    import rdmesh_freecad

    work = os.environ["RDMESH_FC_WORK"]
    doc = FreeCAD.newDocument("rdmesh_test")
    # A STEP part, a parametric cylinder with a hole (curved faces, seams), and a hidden box that
    # must not be meshed (nothing selected: every visible shape is).
    step = doc.addObject("Part::Feature", "StepPart")
    shape = Part.Shape()
    shape.read(os.environ["RDMESH_FC_STEP"])
    step.Shape = shape
    tube = doc.addObject("Part::Feature", "Tube")
    tube.Shape = Part.makeCylinder(10, 30).cut(Part.makeCylinder(4, 30))
    tube.Placement = FreeCAD.Placement(FreeCAD.Vector(100, 0, 0), FreeCAD.Rotation(0, 0, 30))
    hidden = doc.addObject("Part::Box", "HiddenBox")
    doc.recompute()
    hidden.Visibility = False

    # The macro itself, as FreeCAD runs it, on the preferences it reads (the address comes from
    # RDMESH_ADDRESS, which wins over the preference).
    rdmesh_freecad.save_settings("127.0.0.1:1", float(os.environ["RDMESH_FC_DEVIATION_REL"]))
    macro = os.path.join(os.environ["RDMESH_FREECAD_DIR"], "RdmeshMesh.FCMacro")
    with open(macro) as file:
        exec(compile(file.read(), macro, "exec"), {"__file__": macro, "__name__": "__main__"})
    done = [(o.RdmeshSource, o) for o in doc.Objects if hasattr(o, "RdmeshSource")]
    report = {"meshes": []}
    for source, feature in done:
        brep_path = os.path.join(work, source.Name + ".brep")
        with open(brep_path, "wb") as file:
            file.write(rdmesh_freecad.shape_brep(source))
        mesh = feature.Mesh
        # Edge uses from FreeCAD's own facet list: 2 each on a watertight mesh.
        uses = {}
        for facet in mesh.Topology[1]:
            for k in range(3):
                a, b = facet[k], facet[(k + 1) % 3]
                key = (min(a, b), max(a, b))
                uses[key] = uses.get(key, 0) + 1
        # Each segment's facets lie on the B-rep face of that id (FreeCAD's FaceN): the largest
        # distance of a few facet centroids per segment from their face.
        placed = Part.getShape(source)
        groups = rdmesh_freecad.face_groups(feature.RdmeshFaceIds)
        worst_off_face = 0.0
        for k, (face_id, facet_ids) in enumerate(groups):
            segment = sorted(mesh.getSegment(k))
            assert segment == facet_ids, "segment %d is not face %d's facets" % (k, face_id)
            face = placed.Faces[face_id - 1]
            for index in facet_ids[:: max(1, len(facet_ids) // 4)]:
                points = [mesh.Points[i].Vector for i in mesh.Topology[1][index]]
                centroid = (points[0] + points[1] + points[2]) * (1.0 / 3.0)
                worst_off_face = max(worst_off_face,
                                     face.distToShape(Part.Vertex(centroid))[0])
        report["meshes"].append({
            "source": source.Name, "brep": brep_path, "faces": len(placed.Faces),
            "facets": mesh.CountFacets, "points": mesh.CountPoints,
            "facet_list": [list(f) for f in mesh.Topology[1]],
            "point_list": [[p.x, p.y, p.z] for p in mesh.Topology[0]],
            "is_solid": mesh.isSolid(), "non_manifolds": mesh.hasNonManifolds(),
            "open_edges": sum(1 for n in uses.values() if n == 1),
            "overused_edges": sum(1 for n in uses.values() if n > 2),
            "segments": mesh.countSegments(), "segment_faces": [f for f, _ in groups],
            "segment_sizes": [len(ids) for _, ids in groups],
            "worst_off_face": worst_off_face,
            "deviations": len(feature.RdmeshDeviation),
            "max_deviation": feature.RdmeshMaxDeviation,
            "requested_deviation": feature.RdmeshRequestedDeviation,
            "largest_facet_deviation": max(feature.RdmeshDeviation),
        })
    report["meshed_sources"] = [s.Name for s, _ in done]
    # The face groups survive saving: FreeCAD drops the segments, RdmeshFaceIds restores them.
    saved = os.path.join(work, "meshed.FCStd")
    doc.saveAs(saved)
    FreeCAD.closeDocument(doc.Name)
    reopened = FreeCAD.openDocument(saved)
    feature = reopened.getObject("Tube_rdmesh")
    report["segments_after_reload"] = feature.Mesh.countSegments()
    report["segments_restored"] = rdmesh_freecad.mesh_segments(feature).countSegments()
    report["ok"] = True
except Exception:  # noqa: BLE001 - reported to the test
    report = {"ok": False, "error": traceback.format_exc()}
with open(out_path, "w") as file:
    json.dump(report, file)
