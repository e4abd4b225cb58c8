#include "writers/obj_writer.h"

#include <Message_ProgressRange.hxx>
#include <RWObj_CafWriter.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_IndexedDataMapOfStringString.hxx>

#include "writers/face_triangulations.h"
#include "writers/output_file.h"

namespace rdmesh {

Status WriteObj(const Model& model, const MeshResult& result, const std::string& path) {
  if (result.mesh.triangle_count() == 0) {  // RWObj_CafWriter refuses to write nothing
    OutputFile out;
    Status opened = out.Open(path);
    if (!opened.ok()) return opened;
    out.Text("# written by rdmesh: no faces were meshed\n");
    return out.Close();
  }
  try {
    Handle(TDocStd_Document) doc = DocumentForWriting(model);
    ScopedFaceTriangulations lent(model, result);
    RWObj_CafWriter writer(path.c_str());
    TColStd_IndexedDataMapOfStringString file_info;
    file_info.Add("generator", "rdmesh");
    if (!writer.Perform(doc, file_info, Message_ProgressRange()))
      return WriteError(path, "the OBJ writer failed (directory missing or not writable?)");
  } catch (const Standard_Failure& failure) {
    return WriteError(path, std::string("the OBJ writer failed: ") + failure.GetMessageString());
  }
  return Status::Ok();
}

}  // namespace rdmesh
