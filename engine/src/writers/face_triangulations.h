#pragma once
// Lends a MeshResult to the model's faces as OCCT Poly_Triangulations, for OCCT's document
// writers (RWGltf_CafWriter, RWObj_CafWriter), which read triangulations from the faces.

#include <BRep_TFace.hxx>
#include <Poly_ListOfTriangulation.hxx>
#include <Poly_Triangulation.hxx>
#include <TDocStd_Document.hxx>
#include <mutex>
#include <vector>

#include "model/model.h"
#include "rdmesh/mesh.h"

namespace rdmesh {

/// While alive, every face TShape of `model` carries the mesh of one face of its instance class
/// (the representative's when it is ok, else the first ok instance's; none when no instance is
/// ok). Triangulations are in the TShape's frame with nodes, uv and normals; triangles follow
/// the TShape orientation (OCCT readers flip them for REVERSED or mirrored faces), normals are
/// the TShape surface's. The destructor restores the faces' previous triangulations, so the
/// shared Model looks unchanged afterwards.
/// Thread-safety: holds a process-wide mutex for its lifetime, so two writers never lend at
/// once; the meshing engine must not read face triangulations (it does not).
/// With `uv_face_ids`, each node's (u, v) is (face id, 0) instead of the surface parameters: the
/// id of the face that owns the TShape (the first instance), for WriteGlb to turn into _FACE_ID.
class ScopedFaceTriangulations {
 public:
  ScopedFaceTriangulations(const Model& model, const MeshResult& result, bool uv_face_ids = false);
  ~ScopedFaceTriangulations();
  ScopedFaceTriangulations(const ScopedFaceTriangulations&) = delete;
  ScopedFaceTriangulations& operator=(const ScopedFaceTriangulations&) = delete;

 private:
  struct Saved {
    Handle(BRep_TFace) tface;
    Poly_ListOfTriangulation triangulations;
    Handle(Poly_Triangulation) active;
  };

  std::unique_lock<std::mutex> lock_;
  std::vector<Saved> saved_;
};

/// The model's XCAF document, or for models without one (.brep) a new document holding the
/// shape (compounds become assemblies, so shared solids stay instanced).
Handle(TDocStd_Document) DocumentForWriting(const Model& model);

}  // namespace rdmesh
