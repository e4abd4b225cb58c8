#include "writers/gltf_writer.h"

#include <Message_ProgressRange.hxx>
#include <RWGltf_CafWriter.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_IndexedDataMapOfStringString.hxx>

#include "writers/face_triangulations.h"
#include "writers/gltf_ids.h"
#include "writers/output_file.h"

namespace rdmesh {

Status WriteGlb(const Model& model, const MeshResult& result, const std::vector<EdgeLine>& edges,
                bool compress, const std::string& path) {
  try {
    Handle(TDocStd_Document) doc = DocumentForWriting(model);
    ScopedFaceTriangulations lent(model, result, /*uv_face_ids=*/true);
    RWGltf_CafWriter writer(path.c_str(), /*theIsBinary=*/true);
    writer.SetTransformationFormat(RWGltf_WriterTrsfFormat_Compact);
    writer.SetNodeNameFormat(RWMesh_NameFormat_ProductOrInstance);  // part names on nodes
    writer.SetMergeFaces(true);      // one primitive per part instead of one per face
    writer.SetForcedUVExport(true);  // (face id, 0), which AddGltfIdsAndEdges makes _FACE_ID
    writer.ChangeCoordinateSystemConverter().SetInputLengthUnit(0.001);  // mm -> m
    writer.ChangeCoordinateSystemConverter().SetInputCoordinateSystem(RWMesh_CoordinateSystem_Zup);
    TColStd_IndexedDataMapOfStringString file_info;
    file_info.Add("generator", "rdmesh");
    if (!writer.Perform(doc, file_info, Message_ProgressRange()))
      return WriteError(path, "the glTF writer failed (directory missing or not writable?)");
  } catch (const Standard_Failure& failure) {
    return WriteError(path, std::string("the glTF writer failed: ") + failure.GetMessageString());
  }
  return AddGltfIdsAndEdges(model, result, edges, compress, path);
}

}  // namespace rdmesh
