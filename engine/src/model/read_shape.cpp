#include "model/read_shape.h"

#include <BRep_Builder.hxx>
#include <TDF_LabelSequence.hxx>
#include <TopoDS_Compound.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

namespace rdmesh {

TopoDS_Shape FreeShapesCompound(const Handle(TDocStd_Document) & doc) {
  Handle(XCAFDoc_ShapeTool) shape_tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  TDF_LabelSequence labels;
  shape_tool->GetFreeShapes(labels);
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  for (const TDF_Label& label : labels) {
    TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
    if (!shape.IsNull()) builder.Add(compound, shape);
  }
  return compound;
}

}  // namespace rdmesh
