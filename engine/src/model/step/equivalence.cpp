#include "model/step/equivalence.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepGProp.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Quantity_ColorRGBA.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_AsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Iterator.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_LayerTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "core/parallel.h"

namespace rdmesh::step {

namespace {

int Count(const TopoDS_Shape& shape, TopAbs_ShapeEnum type) {
  TopTools_IndexedMapOfShape map;
  TopExp::MapShapes(shape, type, map);
  return map.Extent();
}

std::string LabelName(const TDF_Label& label) {
  Handle(TDataStd_Name) name;
  if (!label.FindAttribute(TDataStd_Name::GetID(), name)) return "";
  return TCollection_AsciiString(name->Get()).ToCString();
}

std::string ColorText(const Handle(XCAFDoc_ColorTool) & colors, const TDF_Label& label) {
  std::string text;
  static const char* const kTypes[] = {"generic", "surface", "curve"};  // XCAFDoc_ColorType
  for (int type = 0; type <= 2; ++type) {
    Quantity_ColorRGBA color;
    if (!colors->GetColor(label, static_cast<XCAFDoc_ColorType>(type), color)) continue;
    char buffer[96];
    std::snprintf(buffer, sizeof(buffer), " %s=(%.6f %.6f %.6f %.3f)", kTypes[type],
                  color.GetRGB().Red(), color.GetRGB().Green(), color.GetRGB().Blue(),
                  color.Alpha());
    text += buffer;
  }
  if (!colors->IsVisible(label)) text += " invisible";
  return text;
}

// The layers a label is in, sorted, each with " (hidden)" when invisible.
std::string LayerText(const Handle(XCAFDoc_LayerTool) & layers, const TDF_Label& label) {
  TDF_LabelSequence layer_labels;
  if (!layers->GetLayers(label, layer_labels) || layer_labels.IsEmpty()) return "";
  std::vector<std::string> names;
  for (const TDF_Label& layer : layer_labels) {
    TCollection_ExtendedString name;
    layers->GetLayer(layer, name);
    names.push_back(std::string("'") + TCollection_AsciiString(name).ToCString() + "'" +
                    (layers->IsVisible(layer) ? "" : " (hidden)"));
  }
  std::sort(names.begin(), names.end());
  std::string text = " layers=";
  for (size_t i = 0; i < names.size(); ++i) text += (i > 0 ? "," : "") + names[i];
  return text;
}

std::string LocationText(const TopLoc_Location& location) {
  const gp_Trsf trsf = location.Transformation();
  std::string text = " at";
  for (int r = 1; r <= 3; ++r)
    for (int c = 1; c <= 4; ++c) {
      char buffer[32];
      std::snprintf(buffer, sizeof(buffer), " %.9g", trsf.Value(r, c));
      text += buffer;
    }
  return text;
}

void DescribeLabel(const TDF_Label& label, const Handle(XCAFDoc_ShapeTool) & tool,
                   const Handle(XCAFDoc_ColorTool) & colors,
                   const Handle(XCAFDoc_LayerTool) & layers, int depth,
                   std::vector<std::string>* lines) {
  std::string indent(2 * depth, ' ');
  if (depth > 64) {
    lines->push_back(indent + "(too deep)");
    return;
  }
  if (XCAFDoc_ShapeTool::IsReference(label)) {
    TDF_Label referred;
    XCAFDoc_ShapeTool::GetReferredShape(label, referred);
    lines->push_back(indent + "instance '" + LabelName(label) + "'" +
                     LocationText(XCAFDoc_ShapeTool::GetLocation(label)) +
                     ColorText(colors, label) + LayerText(layers, label));
    DescribeLabel(referred, tool, colors, layers, depth + 1, lines);
    return;
  }
  if (XCAFDoc_ShapeTool::IsAssembly(label)) {
    lines->push_back(indent + "assembly '" + LabelName(label) + "'" + ColorText(colors, label) +
                     LayerText(layers, label));
    TDF_LabelSequence components;
    XCAFDoc_ShapeTool::GetComponents(label, components);
    for (const TDF_Label& component : components)
      DescribeLabel(component, tool, colors, layers, depth + 1, lines);
    return;
  }
  const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
  lines->push_back(indent + "part '" + LabelName(label) + "' " +
                   (shape.IsNull() ? "null" : TopAbs::ShapeTypeToString(shape.ShapeType())) +
                   ColorText(colors, label) + LayerText(layers, label));
  TDF_LabelSequence subs;
  XCAFDoc_ShapeTool::GetSubShapes(label, subs);
  if (subs.IsEmpty() || shape.IsNull()) return;
  TopTools_IndexedMapOfShape faces, solids;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  TopExp::MapShapes(shape, TopAbs_SOLID, solids);
  std::vector<std::string> sub_lines;
  for (const TDF_Label& sub : subs) {
    const TopoDS_Shape s = XCAFDoc_ShapeTool::GetShape(sub);
    std::string what = "sub-shape";
    if (!s.IsNull() && s.ShapeType() == TopAbs_FACE)
      what = "face " + std::to_string(faces.FindIndex(s));
    else if (!s.IsNull() && s.ShapeType() == TopAbs_SOLID)
      what = "solid " + std::to_string(solids.FindIndex(s));
    // A sub-shape label that carries nothing (OCCT's GD&T and validation property reading
    // make such labels for the faces they refer to) is left out.
    const std::string attributes = ColorText(colors, sub) + LayerText(layers, sub);
    if (attributes.empty() && !sub.IsAttribute(TDataStd_Name::GetID())) continue;
    sub_lines.push_back(indent + "  " + what + " '" + LabelName(sub) + "'" + attributes);
  }
  std::sort(sub_lines.begin(), sub_lines.end());
  lines->insert(lines->end(), sub_lines.begin(), sub_lines.end());
}

}  // namespace

ShapeSummary Summarize(const ReadShape& read, int threads) {
  ShapeSummary summary;
  const TopoDS_Shape& shape = read.shape;
  if (shape.IsNull()) return summary;
  summary.solids = Count(shape, TopAbs_SOLID);
  summary.shells = Count(shape, TopAbs_SHELL);
  TopTools_IndexedMapOfShape edges, vertices;
  TopExp::MapShapes(shape, TopAbs_EDGE, edges);
  TopExp::MapShapes(shape, TopAbs_VERTEX, vertices);
  summary.edges = edges.Extent();
  summary.vertices = vertices.Extent();
  for (int i = 1; i <= vertices.Extent(); ++i) {
    const gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(vertices(i)));
    summary.vertex_points.push_back({p.X(), p.Y(), p.Z()});
    summary.vertex_tolerances.push_back(BRep_Tool::Tolerance(TopoDS::Vertex(vertices(i))));
  }
  for (int i = 1; i <= edges.Extent(); ++i)
    summary.edge_tolerances.push_back(BRep_Tool::Tolerance(TopoDS::Edge(edges(i))));
  for (int i = 1; i <= edges.Extent(); ++i) {
    std::string text;
    for (TopoDS_Iterator it(edges(i), Standard_False); it.More(); it.Next())
      text += std::to_string(vertices.FindIndex(it.Value())) + "/" +
              std::to_string(static_cast<int>(it.Value().Orientation())) + " ";
    summary.edge_vertices.push_back(text);
  }
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  summary.faces = faces.Extent();
  summary.face_types.assign(summary.faces, -1);
  summary.face_areas.assign(summary.faces, 0.0);
  ParallelRunner(threads).For(
      0, summary.faces,
      [&](int i) {
        const TopoDS_Face& face = TopoDS::Face(faces(i + 1));
        try {
          summary.face_types[i] = BRepAdaptor_Surface(face, Standard_False).GetType();
          GProp_GProps props;
          BRepGProp::SurfaceProperties(face, props);
          summary.face_areas[i] = props.Mass();
        } catch (const Standard_Failure&) {
          summary.face_areas[i] = std::nan("");
        }
      },
      Partition::kOnePerTask);
  Bnd_Box box;
  try {
    BRepBndLib::AddOptimal(shape, box, Standard_False, Standard_False);
  } catch (const Standard_Failure&) {
    box.SetVoid();
  }
  if (!box.IsVoid()) {
    box.Get(summary.box[0], summary.box[1], summary.box[2], summary.box[3], summary.box[4],
            summary.box[5]);
    summary.has_box = true;
  }
  if (!read.doc.IsNull()) {
    Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(read.doc->Main());
    Handle(XCAFDoc_ColorTool) colors = XCAFDoc_DocumentTool::ColorTool(read.doc->Main());
    TDF_LabelSequence free;
    tool->GetFreeShapes(free);
    Handle(XCAFDoc_LayerTool) layers = XCAFDoc_DocumentTool::LayerTool(read.doc->Main());
    for (const TDF_Label& label : free)
      DescribeLabel(label, tool, colors, layers, 0, &summary.document);
  }
  return summary;
}

Comparison Compare(const ShapeSummary& ours, const ShapeSummary& theirs, double area_rel,
                   double box_rel) {
  Comparison result;
  auto differ = [&](const std::string& what) {
    if (result.difference.empty()) result.difference = what;
  };
  auto counts = [&](const char* what, int a, int b) {
    if (a != b) differ(std::string(what) + " " + std::to_string(a) + " vs " + std::to_string(b));
  };
  counts("solids", ours.solids, theirs.solids);
  counts("shells", ours.shells, theirs.shells);
  counts("faces", ours.faces, theirs.faces);
  counts("edges", ours.edges, theirs.edges);
  if (ours.faces == theirs.faces) {
    for (int i = 0; i < ours.faces; ++i) {
      if (ours.face_types[i] != theirs.face_types[i]) {
        differ("face " + std::to_string(i + 1) + " surface type " +
               std::to_string(ours.face_types[i]) + " vs " + std::to_string(theirs.face_types[i]));
      }
      const double a = ours.face_areas[i], b = theirs.face_areas[i];
      const double scale = std::max(std::abs(a), std::abs(b));
      const double rel = scale > 0 ? std::abs(a - b) / scale : (a == b ? 0.0 : 1.0);
      if (!(rel <= result.worst_area_rel)) result.worst_area_rel = std::isnan(rel) ? 1.0 : rel;
      if (!(rel <= area_rel)) {
        char buffer[160];
        std::snprintf(buffer, sizeof(buffer), "face %d area %.17g vs %.17g (relative %.3g)", i + 1,
                      a, b, rel);
        differ(buffer);
      }
    }
  }
  if (ours.has_box != theirs.has_box) {
    differ("bounding box present in one read only");
  } else if (ours.has_box) {
    double diagonal = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = theirs.box[k + 3] - theirs.box[k];
      diagonal += d * d;
    }
    diagonal = std::sqrt(diagonal);
    for (int k = 0; k < 6; ++k) {
      const double rel = diagonal > 0 ? std::abs(ours.box[k] - theirs.box[k]) / diagonal : 0;
      result.worst_box_rel = std::max(result.worst_box_rel, rel);
    }
    if (result.worst_box_rel > box_rel) {
      char buffer[96];
      std::snprintf(buffer, sizeof(buffer), "bounding box differs by %.3g of its diagonal",
                    result.worst_box_rel);
      differ(buffer);
    }
  }
  auto without_cr = [](std::vector<std::string> lines) {
    for (std::string& line : lines)
      line.erase(std::remove(line.begin(), line.end(), '\r'), line.end());
    return lines;
  };
  if (ours.document != theirs.document &&
      without_cr(ours.document) == without_cr(theirs.document)) {
    size_t i = 0;
    while (ours.document[i] == theirs.document[i]) ++i;
    result.name_line_break_difference =
        "document line " + std::to_string(i + 1) + ": a name differs by carriage returns only";
  } else if (ours.document != theirs.document) {
    size_t i = 0;
    while (i < ours.document.size() && i < theirs.document.size() &&
           ours.document[i] == theirs.document[i])
      ++i;
    differ("document line " + std::to_string(i + 1) + ": '" +
           (i < ours.document.size() ? ours.document[i] : std::string("(end)")) + "' vs '" +
           (i < theirs.document.size() ? theirs.document[i] : std::string("(end)")) + "'");
  }
  if (ours.vertices != theirs.vertices) {
    result.numbering_difference =
        "vertices " + std::to_string(ours.vertices) + " vs " + std::to_string(theirs.vertices);
  } else if (ours.vertex_points != theirs.vertex_points) {
    result.numbering_difference = "vertex order";
  } else if (ours.edge_vertices != theirs.edge_vertices) {
    for (size_t i = 0; i < ours.edge_vertices.size() && i < theirs.edge_vertices.size(); ++i) {
      if (ours.edge_vertices[i] == theirs.edge_vertices[i]) continue;
      result.numbering_difference = "edge " + std::to_string(i + 1) + " vertices " +
                                    ours.edge_vertices[i] + "vs " + theirs.edge_vertices[i];
      break;
    }
  }
  auto tolerances = [&](const char* what, const std::vector<double>& a,
                        const std::vector<double>& b) {
    if (!result.tolerance_difference.empty() || a.size() != b.size()) return;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i] == b[i]) continue;
      char buffer[128];
      std::snprintf(buffer, sizeof(buffer), "%s %zu tolerance %.17g vs %.17g", what, i + 1, a[i],
                    b[i]);
      result.tolerance_difference = buffer;
      return;
    }
  };
  tolerances("edge", ours.edge_tolerances, theirs.edge_tolerances);
  tolerances("vertex", ours.vertex_tolerances, theirs.vertex_tolerances);
  result.equivalent = result.difference.empty();
  return result;
}

}  // namespace rdmesh::step
