"""rdmesh in FreeCAD: mesh the active document's shapes on an rdmeshd server.

Each shape goes to the server as BREP text made in memory (Shape.exportBrepToString), through
the rdmesh Python client (clients/python), and comes back as a Mesh::Feature whose mesh is the
server's watertight mesh:
  - one mesh segment per B-rep face, in face id order (segment k holds the facets of the k-th
    face that has triangles; the face ids are FreeCAD's own Face1, Face2, ... numbering, since
    both number the faces in TopExp::MapShapes order);
  - the properties RdmeshFaceIds (the B-rep face id of every facet) and RdmeshDeviation (every
    facet's estimated distance to the exact surface), which are saved with the document (FreeCAD
    0.20 does not save mesh segments; mesh_segments() rebuilds them from RdmeshFaceIds).

Used by the RdmeshMesh.FCMacro macro and the Rdmesh workbench command, and headless from
FreeCADCmd (tests/python/test_freecad.py).
"""

import os
import sys

PARAMS = "User parameter:BaseApp/Preferences/Mod/rdmesh"
DEFAULT_ADDRESS = "127.0.0.1:50051"
DEFAULT_DEVIATION_REL = 1e-3


def _import_client():
    """The rdmesh package: importable already, or found through RDMESH_CLIENT_DIR, the
    preference ClientDir, or beside this file (clients/python in the repository)."""
    try:
        import rdmesh  # noqa: F401
        return rdmesh
    except ImportError:
        pass
    here = os.path.dirname(os.path.realpath(__file__))
    candidates = [os.environ.get("RDMESH_CLIENT_DIR"), _param_string("ClientDir"),
                  os.path.join(here, "..", "python")]
    for folder in candidates:
        if folder and os.path.isfile(os.path.join(folder, "rdmesh", "client.py")):
            sys.path.insert(0, os.path.abspath(folder))
            import rdmesh
            return rdmesh
    raise ImportError("the rdmesh Python client was not found: set RDMESH_CLIENT_DIR (or the "
                      "preference %s/ClientDir) to the repository's clients/python" % PARAMS)


def _param_string(name, default=""):
    try:
        import FreeCAD
        return FreeCAD.ParamGet(PARAMS).GetString(name, default)
    except ImportError:
        return default


def settings():
    """(address, relative deviation): RDMESH_ADDRESS or the preference Address, and the
    preference DeviationRel (a fraction of the shape's bounding-box diagonal)."""
    address = os.environ.get("RDMESH_ADDRESS") or _param_string("Address") or DEFAULT_ADDRESS
    try:
        rel = float(_param_string("DeviationRel") or DEFAULT_DEVIATION_REL)
    except ValueError:
        rel = DEFAULT_DEVIATION_REL
    return address, rel


def save_settings(address, deviation_rel):
    import FreeCAD
    params = FreeCAD.ParamGet(PARAMS)
    params.SetString("Address", address)
    params.SetString("DeviationRel", repr(float(deviation_rel)))


def targets(doc, selection=None):
    """The objects to mesh: those of `selection` (FreeCADGui.Selection objects) that have a
    shape, else every visible object of `doc` that has a non-empty shape and is no mesh."""
    def has_shape(obj):
        shape = getattr(obj, "Shape", None)
        return shape is not None and not shape.isNull() and len(shape.Faces) > 0

    chosen = [o for o in (selection or []) if has_shape(o)]
    if chosen:
        return chosen
    return [o for o in doc.Objects
            if getattr(o, "Visibility", True) and has_shape(o)
            and not o.isDerivedFrom("Mesh::Feature")]


def shape_brep(obj):
    """The object's shape, placed where the document shows it, as BREP bytes."""
    import Part
    try:
        shape = Part.getShape(obj)  # with the placements of the containers it lies in
    except Exception:  # noqa: BLE001 - older or unusual objects
        shape = obj.Shape
    return shape.exportBrepToString().encode()


def mesh_shape(client, name, brep, max_deviation=None, max_deviation_rel=None, timeout=None):
    """Meshes BREP bytes on the server: the rdmesh MeshResult (with per-triangle deviations)."""
    info = client.upload(brep, name=name + ".brep", timeout=timeout)
    return client.mesh(info, timeout=timeout, triangle_deviation=True,
                       max_deviation=max_deviation, max_deviation_rel=max_deviation_rel)


def to_freecad_mesh(result):
    """A Mesh.Mesh of the result's watertight mesh (facets in the result's triangle order) with
    one segment per B-rep face that has triangles, in face id order."""
    import FreeCAD
    import Mesh
    points = [FreeCAD.Vector(*map(float, p)) for p in result.xyz]
    facets = [tuple(int(i) for i in t) for t in result.triangles]
    mesh = Mesh.Mesh((points, facets))
    for face_id, facet_ids in face_groups(result.triangle_face):
        mesh.addSegment(facet_ids)
    return mesh


def face_groups(triangle_face):
    """[(face id, [facet indices])] in face id order, from the face id of every facet."""
    groups = {}
    for index, face_id in enumerate(triangle_face):
        groups.setdefault(int(face_id), []).append(index)
    return sorted(groups.items())


def mesh_segments(feature):
    """Restores a saved rdmesh mesh feature's segments from its RdmeshFaceIds property."""
    mesh = feature.Mesh.copy()
    if mesh.countSegments() == 0:
        for _, facet_ids in face_groups(feature.RdmeshFaceIds):
            mesh.addSegment(facet_ids)
        feature.Mesh = mesh
    return feature.Mesh


def add_mesh_feature(doc, source, result):
    """Adds `result` to `doc` as a Mesh::Feature beside `source` (the object it meshes)."""
    feature = doc.addObject("Mesh::Feature", source.Name + "_rdmesh")
    feature.Label = source.Label + " (rdmesh)"
    feature.Mesh = to_freecad_mesh(result)
    props = [("App::PropertyLink", "RdmeshSource", "the object this mesh was made from"),
             ("App::PropertyIntegerList", "RdmeshFaceIds", "B-rep face id of every facet"),
             ("App::PropertyFloatList", "RdmeshDeviation",
              "estimated facet-surface distance of every facet, model units"),
             ("App::PropertyFloat", "RdmeshMaxDeviation", "largest estimated deviation"),
             ("App::PropertyFloat", "RdmeshRequestedDeviation", "deviation asked for"),
             ("App::PropertyString", "RdmeshModelId", "sha256 of the BREP sent")]
    for kind, name, doc_string in props:
        feature.addProperty(kind, name, "rdmesh", doc_string)
    feature.RdmeshSource = source
    feature.RdmeshFaceIds = [int(f) for f in result.triangle_face]
    if result.triangle_deviation is not None:
        feature.RdmeshDeviation = [float(d) for d in result.triangle_deviation]
    feature.RdmeshMaxDeviation = float(result.summary.estimated_deviation)
    feature.RdmeshRequestedDeviation = float(result.summary.requested_deviation)
    feature.RdmeshModelId = result.model.model_id
    return feature


def run(doc=None, selection=None, address=None, max_deviation=None, max_deviation_rel=None,
        timeout=None, client=None, report=print):
    """Meshes the chosen objects of `doc` (targets()) on the server at `address` and adds a mesh
    feature for each. An absolute `max_deviation` wins over `max_deviation_rel` (a fraction of
    each shape's bounding-box diagonal; default the preference, else 1e-3). Returns the list of
    (source object, mesh feature, MeshResult)."""
    import FreeCAD
    _import_client()
    from rdmesh import Client
    doc = doc or FreeCAD.ActiveDocument
    if doc is None:
        raise RuntimeError("no active document")
    default_address, default_rel = settings()
    if max_deviation is None and max_deviation_rel is None:
        max_deviation_rel = default_rel
    objects = targets(doc, selection)
    if not objects:
        raise RuntimeError("nothing to mesh: select a shape, or show one")
    own = client is None
    client = client or Client(address or default_address)
    done = []
    try:
        for obj in objects:
            result = mesh_shape(client, obj.Name, shape_brep(obj), max_deviation,
                                max_deviation_rel, timeout)
            feature = add_mesh_feature(doc, obj, result)
            done.append((obj, feature, result))
            s = result.summary
            report("rdmesh: %s: %d faces (%d failed), %d triangles, deviation %.4g (asked %.4g)"
                   % (obj.Label, result.model.faces, s.faces_failed, len(result.triangles),
                      s.estimated_deviation, s.requested_deviation))
    finally:
        if own:
            client.close()
    doc.recompute()
    return done


def _ask(address, deviation_rel):
    """Address and relative deviation from two dialogs; None when cancelled."""
    from PySide import QtGui
    address, ok = QtGui.QInputDialog.getText(None, "rdmesh", "rdmeshd address (host:port):",
                                             text=address)
    if not ok:
        return None
    deviation_rel, ok = QtGui.QInputDialog.getDouble(
        None, "rdmesh", "Max deviation (fraction of each shape's bounding-box diagonal):",
        deviation_rel, 1e-7, 0.5, 7)
    if not ok:
        return None
    return address, deviation_rel


def main():
    """The macro and the workbench command: in the GUI, asks for the address and deviation
    (remembered as preferences) and meshes the selection (or every visible shape); in FreeCADCmd,
    meshes every visible shape of the active document with the preferences."""
    import FreeCAD
    address, deviation_rel = settings()
    selection = None
    if FreeCAD.GuiUp:
        import FreeCADGui
        selection = FreeCADGui.Selection.getSelection()
        answer = _ask(address, deviation_rel)
        if answer is None:
            return None
        address, deviation_rel = answer
        save_settings(address, deviation_rel)
    try:
        return run(selection=selection, address=address, max_deviation_rel=deviation_rel,
                   report=lambda line: FreeCAD.Console.PrintMessage(line + "\n"))
    except Exception as error:  # noqa: BLE001 - shown to the user
        FreeCAD.Console.PrintError("rdmesh: %s\n" % error)
        if FreeCAD.GuiUp:
            from PySide import QtGui
            QtGui.QMessageBox.warning(None, "rdmesh", str(error))
        return None
