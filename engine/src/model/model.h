#pragma once
// The loaded B-rep: shape, ids, instancing and the XCAF document. Internal to the engine.

#include <Standard_Handle.hxx>
#include <TDocStd_Document.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <array>
#include <gp_Trsf.hxx>
#include <memory>
#include <string>
#include <vector>

#include "model/model_payload.h"
#include "rdmesh/context.h"
#include "rdmesh/model_info.h"
#include "rdmesh/status.h"

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

  /// Adjacency, as plain id lists. Per face id - 1: its edge ids, each once, in the order a
  /// TopExp_Explorer first meets them; per edge id - 1: the ids of the faces it bounds, each
  /// once, ascending (the order of TopExp::MapShapesAndAncestors).
  std::vector<std::vector<int>> face_edges;
  std::vector<std::vector<int>> edge_faces;

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

/// A model parsed from its file, and its canonical payload: the model is what the payload reads
/// back as (see ParseCanonical).
struct CanonicalModel {
  std::shared_ptr<const Model> model;
  std::string payload;  ///< OCCT binary bytes (model_payload.h), of `kind`
  PayloadKind kind = PayloadKind::kBinXcaf;
};

/// "step", "iges", "brep" ("unknown" for kAuto): ModelInfo::format.
const char* FormatName(ModelFormat format);

/// The whole file at `path`, with LoadModel's errors (kNotFound, kIoError).
Result<std::string> ReadModelFile(const std::string& path);

/// Reads the bytes of a model file (`format` kAuto: from the content), writes what the reader
/// produced as a payload (BinXCAF, or BinTools for BREP), reads that back and builds the Model
/// of THAT: OCCT's binary formats do not restore every bit the readers produced (BinTools
/// rebuilds a plane's axes, re-orthogonalising its X direction), so a model parsed here and one
/// read later from its stored payload (model_store.h) are the same bits and mesh identically.
/// `path` is the file on disk ("" when none), `name` appears in messages, `display_name` in
/// ModelInfo. The reader's errors, or the context's stop status.
Result<CanonicalModel> ParseCanonical(const std::string& bytes, ModelFormat format,
                                      const std::string& path, const std::string& name,
                                      const std::string& display_name, Context* context);

/// What BuildModel computes slowly (exact face areas, the tight bounding box): a stored model
/// brings them along, so that reading it is not dominated by recomputing them. Exactly the values
/// BuildModel computed for the same payload, so a model built with them is the same.
struct DerivedValues {
  std::vector<double> face_area;  ///< Model::face_area
  std::array<double, 6> bbox{};   ///< ModelInfo::bbox
  double diagonal = 0.0;          ///< ModelInfo::diagonal
};

/// The DerivedValues of a built model.
DerivedValues DerivedValuesOf(const Model& model);

/// The Model of what a reader produced: ids, instancing, face areas, model info. `name` appears
/// in messages, `display_name` in ModelInfo. With `derived`, face areas and the bounding box are
/// taken from it (kParseError when it does not fit the shape) instead of computed. kEmptyModel,
/// or kParseError for invalid topology.
Result<std::shared_ptr<const Model>> BuildModel(ReadShape read, ModelFormat format,
                                                const std::string& name,
                                                const std::string& display_name,
                                                const DerivedValues* derived = nullptr);

}  // namespace rdmesh
