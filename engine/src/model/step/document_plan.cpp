#include "model/step/document_plan.h"

#include <BRep_Builder.hxx>
#include <TCollection_AsciiString.hxx>
#include <TCollection_ExtendedString.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Iterator.hxx>
#include <set>

namespace rdmesh::step {
namespace {

// A name as the document's label holds it and ModelInfo reads it back (TDataStd_Name through
// TCollection_ExtendedString): the same bytes as the document path gives.
std::string DocumentName(const std::string& utf8) {
  return TCollection_AsciiString(TCollection_ExtendedString(utf8.c_str(), Standard_True))
      .ToCString();
}

TopoDS_Shape Unlocated(const TopoDS_Shape& shape) {
  TopoDS_Shape unlocated = shape;
  unlocated.Location(TopLoc_Location());
  return unlocated;
}

}  // namespace

bool LeanShape(const DocumentPlan& plan, ReadShape* read) {
  // A plain structure: each root is a label of its own (distinct, unlocated), which
  // XCAFDoc_ShapeTool::AddShape stores as it is (no compound of it holds a product's or a
  // representation's shape, which would make it an assembly).
  const std::size_t n = plan.roots.size();
  for (std::size_t i = 0; i < n; ++i) {
    const TopoDS_Shape& root = plan.roots[i];
    if (root.IsNull() || !root.Location().IsIdentity()) return false;
    for (std::size_t j = 0; j < i; ++j)
      if (plan.roots[j].IsSame(root)) return false;
    if (root.ShapeType() != TopAbs_COMPOUND) continue;
    for (TopoDS_Iterator it(root); it.More(); it.Next())
      if (plan.new_shapes.Contains(Unlocated(it.Value()))) return false;
  }
  // Each root's name is the last one given to its shape. A name given to a root placed
  // elsewhere would reach its label through XCAFDoc_ShapeTool::Search: left to the document.
  std::vector<const std::string*> names(n, nullptr);
  for (const PlannedName& planned : plan.names) {
    bool root = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (!planned.shape.IsSame(plan.roots[i])) continue;
      names[i] = &planned.name;
      root = true;
    }
    if (root) continue;
    const TopoDS_Shape unlocated = Unlocated(planned.shape);
    for (const TopoDS_Shape& other : plan.roots)
      if (unlocated.IsSame(other)) return false;
  }
  // An unnamed root would carry the document's automatic name.
  for (const std::string* name : names)
    if (name == nullptr) return false;

  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  for (const TopoDS_Shape& root : plan.roots) builder.Add(compound, root);
  read->shape = compound;
  read->instances = static_cast<int>(n);
  read->part_names.clear();
  std::set<std::string> seen;
  for (const std::string* name : names) {
    std::string text = DocumentName(*name);
    if (!text.empty() && seen.insert(text).second) read->part_names.push_back(std::move(text));
  }
  return true;
}

}  // namespace rdmesh::step
