#pragma once
// The last stages of OCCT's healing and transfer, with the same results, their costly checks run
// in parallel: ShapeFix::SameParameter and ShapeFix_Shape's vertex-tolerance pass (deviation and
// vertex checks in parallel, the tolerance updates replayed in OCCT's order) and
// BRepLib::EncodeRegularity (one edge per task: each call changes its own edge only).
#include <ShapeFix_Edge.hxx>
#include <TopoDS_Shape.hxx>

#include "core/parallel.h"

namespace rdmesh::step {

/// ShapeFix::SameParameter(shape, false, 0) as ShapeFix_Shape runs it. For shapes whose edges are
/// all same-parameter and same-range (ShapeFix then only measures deviations and raises
/// tolerances); false, and nothing done, otherwise (the caller runs OCCT's).
bool SameParameterInParallel(const TopoDS_Shape& shape, const ParallelRunner& runner);

/// The vertex-tolerance pass that ends ShapeFix_Shape::Perform on `shape` (its result so far):
/// every edge of every face checked, vertices copied with larger tolerances through `tool`'s
/// context, in OCCT's order.
void FixVertexTolerancesInParallel(const TopoDS_Shape& shape, const Handle(ShapeFix_Edge) & tool,
                                   const ParallelRunner& runner);

/// ShapeFix_Shape's shell and solid stages as the reader runs them on items whose faces are
/// fixed already (ShapeFix_Shell without face fixing, ShapeFix_Solid without open solids), where
/// they provably change nothing: every solid holds one shell, every shell's faces are distinct
/// and connected through edges each used once FORWARD and once REVERSED (or, in a shell outside
/// a solid, once: a free edge; degenerated edges also once), and no solid is inside out. Then the
/// flags those stages set are set and true is returned; otherwise nothing is done and false is
/// returned (the caller runs OCCT's). The solids' orientation test builds its face intersectors
/// on `runner`.
bool ShellAndSolidStagesWithoutChange(const TopoDS_Shape& shape, const ParallelRunner& runner);

/// BRepLib::EncodeRegularity(shape, angle).
void EncodeRegularityInParallel(const TopoDS_Shape& shape, double angle,
                                const ParallelRunner& runner);

}  // namespace rdmesh::step
