#pragma once
// The healing of built STEP items (model/step/topology.h) with the ShapeFix calls and settings of
// OCCT's reader (XSAlgo_AlgoContainer::ProcessShape without a resource file): whole, as OCCT runs
// it, or face by face in parallel where that gives the same B-rep.
#include <Geom2d_Curve.hxx>
#include <TopoDS_Shape.hxx>
#include <functional>
#include <string>
#include <vector>

#include "model/step/topology.h"

namespace rdmesh::step {

/// Heals `item.raw` into `item.healed` as XSAlgo_AlgoContainer::ProcessShape does by default:
/// ShapeFix_Shape with the item's precision and maximum tolerance, same-parameter fixing off in
/// the wire tool, no open solids. Thread-safe for items that share no TShapes or Geom objects.
void HealItem(BrepItem* item);

/// Heals every item as HealItem does, the faces of all items in parallel: each face is fixed
/// by ShapeFix_Face (as ShapeFix_Shell would) on private copies of its edges and vertices; where
/// that changed nothing but pcurves, ranges, tolerances and flags, the copies are merged back
/// into shared edges and the shell, solid, same-parameter and vertex tolerance stages of
/// ShapeFix_Shape run on the result. An item whose faces' fixing changed more (an edge removed,
/// split or added, a wire reordered or reversed) is healed by HealItem instead, as OCCT does.
/// `stop` is polled between faces.
struct HealStats {
  int items_face_parallel = 0;  ///< items healed face by face (the others by HealItem)
  std::string refused;          ///< why the first other item was not, e.g. "shared edge's curve"
  double face_seconds = 0;      ///< the parallel face fixing
  /// Items where a face's fixing cut a shared edge's range, whose faces then found their edges
  /// and vertices as the faces before them left them, and how many faces that fixed again.
  int items_in_order = 0;
  int faces_fixed_again = 0;
  double finish_seconds = 0;  ///< merging, the shell and solid stages, and HealItem fallbacks
  /// Pcurves on planes the fixing stored and left on the healed items (OCCT projects them on
  /// demand and stores none): RemovePcurves takes them off once the last stage that reads them
  /// has run.
  std::vector<Handle(Geom2d_Curve)> kept_pcurves;
};
HealStats HealItems(const std::vector<BrepItem*>& items, int threads,
                    const std::function<bool()>& stop);

/// Removes from every edge of `shape` the curve-on-surface representations whose pcurve is one
/// of `pcurves`.
void RemovePcurves(const TopoDS_Shape& shape, const std::vector<Handle(Geom2d_Curve)>& pcurves);

/// The shape OCCT's reader binds to a face, shell or item after healing (MergeTransferInfo):
/// what the healing replaced `raw` with, `raw` when untouched, null when removed.
TopoDS_Shape HealedShape(const BrepItem& item, const TopoDS_Shape& raw);

}  // namespace rdmesh::step
