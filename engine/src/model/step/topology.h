#pragma once
// STEP topology (ISO 10303-42 B-reps) to TopoDS shapes, built as OCCT 7.6's StepToTopoDS builds
// them (Builder, TranslateShell/Face/EdgeLoop/Edge/Vertex): one TopoDS vertex per VERTEX_POINT and
// one edge per EDGE_CURVE within a representation item, the same vertex merging, the same edge
// parameters (projections of the vertices on the curve), the file's pcurves where OCCT takes
// them, the same wire and face orientations. The healing that follows is model/step/heal_items.h.
#include <TopTools_DataMapOfShapeShape.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Wire.hxx>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "model/step/geometry.h"

namespace rdmesh::step {

/// The representation items BuildItem makes shapes of: the B-reps MANIFOLD_SOLID_BREP,
/// BREP_WITH_VOIDS, SHELL_BASED_SURFACE_MODEL, and the wireframes GEOMETRIC_CURVE_SET and
/// GEOMETRIC_SET (of curves and points).
bool IsBrepItem(const Entities& entities, const Instance& instance);

/// One B-rep representation item, built and then healed.
struct BrepItem {
  uint64_t id = 0;
  UnitFactors units;
  TopoDS_Shape raw;     ///< as StepToTopoDS_Builder leaves it
  TopoDS_Shape healed;  ///< after ShapeFix, what OCCT's reader binds to the item
  /// The faces and shells as built (id, raw shape), for the styled items that point at them;
  /// HealedShape maps them to what the healing made of them.
  std::vector<std::pair<uint64_t, TopoDS_Shape>> bound;
  /// What the healing replaced each sub-shape of `raw` with (down to edges), as OCCT's
  /// ShapeProcess_ShapeContext records it; empty when the healing changed nothing.
  TopTools_DataMapOfShapeShape modified;
  /// Curve entities whose Geom curve this item's edges use (shared with other items through
  /// Geometry::SharedCurve): items sharing one are healed one after the other.
  std::vector<uint64_t> curves;
  /// A curve set's elements (curves and points), bound to their edges and vertices in OCCT's
  /// transfer process: one used elsewhere too (another set, an edge's curve) is not reproduced.
  std::vector<uint64_t> elements;
};

/// Puts an edge's parameters on its 3D curve (the projections of its vertices) in increasing
/// order as OCCT 7.6's STEP reader does (StepToTopoDS_GeometricTool::UpdateParam3d), without
/// loading its toolkit: clamped to a bounded open curve's ends; on a periodic curve moved by
/// periods; on a closed curve (or a B-spline whose ends meet within `preci`) an end taken on the
/// wrong side of the seam moves to the other side, else the two are swapped; on any other curve
/// a decreasing pair reverses the curve itself (shared: the caller's other edges see it).
void OrderEdgeParameters(const Handle(Geom_Curve) & curve, double& w1, double& w2, double preci);

/// OCCT 7.6's check of a pcurve read from the file (XSAlgo_AlgoContainer::CheckPCurve under
/// XSAlgo's defaults), without loading TKXSBase: removes a pcurve that spans several periods of
/// the surface or whose ends miss the edge's by more than `preci`; otherwise makes it
/// same-parameter on a scratch edge, lets a projection of the 3D curve replace it where that
/// gives a lower tolerance, and puts the result back on `edge`. `seam`: the edge is a seam of
/// `face`. False when it removed the pcurve or there was none (or no 3D curve) to check.
bool CheckPCurve(const TopoDS_Edge& edge, const TopoDS_Face& face, double preci, bool seam);

/// Builds the raw shape of `item.id` (StepToTopoDS_Builder::Init). Throws Unsupported where
/// OCCT's reader would drop a face, an edge or a wire, or builds something not reproduced here.
void BuildItem(Geometry& geometry, BrepItem* item);

/// Initialises, once per process, the OCCT globals BuildItem and HealItem use (the shape
/// healing algorithm containers, lazily built planes), so HealItem may run in parallel.
void PrepareOcct();

}  // namespace rdmesh::step
