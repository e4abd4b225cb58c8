#pragma once
// OCCT's document framework (XCAF: part names, colours, the assembly tree, and its binary
// format), apart from the rest of the engine. Its toolkits (TKXCAF, TKLCAF, TKCDF, TKBinXCAF,
// TKRWMesh and what TKXCAF pulls in: TKV3d, TKService, FreeImage, OpenEXR, X11) are half of the
// dynamic loading of a program that links them: 22 ms of the rdmesh CLI's 38 ms start-up. A
// run needs them only to keep a document: for the .glb and .obj writers, the model store, a
// STEP file with an assembly, or a file read by OCCT's readers. `rdmesh_engine` has them built
// in; a program linked to `rdmesh_engine_lean` (the rdmesh CLI) loads them from the module
// rdmesh_occt_xcaf.so beside its executable the first time a run needs them.
// Internal to the engine.

#include <string>
#include <vector>

#include "model/model.h"
#include "model/read_shape.h"
#include "model/step/document_plan.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Changes whenever XcafApi or what it passes changes: a module of another build is refused.
constexpr int kXcafApiVersion = 1;

struct XcafApi {
  int version;
  /// STEPCAFControl_Reader::Transfer's document from the translator's plan: sets read->doc and
  /// read->shape (the document's free shapes). OCCT exceptions leave it as thrown.
  void (*build_step_document)(const step::DocumentPlan& plan, ReadShape* read);
  /// The document in OCCT's BinXCAF format (model_payload.h).
  Result<std::string> (*write_document)(const Handle(TDocStd_Document) & doc);
  /// The document in `payload` (BinXCAF), with its free shapes' compound as the shape.
  Result<ReadShape> (*read_document)(const std::string& payload);
  /// The placed leaf parts of the document's assembly tree, and the parts' distinct names.
  void (*walk_parts)(const Handle(TDocStd_Document) & doc, int* instances,
                     std::vector<std::string>* names);
  /// WriteGlb and WriteObj (writers/gltf_writer.h, writers/obj_writer.h).
  Status (*write_glb)(const Model& model, const MeshResult& result,
                      const std::vector<EdgeLine>& edges, bool compress, const std::string& path);
  Status (*write_obj)(const Model& model, const MeshResult& result,
                      const std::vector<EdgeLine>& edges, const std::string& path);
};

/// The document framework's entry points: built in, or loaded from the module once per process
/// (its errors then, as LoadEngineModule's).
Result<const XcafApi*> Xcaf();

}  // namespace rdmesh
