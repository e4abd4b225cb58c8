#pragma once
// The pcurves of a run's faces, looked up once: each face's wires in walking order with the
// pcurves of their edges, its (u,v) bounds, and the pcurve of any of its edges, in parallel,
// before the edge grids. OCCT answers BRep_Tool::CurveOnSurface for an edge of a plane that stores
// no pcurve by projecting the edge's curve anew (a loaded model stores them: StorePlanePcurves in
// model.cpp), BRepTools::UVBounds asks for every edge's pcurve of the face, and
// BRepTools_WireExplorer maps the wire's vertices; the edge grids, healing and each
// face's domain asked all this several times per face and edge, and with two threads the
// reference counts of the locations those lookups copy were shared by both.

#include <Geom2d_Curve.hxx>
#include <Standard_Handle.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <utility>
#include <vector>

#include "geometry/surface.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;

/// An edge's curve in a face's (u,v) and its parameter range; a null curve when the face has
/// none for the edge.
struct Pcurve {
  Handle(Geom2d_Curve) curve;
  double first = 0, last = 0;
};

/// One edge of a face's wire, as BRepTools_WireExplorer walks it: its edge id (0 when the
/// model's edge map lacks it), whether the face uses it REVERSED, and its pcurve on the face
/// (null when there is none).
struct WireEdge {
  int eid = 0;
  bool reversed = false;
  Handle(Geom2d_Curve) pcurve;
};

/// A loop of a face: FORWARD and REVERSED edges of one of its wires in walking order (a wire the
/// wire explorer cannot walk is chained by its edges' ends, and may make more than one loop).
/// `reached` fails when the walk could not reach them all (edges that do not connect end to end).
struct FaceWire {
  std::vector<WireEdge> edges;
  Status reached;
};

/// The wires of a face (its FORWARD orientation), and the periods of its surface (0 where it is
/// not periodic).
struct FaceLoops {
  std::vector<FaceWire> wires;
  double period_u = 0, period_v = 0;
};

/// Whether the shape's placement is a rigid motion (no scaling).
bool RigidlyPlaced(const TopoDS_Shape& shape);

/// `face` and `edge` without the face's placement, when that is a rigid motion and the edge shares
/// it: OCCT's answers about the edge on the face (its pcurve, whether it is a seam) are the same
/// there, since OCCT works in the surface's frame, but it need not walk the placement's chain of
/// locations to get there. Otherwise the two as they are.
std::pair<TopoDS_Face, TopoDS_Edge> InOwnFrame(const TopoDS_Face& face, const TopoDS_Edge& edge);

/// What faces a run works on know of their pcurves. Read-only once built, from any thread. A
/// face it was not built for, or one OCCT failed on while it was built, is looked up from OCCT
/// at every call, with OCCT's exceptions: the same answers either way.
class FacePcurves {
 public:
  /// Nothing built: every lookup goes to OCCT.
  FacePcurves() = default;

  /// Looks up the pcurves and bounds of `faces` (face ids), in parallel.
  static FacePcurves Build(const Model& model, const std::vector<int>& faces, int threads,
                           Context* context);

  /// Lets go of everything, on up to `threads` threads (the table holds a handle per pcurve,
  /// and a run's last stages need none of them).
  void Release(int threads);

  /// BRep_Tool::CurveOnSurface(edge, face): `face` is model.face(face_id) in any orientation,
  /// `edge` is model.edge(edge_id) in any orientation, one of the face's edges (the orientation
  /// picks a seam's side, as in OCCT).
  Pcurve Find(int face_id, const TopoDS_Face& face, int edge_id, const TopoDS_Edge& edge) const;

  /// BRep_Tool::IsClosed(edge, face): whether the edge is a seam of the face (arguments as for
  /// Find).
  bool IsSeam(int face_id, const TopoDS_Face& face, int edge_id, const TopoDS_Edge& edge) const;

  /// BRepTools::UVBounds of face `face_id`.
  UvBounds Bounds(const Model& model, int face_id) const;

  /// The ids of face `face_id`'s edges, each time a TopExp_Explorer meets one, seams left out
  /// (they are no boundary); null for a face the table was not built for.
  const std::vector<int>* Rim(int face_id) const;

  /// The loops of face `face_id`: the table's, or for a face it was not built for, looked up
  /// from OCCT into `scratch` (with OCCT's exceptions).
  const FaceLoops& Loops(const Model& model, int face_id, FaceLoops* scratch) const;

 private:
  struct Entry {
    int eid = 0;
    bool second = false;  // a seam's second pcurve (the edge REVERSED in the FORWARD face)
    bool either = false;  // not a seam: the pcurve for both orientations
    Pcurve pcurve;
  };
  struct Face {
    bool built = false;
    UvBounds bounds;
    std::vector<Entry> entries;
    std::vector<int> rim;
    FaceLoops loops;
    // The entry for edge `eid` on the side `second`; null when there is none.
    const Pcurve* Lookup(int eid, bool second) const;
  };
  const Face* Built(int face_id) const;
  static void BuildFace(const Model& model, int face_id, Face* out);

  std::vector<Face> faces_;  // per face id - 1
};

}  // namespace rdmesh
