#include "model/step/document_plan.h"

#include <BRep_Builder.hxx>
#include <NCollection_DataMap.hxx>
#include <TCollection_AsciiString.hxx>
#include <TCollection_ExtendedString.hxx>
#include <TopAbs.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_ShapeMapHasher.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Iterator.hxx>
#include <set>
#include <vector>

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

// The labels XCAF's shape tool would hold for the plan's roots (STEPCAFControl_Reader's
// AddShape into XCAFDoc_ShapeTool, then UpdateAssemblies), for plans whose roots are unlocated:
// top-level labels in the order the tool makes them, each a part (a shape stored as it is) or
// an assembly (a new compound of its components), and the components of each assembly.
class LeanLabels {
 public:
  explicit LeanLabels(const DocumentPlan& plan) : plan_(plan) {}

  // DocumentBuilder::AddShape's walk; false where the tool would do what this does not follow
  // (a located shape outside an assembly's components).
  bool Add(const TopoDS_Shape& shape, int* label) {
    if (const int* found = by_shape_.Seek(shape)) {
      *label = *found;
      return *found != kComponent;  // a placed shape stands for a component, not a label
    }
    if (!shape.Location().IsIdentity()) return false;
    bool assembly = false;
    if (shape.ShapeType() == TopAbs_COMPOUND) {
      for (TopoDS_Iterator it(shape); it.More() && !assembly; it.Next())
        assembly = plan_.new_shapes.Contains(Unlocated(it.Value()));
    }
    *label = static_cast<int>(labels_.size());
    labels_.push_back({assembly, shape, {}, nullptr, false, false});
    if (!assembly) {
      by_shape_.Bind(shape, *label);
      return true;
    }
    // XCAFDoc_ShapeTool::NewShape, then AddComponent per child: each child's own label first
    // (a part or an assembly), then the component that places it.
    for (TopoDS_Iterator it(shape); it.More(); it.Next()) {
      int child;
      if (!Add(Unlocated(it.Value()), &child)) return false;
      labels_[*label].components.push_back({child, it.Value().Location()});
      labels_[child].referred = true;
      // A located child names its component, which no part name reads (WalkParts).
      if (!by_shape_.IsBound(it.Value())) by_shape_.Bind(it.Value(), kComponent);
    }
    by_shape_.Bind(shape, *label);
    return true;
  }

  // ApplyNames: the last name given to a label's shape; false for a name whose shape the map
  // does not hold (XCAFDoc_ShapeTool::Search would look for it).
  bool Name() {
    for (const PlannedName& planned : plan_.names) {
      if (planned.shape.IsNull()) continue;
      const int* found = by_shape_.Seek(planned.shape);
      if (found == nullptr) return false;
      if (*found != kComponent) labels_[*found].name = &planned.name;
    }
    return true;
  }

  // FreeShapesCompound: the shapes of the labels no component refers to, in order, an
  // assembly's as UpdateAssemblies builds it; and DocumentParts' placed parts and names.
  void Fill(ReadShape* read) {
    BRep_Builder builder;
    TopoDS_Compound compound;
    builder.MakeCompound(compound);
    read->instances = 0;
    read->part_names.clear();
    std::set<std::string> seen;
    for (int i = 0; i < static_cast<int>(labels_.size()); ++i) {
      if (labels_[i].referred) continue;
      builder.Add(compound, ShapeOf(i));
      Walk(i, read, &seen);
    }
    read->shape = compound;
  }

 private:
  static constexpr int kComponent = -1;
  struct Component {
    int label;
    TopLoc_Location location;
  };
  struct Label {
    bool assembly;
    TopoDS_Shape shape;  // a part's; an assembly's once built
    std::vector<Component> components;
    const std::string* name;  // null: the shape tool's automatic one
    bool referred;
    bool built;  // an assembly's shape rebuilt from its components
  };

  // XCAFDoc_ShapeTool::updateComponent: a new compound of the components, a part placed by
  // its component's location (GetShape's Move), a sub-assembly's compound relocated.
  const TopoDS_Shape& ShapeOf(int i) {
    Label& label = labels_[i];
    if (!label.assembly || label.built) return label.shape;
    BRep_Builder builder;
    TopoDS_Compound compound;
    builder.MakeCompound(compound);
    for (const Component& c : label.components) {
      TopoDS_Shape shape = ShapeOf(c.label);
      if (labels_[c.label].assembly)
        shape.Location(c.location, Standard_False);
      else
        shape.Move(c.location, Standard_False);
      builder.Add(compound, shape);
    }
    labels_[i].built = true;
    return labels_[i].shape = compound;
  }

  void Walk(int i, ReadShape* read, std::set<std::string>* seen) const {
    const Label& label = labels_[i];
    if (label.assembly) {
      for (const Component& c : label.components) Walk(c.label, read, seen);
      return;
    }
    ++read->instances;
    std::string text;
    if (label.name != nullptr) {
      text = DocumentName(*label.name);
    } else {
      // XCAFDoc_ShapeTool's automatic name: the shape type as TopAbs::Print writes it.
      text = TopAbs::ShapeTypeToString(label.shape.ShapeType());
    }
    if (!text.empty() && seen->insert(text).second) read->part_names.push_back(std::move(text));
  }

  const DocumentPlan& plan_;
  std::vector<Label> labels_;
  NCollection_DataMap<TopoDS_Shape, int, TopTools_ShapeMapHasher> by_shape_;
};

}  // namespace

bool LeanShape(const DocumentPlan& plan, ReadShape* read) {
  // Roots placed elsewhere or given twice are left to the document (XCAF makes references).
  const std::size_t n = plan.roots.size();
  for (std::size_t i = 0; i < n; ++i) {
    const TopoDS_Shape& root = plan.roots[i];
    if (root.IsNull() || !root.Location().IsIdentity()) return false;
    for (std::size_t j = 0; j < i; ++j)
      if (plan.roots[j].IsSame(root)) return false;
  }
  LeanLabels labels(plan);
  for (const TopoDS_Shape& root : plan.roots) {
    int label;
    if (!labels.Add(root, &label)) return false;
  }
  if (!labels.Name()) return false;
  labels.Fill(read);
  return true;
}

}  // namespace rdmesh::step
