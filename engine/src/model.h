#pragma once
// The loaded B-rep: shape, ids, instancing and the XCAF document. Internal to the engine.

#include <Standard_Handle.hxx>
#include <TDocStd_Document.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <gp_Trsf.hxx>
#include <string>
#include <vector>

#include "rdmesh/engine.h"

namespace rdmesh {

/// An immutable loaded model. Safe to read from many threads at once, as long as every thread
/// builds its own OCCT adaptors (BRepAdaptor_* cache state and are not thread-safe).
class Model {
 public:
  /// The whole shape: a compound of the document's free shapes, with instance locations applied.
  TopoDS_Shape shape;
  /// The XCAF document (names, colours, assembly structure); null for .brep files.
  Handle(TDocStd_Document) doc;

  /// Ids: face id f is faces(f), edge id e is edges(e), vertex id v is vertices(v), all
  /// TopExp::MapShapes order of `shape`, 1-based. Shapes carry their full location.
  TopTools_IndexedMapOfShape faces;
  TopTools_IndexedMapOfShape edges;
  TopTools_IndexedMapOfShape vertices;

  /// Per face id - 1: the face id that is meshed for it. A face whose TShape already appeared
  /// under another location (an instanced part) points at that first occurrence; others point
  /// at themselves.
  std::vector<int> face_representative;
  /// Per face id - 1: transform from the representative's world frame to this face's world frame
  /// (identity for representatives).
  std::vector<gp_Trsf> face_placement;
  /// Per face id - 1: true when this face's orientation differs from its representative's.
  std::vector<bool> face_flipped;

  /// Per face id - 1: exact area (model units^2).
  std::vector<double> face_area;

  /// Largest BRep tolerance over all edges (model units): the model's own precision.
  double max_edge_tolerance = 0.0;

  ModelInfo info;

  int face_count() const { return faces.Extent(); }
  int edge_count() const { return edges.Extent(); }
  const TopoDS_Face& face(int id) const;  ///< id 1..F
  const TopoDS_Edge& edge(int id) const;  ///< id 1..E
};

struct ReadShape;

/// The Model of what a reader produced: ids, instancing, face areas, model info. `name` appears
/// in messages, `display_name` in ModelInfo. kEmptyModel, or kParseError for invalid topology.
Result<std::shared_ptr<const Model>> BuildModel(ReadShape read, ModelFormat format,
                                                const std::string& name,
                                                const std::string& display_name);

}  // namespace rdmesh
