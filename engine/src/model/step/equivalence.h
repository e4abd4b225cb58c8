#pragma once
// Whether two reads of one STEP file give the same model, as the engine uses it: the same solids,
// faces and edges (in TopExp::MapShapes order), the same surface type and area per face, the
// same bounding box, and an XCAF document with the same assembly tree, names and colours. For
// the translator's tests and its equivalence bench (bench/robustness/step_equivalence.cpp).
#include <array>
#include <string>
#include <vector>

#include "model/read_shape.h"

namespace rdmesh::step {

/// What the comparison looks at, of one read.
struct ShapeSummary {
  int solids = 0, shells = 0, faces = 0, edges = 0, vertices = 0;
  std::vector<int> face_types;     ///< GeomAbs_SurfaceType per face
  std::vector<double> face_areas;  ///< BRepGProp surface area per face
  /// Per edge (TopExp::MapShapes order): its vertices' ids in the edge's own order, with their
  /// orientations, so edge and vertex numbering can be compared.
  std::vector<std::string> edge_vertices;
  std::vector<std::array<double, 3>> vertex_points;        ///< per vertex id
  std::vector<double> edge_tolerances, vertex_tolerances;  ///< per edge and vertex id
  std::array<double, 6> box{};  ///< BRepBndLib::AddOptimal, without tolerances
  bool has_box = false;
  /// The document as lines: every label under the free shapes with its kind (assembly,
  /// instance with its placement, part), name, colours, visibility and layers, and its
  /// sub-shapes (faces by index) that have a name, a colour, a visibility or a layer.
  std::vector<std::string> document;
};

/// Summarises `read`: counts, per-face types and areas (on `threads` threads, 0 = all cores),
/// the box and the document.
ShapeSummary Summarize(const ReadShape& read, int threads = 0);

struct Comparison {
  bool equivalent = false;
  std::string difference;     ///< the first difference found, "" when equivalent
  double worst_area_rel = 0;  ///< largest |a - b| / max(|a|, |b|) over faces
  double worst_box_rel = 0;   ///< largest box coordinate difference / box diagonal
  /// Where vertex numbering or the vertices of edges differ (not part of `equivalent`: the
  /// engine numbers faces and edges, and those are compared), "" when identical.
  std::string numbering_difference;
  /// Where edge or vertex tolerances differ, "" when identical (not part of `equivalent`).
  std::string tolerance_difference;
  /// Where the documents differ only by carriage returns in names, "" otherwise (not part of
  /// `equivalent`): OCCT's STEP lexer keeps the CR of a CRLF line break inside a string (it
  /// drops the LF), where Part 21 (and DecodeString) drops line breaks; KiCad's long DSUB names.
  std::string name_line_break_difference;
};

/// Compares two summaries: exact counts, types and document; areas within `area_rel`
/// (relative), the box within `box_rel` of its diagonal.
Comparison Compare(const ShapeSummary& ours, const ShapeSummary& theirs, double area_rel = 1e-9,
                   double box_rel = 1e-9);

}  // namespace rdmesh::step
