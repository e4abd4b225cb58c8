// CheckPCurve (model/step/topology.h) against the OCCT 7.6 function it stands in for,
// XSAlgo_AlgoContainer::CheckPCurve: on copies of every edge of every face of bundled models, the
// same pcurves (values at the range's ends and middle), ranges, tolerances and flags, with the
// file's precision and with one so fine that the projection branch runs, on pcurves moved by
// several periods or off their edge (the removal branches) and on reparametrised ones (a
// projection replaces them).

#include <gtest/gtest.h>

#include <BRepBuilderAPI_Copy.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeAnalysis_Edge.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <XSAlgo.hxx>
#include <XSAlgo_AlgoContainer.hxx>
#include <cstdio>
#include <gp_Trsf2d.hxx>
#include <gp_Vec2d.hxx>
#include <string>

#include "model/step/topology.h"

namespace rdmesh::step {
namespace {

TopoDS_Shape ReadWithOcct(const std::string& path) {
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) return TopoDS_Shape();
  reader.TransferRoots();
  return reader.OneShape();
}

// What CheckPCurve leaves on an edge of a face, to compare bit for bit.
struct EdgeState {
  bool has_pcurve = false;
  double first = 0, last = 0;
  gp_Pnt2d at_first, at_middle, at_last;
  double tolerance = 0, tolerance_v1 = 0, tolerance_v2 = 0;
  bool same_range = false, same_parameter = false;
  bool result = false;
};

EdgeState StateOf(const TopoDS_Edge& edge, const TopoDS_Face& face, bool result) {
  EdgeState state;
  state.result = result;
  Handle(Geom2d_Curve) pcurve;
  state.has_pcurve =
      ShapeAnalysis_Edge().PCurve(edge, face, pcurve, state.first, state.last, Standard_False);
  if (state.has_pcurve) {
    state.at_first = pcurve->Value(state.first);
    state.at_middle = pcurve->Value(0.5 * (state.first + state.last));
    state.at_last = pcurve->Value(state.last);
  }
  state.tolerance = BRep_Tool::Tolerance(edge);
  state.tolerance_v1 = BRep_Tool::Tolerance(TopExp::FirstVertex(edge));
  state.tolerance_v2 = BRep_Tool::Tolerance(TopExp::LastVertex(edge));
  state.same_range = BRep_Tool::SameRange(edge);
  state.same_parameter = BRep_Tool::SameParameter(edge);
  return state;
}

void ExpectSame(const EdgeState& ours, const EdgeState& occt) {
  EXPECT_EQ(ours.result, occt.result);
  ASSERT_EQ(ours.has_pcurve, occt.has_pcurve);
  if (ours.has_pcurve) {
    EXPECT_EQ(ours.first, occt.first);
    EXPECT_EQ(ours.last, occt.last);
    for (auto [a, b] :
         {std::pair(ours.at_first, occt.at_first), std::pair(ours.at_middle, occt.at_middle),
          std::pair(ours.at_last, occt.at_last)}) {
      EXPECT_EQ(a.X(), b.X());
      EXPECT_EQ(a.Y(), b.Y());
    }
  }
  EXPECT_EQ(ours.tolerance, occt.tolerance);
  EXPECT_EQ(ours.tolerance_v1, occt.tolerance_v1);
  EXPECT_EQ(ours.tolerance_v2, occt.tolerance_v2);
  EXPECT_EQ(ours.same_range, occt.same_range);
  EXPECT_EQ(ours.same_parameter, occt.same_parameter);
}

// How often OCCT's check kept and removed a pcurve, and replaced a kept one.
struct Branches {
  int kept = 0, removed = 0, pcurve_changed = 0;
};

// How a copy's pcurve is spoiled before the check, to reach the removal branches.
// kReparametrised keeps the pcurve's ends and moves an inner knot: same-parameter fixing then
// leaves a large tolerance, and a projection of the 3D curve replaces the pcurve.
enum class Spoil { kNone, kPeriods, kOffTheEdge, kReparametrised };

// Runs both checks on separate deep copies of face `f` of `shape`, edge by edge; returns how
// many edges were compared.
int CompareOnFace(const TopoDS_Shape& shape, int f, double preci, Spoil spoil, Branches* branches) {
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  const TopoDS_Face original = TopoDS::Face(faces(f));
  TopTools_IndexedMapOfShape original_edges;
  TopExp::MapShapes(original, TopAbs_EDGE, original_edges);
  int compared = 0;
  for (int e = 1; e <= original_edges.Extent(); ++e) {
    TopoDS_Face copies[2];
    TopoDS_Edge edges[2];
    for (int side = 0; side < 2; ++side) {
      copies[side] = TopoDS::Face(BRepBuilderAPI_Copy(original, true, false).Shape());
      TopTools_IndexedMapOfShape copy_edges;
      TopExp::MapShapes(copies[side], TopAbs_EDGE, copy_edges);
      edges[side] = TopoDS::Edge(copy_edges(e));
      // The edge as the face's wire holds it (orientation included).
      for (TopExp_Explorer ex(copies[side], TopAbs_EDGE); ex.More(); ex.Next())
        if (ex.Current().IsSame(edges[side])) edges[side] = TopoDS::Edge(ex.Current());
      if (spoil == Spoil::kNone) continue;
      Handle(Geom2d_Curve) pcurve;
      double first, last;
      if (!ShapeAnalysis_Edge().PCurve(edges[side], copies[side], pcurve, first, last,
                                       Standard_False))
        continue;
      if (BRep_Tool::IsClosed(edges[side], copies[side])) continue;  // a seam's pair stays
      Handle(Geom2d_Curve) moved;
      if (spoil == Spoil::kReparametrised) {
        Handle(Geom2d_BSplineCurve) spline =
            Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(pcurve, first, last));
        const double mid = 0.5 * (spline->FirstParameter() + spline->LastParameter());
        spline->InsertKnot(mid);
        for (int k = 2; k < spline->NbKnots(); ++k)
          if (spline->Knot(k) == mid) spline->SetKnot(k, 0.5 * (spline->Knot(k - 1) + mid));
        moved = spline;
      } else {
        moved = Handle(Geom2d_Curve)::DownCast(pcurve->Copy());
        gp_Trsf2d shift;
        shift.SetTranslation(spoil == Spoil::kPeriods ? gp_Vec2d(1e3, 1e3) : gp_Vec2d(0.1, 0.1));
        moved->Transform(shift);
      }
      BRep_Builder().UpdateEdge(edges[side], moved, copies[side],
                                BRep_Tool::Tolerance(edges[side]));
    }
    const bool seam = BRep_Tool::IsClosed(edges[0], copies[0]);
    const EdgeState before = StateOf(edges[1], copies[1], false);
    const bool ours = CheckPCurve(edges[0], copies[0], preci, seam);
    const bool occt = XSAlgo::AlgoContainer()->CheckPCurve(edges[1], copies[1], preci, seam);
    SCOPED_TRACE("face " + std::to_string(f) + " edge " + std::to_string(e));
    ExpectSame(StateOf(edges[0], copies[0], ours), StateOf(edges[1], copies[1], occt));
    (occt ? branches->kept : branches->removed) += 1;
    const EdgeState after = StateOf(edges[1], copies[1], occt);
    if (occt && (after.at_middle.X() != before.at_middle.X() ||
                 after.at_middle.Y() != before.at_middle.Y()))
      ++branches->pcurve_changed;
    ++compared;
  }
  return compared;
}

TEST(StepCheckPCurveTest, ChecksAsOcctsStepReader) {
  XSAlgo::Init();
  Branches branches;
  for (const char* name : {"cq_red_cube_blue_cylinder.step", "axom_sliced_cylinder.step",
                           "nist_mbe_pmi_11.stp", "pyocc_eight_cyl.stp"}) {
    SCOPED_TRACE(name);
    TopoDS_Shape shape = ReadWithOcct(std::string(RDMESH_TEST_DATA) + "/" + name);
    ASSERT_FALSE(shape.IsNull());
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(shape, TopAbs_FACE, faces);
    int compared = 0;
    for (int f = 1; f <= faces.Extent(); ++f) {
      for (double preci : {1e-7, 1e-13})
        compared += CompareOnFace(shape, f, preci, Spoil::kNone, &branches);
      compared += CompareOnFace(shape, f, 1e-7, Spoil::kPeriods, &branches);
      compared += CompareOnFace(shape, f, 1e-7, Spoil::kOffTheEdge, &branches);
      compared += CompareOnFace(shape, f, 1e-7, Spoil::kReparametrised, &branches);
    }
    EXPECT_GT(compared, 0);
  }
  // Every branch ran: pcurves kept, removed, and kept ones replaced by a projection.
  EXPECT_GT(branches.kept, 0);
  EXPECT_GT(branches.removed, 0);
  EXPECT_GT(branches.pcurve_changed, 0);
  std::printf("kept %d, removed %d, replaced %d\n", branches.kept, branches.removed,
              branches.pcurve_changed);
}

}  // namespace
}  // namespace rdmesh::step
