// FacePcurves: a run's table of pcurves and (u,v) bounds answers exactly what OCCT answers.

#include "boundary/pcurves.h"

#include <gtest/gtest.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_Circle.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>
#include <gp_Pln.hxx>
#include <gp_Trsf.hxx>
#include <gp_Vec2d.hxx>
#include <map>
#include <set>
#include <vector>

#include "domain_fixture.h"
#include "model/model.h"
#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

// A cylinder (a seam: one edge, two pcurves on its side) beside a plane with a round hole made
// from its wires alone, so that the shape stores no pcurve for the plane's edges (OCCT would
// project them at every lookup; a loaded model stores the projections: StorePlanePcurves).
TopoDS_Shape CylinderAndHoledPlane() {
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  builder.Add(compound, BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp::DZ()), 1, 2).Shape());
  BRepBuilderAPI_MakeWire outer;
  const gp_Pnt corners[] = {{3, 0, 0}, {6, 0, 0}, {6, 3, 0}, {3, 3, 0}};
  for (int i = 0; i < 4; ++i) outer.Add(BRepBuilderAPI_MakeEdge(corners[i], corners[(i + 1) % 4]));
  TopoDS_Wire hole = BRepBuilderAPI_MakeWire(
      BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp_Pnt(4.5, 1.5, 0), gp::DZ()), 0.5)));
  hole.Reverse();
  BRepBuilderAPI_MakeFace face(gp_Pln(gp::Origin(), gp::DZ()), outer.Wire());
  face.Add(hole);
  builder.Add(compound, face.Face());
  return compound;
}

// Every face in both orientations, every edge occurrence in both: the table's pcurve has OCCT's
// range and OCCT's points, bit for bit. Returns how many lookups OCCT answered by projection.
// (None, on a loaded model: it stores every plane edge's pcurve.)
int ExpectSameAsOcct(const Model& model, const FacePcurves& table) {
  int projected = 0;
  for (int f = 1; f <= model.face_count(); ++f) {
    for (TopAbs_Orientation o : {TopAbs_FORWARD, TopAbs_REVERSED}) {
      const TopoDS_Face face = TopoDS::Face(model.face(f).Oriented(o));
      for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
        for (bool reverse : {false, true}) {
          TopoDS_Edge edge = TopoDS::Edge(ex.Current());
          if (reverse) edge.Reverse();
          double first, last;
          Standard_Boolean stored = Standard_True;
          Handle(Geom2d_Curve) occt = BRep_Tool::CurveOnSurface(edge, face, first, last, &stored);
          projected += !stored;
          const Pcurve ours = table.Find(f, face, model.edges.FindIndex(edge), edge);
          if (occt.IsNull() || ours.curve.IsNull()) {
            ADD_FAILURE() << "face " << f << ": a null pcurve";
            continue;
          }
          EXPECT_EQ(ours.first, first);
          EXPECT_EQ(ours.last, last);
          for (double t : {first, 0.3 * first + 0.7 * last, last}) {
            const gp_Pnt2d a = occt->Value(t), b = ours.curve->Value(t);
            EXPECT_EQ(a.X(), b.X()) << "face " << f << " at " << t;
            EXPECT_EQ(a.Y(), b.Y()) << "face " << f << " at " << t;
          }
        }
      }
    }
  }
  return projected;
}

// Every wire of every face as BRepTools_WireExplorer walks it: (edge id, reversed) in order.
void ExpectLoopsAsTheExplorerWalks(const Model& model, const FacePcurves& table) {
  for (int f = 1; f <= model.face_count(); ++f) {
    const TopoDS_Face face = TopoDS::Face(model.face(f).Oriented(TopAbs_FORWARD));
    FaceLoops scratch;
    const FaceLoops& loops = table.Loops(model, f, &scratch);
    size_t w = 0;
    for (TopExp_Explorer wexp(face, TopAbs_WIRE); wexp.More(); wexp.Next(), ++w) {
      ASSERT_LT(w, loops.wires.size()) << "face " << f;
      const FaceWire& wire = loops.wires[w];
      EXPECT_TRUE(wire.reached.ok()) << wire.reached.message();
      size_t k = 0;
      for (BRepTools_WireExplorer ex(TopoDS::Wire(wexp.Current()), face); ex.More();
           ex.Next(), ++k) {
        ASSERT_LT(k, wire.edges.size()) << "face " << f << " wire " << w;
        EXPECT_EQ(wire.edges[k].eid, model.edges.FindIndex(ex.Current()))
            << "face " << f << " wire " << w << " edge " << k;
        EXPECT_EQ(wire.edges[k].reversed, ex.Current().Orientation() == TopAbs_REVERSED);
        double first, last;
        Handle(Geom2d_Curve) occt = BRep_Tool::CurveOnSurface(ex.Current(), face, first, last);
        EXPECT_EQ(wire.edges[k].pcurve->Value(first).X(), occt->Value(first).X());
        EXPECT_EQ(wire.edges[k].pcurve->Value(last).Y(), occt->Value(last).Y());
      }
      EXPECT_EQ(k, wire.edges.size()) << "face " << f << " wire " << w;
    }
    EXPECT_EQ(w, loops.wires.size()) << "face " << f;
  }
}

// How many edge occurrences of the shape's faces have no stored pcurve.
int Unstored(const TopoDS_Shape& shape) {
  int unstored = 0;
  for (TopExp_Explorer fx(shape, TopAbs_FACE); fx.More(); fx.Next()) {
    const TopoDS_Face& face = TopoDS::Face(fx.Current());
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
      double first, last;
      Standard_Boolean stored = Standard_True;
      BRep_Tool::CurveOnSurface(TopoDS::Edge(ex.Current()), face, first, last, &stored);
      unstored += !stored;
    }
  }
  return unstored;
}

TEST(FacePcurvesTest, AnswersAsOcctOnSeamsAndOnPlanesWithoutStoredPcurves) {
  const TopoDS_Shape shape = CylinderAndHoledPlane();
  EXPECT_EQ(Unstored(shape), 5) << "the plane's four sides and its hole";
  auto model = LoadShape(shape, "pcurves");
  ASSERT_TRUE(model);
  const FacePcurves table = testing::Pcurves(*model);
  EXPECT_EQ(ExpectSameAsOcct(*model, table), 0) << "the loaded model stores them";
  // The cylinder's side: the seam's two pcurves lie a period apart in u.
  bool seam_seen = false;
  for (int f = 1; f <= model->face_count(); ++f) {
    const TopoDS_Face& face = model->face(f);
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
      if (!BRep_Tool::IsClosed(edge, face)) continue;
      const int e = model->edges.FindIndex(edge);
      const Pcurve a = table.Find(f, face, e, edge);
      const Pcurve b = table.Find(f, face, e, TopoDS::Edge(edge.Reversed()));
      EXPECT_NEAR(std::fabs(a.curve->Value(a.first).X() - b.curve->Value(b.first).X()), 2 * M_PI,
                  1e-12);
      seam_seen = true;
    }
  }
  EXPECT_TRUE(seam_seen);
}

// The shape and a placed copy of it (an instance: its faces share their TShapes and carry a
// location, which the table looks through).
TEST(FacePcurvesTest, APlacedCopyAnswersAsOcct) {
  gp_Trsf trsf;
  trsf.SetRotation(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(1, 1, 0)), 0.7);
  trsf.SetTranslationPart(gp_Vec(10, -4, 2));
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  const TopoDS_Shape shape = CylinderAndHoledPlane();
  builder.Add(compound, shape);
  builder.Add(compound, shape.Moved(TopLoc_Location(trsf)));
  auto model = LoadShape(compound, "pcurves_placed");
  ASSERT_TRUE(model);
  int located = 0;
  for (int f = 1; f <= model->face_count(); ++f) located += !model->face(f).Location().IsIdentity();
  EXPECT_GE(located, model->face_count() / 2);
  const FacePcurves table = testing::Pcurves(*model);
  EXPECT_EQ(ExpectSameAsOcct(*model, table), 0);
  ExpectLoopsAsTheExplorerWalks(*model, table);
  for (int f = 1; f <= model->face_count(); ++f) {
    double u0, u1, v0, v1;
    BRepTools::UVBounds(model->face(f), u0, u1, v0, v1);
    EXPECT_EQ(table.Bounds(*model, f).umin, u0);
    EXPECT_EQ(table.Bounds(*model, f).vmax, v1);
  }
}

TEST(FacePcurvesTest, BoundsAreOccts) {
  auto model = LoadShape(CylinderAndHoledPlane(), "pcurves_bounds");
  ASSERT_TRUE(model);
  const FacePcurves table = testing::Pcurves(*model);
  for (int f = 1; f <= model->face_count(); ++f) {
    double u0, u1, v0, v1;
    BRepTools::UVBounds(model->face(f), u0, u1, v0, v1);
    const UvBounds b = table.Bounds(*model, f);
    EXPECT_EQ(b.umin, u0);
    EXPECT_EQ(b.umax, u1);
    EXPECT_EQ(b.vmin, v0);
    EXPECT_EQ(b.vmax, v1);
  }
}

// A square whose wire lists its edges out of order (the explorer sorts them) beside the
// cylinder (a seam: its vertex begins two edges of the side's wire) and the holed plane (wires in
// order: the table walks them without the explorer).
TEST(FacePcurvesTest, LoopsAreWalkedAsTheWireExplorerWalksThem) {
  BRep_Builder builder;
  TopoDS_Wire shuffled;
  builder.MakeWire(shuffled);
  const gp_Pnt corners[] = {{0, 5, 0}, {1, 5, 0}, {1, 6, 0}, {0, 6, 0}};
  TopoDS_Vertex v[4];
  for (int i = 0; i < 4; ++i) v[i] = BRepBuilderAPI_MakeVertex(corners[i]);
  for (int i : {0, 2, 1, 3}) builder.Add(shuffled, BRepBuilderAPI_MakeEdge(v[i], v[(i + 1) % 4]));
  shuffled.Closed(Standard_True);
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  builder.Add(compound, CylinderAndHoledPlane());
  builder.Add(compound, BRepBuilderAPI_MakeFace(gp_Pln(gp::Origin(), gp::DZ()), shuffled).Face());
  auto model = LoadShape(compound, "pcurves_loops");
  ASSERT_TRUE(model);
  ASSERT_EQ(model->face_count(), 5);
  // The square's wire still lists its edges out of walking order (and the explorer walks the
  // cylinder's side from another edge than the first listed).
  int out_of_order = 0;
  for (int f = 1; f <= model->face_count(); ++f) {
    const TopoDS_Face face = TopoDS::Face(model->face(f).Oriented(TopAbs_FORWARD));
    for (TopExp_Explorer wexp(face, TopAbs_WIRE); wexp.More(); wexp.Next()) {
      TopoDS_Iterator listed(wexp.Current());
      for (BRepTools_WireExplorer ex(TopoDS::Wire(wexp.Current()), face);
           ex.More() && listed.More(); ex.Next(), listed.Next())
        if (!ex.Current().IsEqual(listed.Value())) {
          ++out_of_order;
          break;
        }
    }
  }
  EXPECT_EQ(out_of_order, 2);
  ExpectLoopsAsTheExplorerWalks(*model, testing::Pcurves(*model));
  ExpectLoopsAsTheExplorerWalks(*model, FacePcurves());
}

// Moves the pcurves of `edge` on `face` (FORWARD) by `forward` and, for a seam, its REVERSED side
// by `reversed`, and sets the edge's tolerance.
void MovePcurves(const TopoDS_Face& face, const TopoDS_Edge& edge, gp_Vec2d forward,
                 gp_Vec2d reversed, double tolerance) {
  const TopoDS_Face f = TopoDS::Face(face.Oriented(TopAbs_FORWARD));
  double first, last;
  Handle(Geom2d_Curve) a =
      BRep_Tool::CurveOnSurface(TopoDS::Edge(edge.Oriented(TopAbs_FORWARD)), f, first, last);
  Handle(Geom2d_Curve) b =
      BRep_Tool::CurveOnSurface(TopoDS::Edge(edge.Oriented(TopAbs_REVERSED)), f, first, last);
  a = Handle(Geom2d_Curve)::DownCast(a->Translated(forward));
  BRep_Builder builder;
  if (BRep_Tool::IsClosed(edge, f))
    builder.UpdateEdge(edge, a, Handle(Geom2d_Curve)::DownCast(b->Translated(reversed)), f,
                       tolerance);
  else
    builder.UpdateEdge(edge, a, f, tolerance);
}

// The curved face of `shape` of surface type `type`, FORWARD.
TopoDS_Face CurvedFace(const TopoDS_Shape& shape, GeomAbs_SurfaceType type) {
  for (TopExp_Explorer fx(shape, TopAbs_FACE); fx.More(); fx.Next())
    if (BRepAdaptor_Surface(TopoDS::Face(fx.Current())).GetType() == type)
      return TopoDS::Face(fx.Current().Oriented(TopAbs_FORWARD));
  return TopoDS_Face();
}

// Two closed solids with the wires of KiCad's bent leads and fillet rings (issue 35), which
// BRepTools_WireExplorer cannot walk:
// - a quarter of a torus tube, its seam on the inner equator. The seam's pcurves sit 1e-5 off
//   the circles in u: 5e-6 in 3D at the inner radius 0.5, within the 6e-6 tolerance of the
//   seam and its vertex. The explorer allows twice the vertex tolerance's u resolution, which is
//   taken at the outer radius 1.5: 8e-6 in u.
// - a fillet ring, a surface of revolution (of a B-spline arc) whose top circle and the seam's
//   side beside it run a period lower in u than the bottom circle and the other side: they meet
//   only a period apart.
TopoDS_Shape BentLeadAndFilletRing() {
  TopoDS_Shape tube = BRepPrimAPI_MakeTorus(gp_Ax2(), 1.0, 0.5, -M_PI, M_PI, M_PI / 2).Shape();
  const TopoDS_Face torus = CurvedFace(tube, GeomAbs_Torus);
  BRep_Builder builder;
  for (TopExp_Explorer ex(torus, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
    if (!BRep_Tool::IsClosed(edge, torus)) continue;
    MovePcurves(torus, edge, gp_Vec2d(1e-5, 0), gp_Vec2d(1e-5, 0), 6e-6);
    TopoDS_Vertex v0, v1;
    TopExp::Vertices(edge, v0, v1);
    builder.UpdateVertex(v0, 6e-6);
    builder.UpdateVertex(v1, 6e-6);
  }
  const gp_Pnt centre(2, 0, 0);
  Handle(Geom_BSplineCurve) arc = GeomConvert::CurveToBSplineCurve(
      new Geom_TrimmedCurve(new Geom_Circle(gp_Ax2(centre, gp::DY()), 0.5), 0, M_PI / 2));
  const TopoDS_Wire profile = BRepBuilderAPI_MakeWire(
      BRepBuilderAPI_MakeEdge(arc), BRepBuilderAPI_MakeEdge(arc->EndPoint(), centre),
      BRepBuilderAPI_MakeEdge(centre, arc->StartPoint()));
  TopoDS_Shape ring =
      BRepPrimAPI_MakeRevol(BRepBuilderAPI_MakeFace(profile).Face(), gp_Ax1(gp::Origin(), gp::DZ()))
          .Shape();
  const TopoDS_Face revolution = CurvedFace(ring, GeomAbs_SurfaceOfRevolution);
  for (TopExp_Explorer ex(revolution, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
    double first, last;
    Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, revolution, first, last);
    if (BRep_Tool::IsClosed(edge, revolution)) {
      if (edge.Orientation() == TopAbs_FORWARD)
        MovePcurves(revolution, edge, gp_Vec2d(0, 0), gp_Vec2d(-2 * M_PI, 0), 1e-7);
    } else if (pcurve->Value(first).Y() > 1) {  // the top circle
      MovePcurves(revolution, edge, gp_Vec2d(-2 * M_PI, 0), gp_Vec2d(), 1e-7);
    }
  }
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  builder.Add(compound, tube);
  builder.Add(compound, ring);
  return compound;
}

// Edges of the mesh used by one triangle (free) and by more than two (non-manifold).
std::pair<int, int> FreeAndNonManifoldEdges(const Mesh& mesh) {
  std::map<std::pair<int, int>, int> uses;
  for (size_t k = 0; k < mesh.triangles.size(); k += 3)
    for (int i = 0; i < 3; ++i) {
      const int a = mesh.triangles[k + i], b = mesh.triangles[k + (i + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  int free = 0, nonmanifold = 0;
  for (const auto& [edge, n] : uses) free += n == 1, nonmanifold += n > 2;
  return {free, nonmanifold};
}

TEST(FacePcurvesTest, WiresTheExplorerCannotWalkAreChainedByTheirEnds) {
  auto model = LoadShape(BentLeadAndFilletRing(), "pcurves_chained");
  ASSERT_TRUE(model);
  const FacePcurves table = testing::Pcurves(*model);
  int curved = 0;
  for (int f = 1; f <= model->face_count(); ++f) {
    const TopoDS_Face face = TopoDS::Face(model->face(f).Oriented(TopAbs_FORWARD));
    if (BRepAdaptor_Surface(face).GetType() == GeomAbs_Plane ||
        BRepAdaptor_Surface(face).GetType() == GeomAbs_Cylinder)
      continue;
    ++curved;
    // The explorer stops early (after one edge on the torus, two on the ring).
    const TopoDS_Wire wire = TopoDS::Wire(TopoDS_Iterator(face).Value());
    int explored = 0;
    for (BRepTools_WireExplorer ex(wire, face); ex.More(); ex.Next()) ++explored;
    EXPECT_LT(explored, 4) << "face " << f;
    // The table's loop holds every edge of the wire, as the wire uses it.
    FaceLoops scratch;
    const FaceLoops& loops = table.Loops(*model, f, &scratch);
    ASSERT_EQ(loops.wires.size(), 1u) << "face " << f;
    EXPECT_TRUE(loops.wires[0].reached.ok()) << loops.wires[0].reached.message();
    std::multiset<std::pair<int, bool>> walked, listed;
    for (const WireEdge& e : loops.wires[0].edges) walked.insert({e.eid, e.reversed});
    for (TopoDS_Iterator it(wire); it.More(); it.Next())
      listed.insert(
          {model->edges.FindIndex(it.Value()), it.Value().Orientation() == TopAbs_REVERSED});
    EXPECT_EQ(walked, listed) << "face " << f;
    // Each edge begins where the one before ends, up to whole periods.
    FaceDomain domain;
    const std::vector<EdgeGrid> grids = testing::Grids(*model, 1e-3);
    EXPECT_TRUE(testing::Domain(*model, f, grids, &domain).ok()) << "face " << f;
    EXPECT_TRUE(FindConflicts(domain).empty()) << "face " << f;
  }
  EXPECT_EQ(curved, 2);
  // Both solids mesh whole and watertight.
  auto result = MeshModel(*model, MeshOptions());
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  for (const FaceMesh& f : result->faces)
    EXPECT_EQ(f.status, FaceStatus::kOk) << "face " << f.face_id << ": " << f.reason;
  EXPECT_EQ(FreeAndNonManifoldEdges(result->mesh), std::make_pair(0, 0));
}

TEST(FacePcurvesTest, AFaceLeftOutIsLookedUpFromOcct) {
  auto model = LoadData("nist_mbe_pmi_11.stp");
  ASSERT_TRUE(model);
  // Built for the odd faces only: the even ones go to OCCT, and all answer the same.
  std::vector<int> odd;
  for (int f = 1; f <= model->face_count(); f += 2) odd.push_back(f);
  const FacePcurves partial = FacePcurves::Build(*model, odd, 2, nullptr);
  ExpectSameAsOcct(*model, partial);
  ExpectSameAsOcct(*model, FacePcurves());
  for (int f = 1; f <= model->face_count(); ++f) {
    double u0, u1, v0, v1;
    BRepTools::UVBounds(model->face(f), u0, u1, v0, v1);
    EXPECT_EQ(partial.Bounds(*model, f).umax, u1);
    EXPECT_EQ(partial.Bounds(*model, f).vmin, v0);
  }
}

}  // namespace
}  // namespace rdmesh
