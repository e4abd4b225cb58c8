#pragma once
// What a model reader produced (a shape, its XCAF document, its unit): the common currency of the
// readers, the stored payload and the model build. Internal to the engine.
#include <Standard_Handle.hxx>
#include <TDocStd_Document.hxx>
#include <TopoDS_Shape.hxx>
#include <string>

namespace rdmesh {

/// What a reader produced: the shape, the XCAF document (null for BREP) and the file's length
/// unit ("" when the format has none).
struct ReadShape {
  TopoDS_Shape shape;
  Handle(TDocStd_Document) doc;
  std::string length_unit;
  double unit_scale_mm = 1.0;
};

/// The document's free shapes (with their locations) as one compound: the model's shape.
TopoDS_Shape FreeShapesCompound(const Handle(TDocStd_Document) & doc);

}  // namespace rdmesh
