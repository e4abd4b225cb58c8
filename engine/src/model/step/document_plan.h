#pragma once
// What the STEP translator read of a file's product structure, names, colours and layers, as
// plain data: the XCAF document is built from it (model/xcaf_document.cpp, OCCT's
// STEPCAFControl_Reader::Transfer step by step) only where a run keeps the document; the
// product structure gives the model's shape and part names without one (LeanShape below).
// Internal to the engine.

#include <Quantity_Color.hxx>
#include <Quantity_ColorRGBA.hxx>
#include <TopTools_MapOfShape.hxx>
#include <TopoDS_Shape.hxx>
#include <optional>
#include <string>
#include <vector>

#include "model/read_shape.h"

namespace rdmesh::step {

/// A name for the label of `shape` (STEPCAFControl_Reader::ReadNames), in the file's order.
struct PlannedName {
  TopoDS_Shape shape;
  std::string name;  ///< UTF-8
};

/// One styled item's colours (STEPCAFControl_Reader::ReadColors), in the styles' order.
struct PlannedStyle {
  TopoDS_Shape shape;
  bool visible = true;
  std::optional<Quantity_ColorRGBA> surface;  ///< fill area or rendering colour
  std::optional<Quantity_Color> boundary;
  std::optional<Quantity_Color> curve;
};

/// One PRESENTATION_LAYER_ASSIGNMENT with transferred items (STEPCAFControl_Reader::ReadLayers).
struct PlannedLayer {
  std::string name;  ///< UTF-8
  bool visible = true;
  std::vector<TopoDS_Shape> items;
};

/// The document of a translated file, before OCCT's document framework builds it.
struct DocumentPlan {
  std::vector<TopoDS_Shape> roots;  ///< the roots' shapes, in order
  /// The shapes of product definitions and shape representations among the roots and their
  /// compounds' components (unlocated): a compound holding one is an assembly.
  TopTools_MapOfShape new_shapes;
  std::vector<PlannedName> names;
  bool has_styles = false;  ///< the file has styled items (the colours' tree is then reordered)
  std::vector<PlannedStyle> styles;
  std::vector<PlannedLayer> layers;
};

/// The shape and parts the document would give, without building it, where every root is a
/// distinct unlocated shape and every name's shape is one the document maps (a part, an
/// assembly or a component; not a sub-shape). Then sets read->shape (FreeShapesCompound of the
/// document: its free labels' shapes, an assembly's rebuilt from its components as
/// XCAFDoc_ShapeTool::UpdateAssemblies builds it), read->instances and read->part_names
/// (DocumentParts), and returns true; else false, and the caller builds the document.
bool LeanShape(const DocumentPlan& plan, ReadShape* read);

}  // namespace rdmesh::step
