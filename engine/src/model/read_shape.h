#pragma once
// What a model reader produced (a shape, its XCAF document, its unit): the common currency of the
// readers, the stored payload and the model build. Internal to the engine.
#include <Standard_Handle.hxx>
#include <TDocStd_Document.hxx>
#include <TopoDS_Shape.hxx>
#include <string>
#include <utility>
#include <vector>

namespace rdmesh {

/// What a reader produced: the shape, the XCAF document (null for BREP) and the file's length
/// unit ("" when the format has none).
struct ReadShape {
  TopoDS_Shape shape;
  Handle(TDocStd_Document) doc;
  std::string length_unit;
  double unit_scale_mm = 1.0;
  /// Where the load's time went so far, in order (stage name, seconds; SecondsSince in
  /// rdmesh/context.h): ModelInfo::load_stages.
  std::vector<std::pair<std::string, double>> stages;
  /// Which reader built it: "rdmesh" (model/step), "occt", or "" (BREP, IGES, a stored payload).
  std::string reader;
  /// Why rdmesh's own STEP reader passed the file to OCCT's ("" when it did not).
  std::string reader_note;
  /// Where a reader knew them without building a document (doc null): the placed part instances
  /// and the parts' distinct names, as the document would give them (ModelInfo::instances and
  /// part_names); instances < 0 when not known.
  int instances = -1;
  std::vector<std::string> part_names;
};

/// The document's free shapes (with their locations) as one compound: the model's shape.
TopoDS_Shape FreeShapesCompound(const Handle(TDocStd_Document) & doc);

}  // namespace rdmesh
