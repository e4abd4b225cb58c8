// ClosedFormFaceBox and SampledFaceBox against dense sampling of the face and against OCCT's
// BRepBndLib::AddOptimal.

#include "model/face_boxes.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRepTools.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_PointsToBSpline.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom_Surface.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <gp_Trsf.hxx>
#include <vector>

namespace rdmesh {
namespace {

bool Round(const TopoDS_Face& face) {
  TopLoc_Location location;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
  return !Handle(Geom_ToroidalSurface)::DownCast(surface).IsNull() ||
         !Handle(Geom_SphericalSurface)::DownCast(surface).IsNull();
}

// The faces on tori and spheres.
std::vector<TopoDS_Face> RoundFaces(const TopoDS_Shape& shape) {
  std::vector<TopoDS_Face> faces;
  for (TopExp_Explorer it(shape, TopAbs_FACE); it.More(); it.Next()) {
    const TopoDS_Face& face = TopoDS::Face(it.Current());
    if (Round(face)) faces.push_back(face);
  }
  return faces;
}

// The box of a 400 x 400 grid of the face's points inside its domain.
Bnd_Box SampledBox(const TopoDS_Face& face) {
  const TopoDS_Face forward = TopoDS::Face(face.Oriented(TopAbs_FORWARD));
  double u0, u1, v0, v1;
  BRepTools::UVBounds(forward, u0, u1, v0, v1);
  BRepTopAdaptor_FClass2d classifier(forward, 1e-9);
  TopLoc_Location location;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(forward, location);
  Bnd_Box box;
  const int n = 400;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double u = u0 + (u1 - u0) * i / n, v = v0 + (v1 - v0) * j / n;
      if (classifier.Perform(gp_Pnt2d(u, v)) == TopAbs_OUT) continue;
      box.Add(surface->Value(u, v).Transformed(location.Transformation()));
    }
  }
  return box;
}

// `box` holds `inner` within `slack` and reaches each of its sides within `reach`.
void ExpectTight(const Bnd_Box& box, const Bnd_Box& inner, double slack, double reach) {
  double a[6], b[6];
  box.Get(a[0], a[1], a[2], a[3], a[4], a[5]);
  inner.Get(b[0], b[1], b[2], b[3], b[4], b[5]);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(a[k], b[k] + slack) << "axis " << k;
    EXPECT_GE(a[k + 3], b[k + 3] - slack) << "axis " << k;
    EXPECT_GE(a[k], b[k] - reach) << "axis " << k;
    EXPECT_LE(a[k + 3], b[k + 3] + reach) << "axis " << k;
  }
}

// `box` of `face` against sampling (holding it within `slack` of the box's size) and, with
// `against_optimal`, within 1e-6 of OCCT's AddOptimal box.
void CheckBox(const TopoDS_Face& face, const Bnd_Box& box, double slack, bool against_optimal) {
  ASSERT_FALSE(box.IsVoid());
  const double size = std::sqrt(box.SquareExtent());
  // Sampling reaches within (grid step)^2 of an interior extreme: 1e-4 of the size here.
  {
    SCOPED_TRACE("against sampling");
    ExpectTight(box, SampledBox(face), slack * size, 1e-4 * size);
  }
  if (!against_optimal) return;
  Bnd_Box optimal;
  BRepBndLib::AddOptimal(face, optimal, /*useTriangulation=*/false, /*useShapeTolerance=*/false);
  SCOPED_TRACE("against AddOptimal");
  ExpectTight(box, optimal, 1e-6 * size, 1e-6 * size);
}

void CheckFaces(const TopoDS_Shape& shape, size_t expected_faces, bool against_optimal = true) {
  const std::vector<TopoDS_Face> faces = RoundFaces(shape);
  ASSERT_EQ(faces.size(), expected_faces);
  for (const TopoDS_Face& face : faces)
    CheckBox(face, ClosedFormFaceBox(face), /*slack=*/1e-9, against_optimal);
}

TEST(ClosedFormFaceBox, FilletedCylinderRimTiltedAndMoved) {
  // A fillet along a cylinder's top rim is a quarter of a torus's tube around the full circle.
  TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(gp_Ax2(gp::Origin(), gp::DZ()), 10, 20).Shape();
  BRepFilletAPI_MakeFillet fillet(cylinder);
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(cylinder, TopAbs_EDGE, edges);
  for (int i = 1; i <= edges.Extent(); ++i) {
    gp_Pnt p = BRep_Tool::Pnt(TopExp::FirstVertex(TopoDS::Edge(edges(i))));
    if (p.Z() > 19 && !BRep_Tool::Degenerated(TopoDS::Edge(edges(i))))
      fillet.Add(3, TopoDS::Edge(edges(i)));
  }
  TopoDS_Shape rounded = fillet.Shape();
  CheckFaces(rounded, 1);
  // The same, turned off every axis and moved (a located face).
  gp_Trsf turn;
  turn.SetRotation(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(1, 2, 0.5)), 0.7);
  CheckFaces(rounded.Moved(TopLoc_Location(turn)), 1);
}

TEST(ClosedFormFaceBox, PartialTorusPatches) {
  // A torus patch of 100 degrees around and 250 of its tube: interior extremes and boundary ones.
  gp_Ax2 axis(gp_Pnt(5, -3, 2), gp_Dir(0.3, -0.2, 1), gp_Dir(1, 0, -0.3));
  TopoDS_Shape patch = BRepPrimAPI_MakeTorus(axis, 12, 4, -1.2, 3.1, 100 * M_PI / 180).Shape();
  CheckFaces(patch, 1);
  // An axis along z: the extremes in z are circles of critical points.
  TopoDS_Shape upright =
      BRepPrimAPI_MakeTorus(gp_Ax2(gp::Origin(), gp::DZ()), 12, 4, 0.5, 2.5, 1.0).Shape();
  CheckFaces(upright, 1);
  // A hole cut into a full torus: the domain is not a rectangle, and an extreme is cut away.
  TopoDS_Shape full = BRepPrimAPI_MakeTorus(gp_Ax2(gp::Origin(), gp::DZ()), 12, 4).Shape();
  TopoDS_Shape cutter = BRepPrimAPI_MakeBox(gp_Pnt(10, -3, 0), 10, 6, 10).Shape();
  CheckFaces(BRepAlgoAPI_Cut(full, cutter).Shape(), 1);
}

TEST(ClosedFormFaceBox, TubesThatCrossTheAxis) {
  // Horn (R = r) and spindle (R < r) tori, common in generated pin models: the points on the
  // axis are extremes where the tube meets it. AddOptimal's optimiser misses the one of the
  // spindle here by 0.3 (sampling finds it), so only sampling is the reference.
  const gp_Ax3 frame(gp_Pnt(1, 1, 1), gp_Dir(0.2, 0.1, 1), gp_Dir(1, 0, -0.2));
  for (double major : {2.0, 1.2}) {
    Handle(Geom_ToroidalSurface) surface = new Geom_ToroidalSurface(frame, major, 2.0);
    CheckFaces(BRepBuilderAPI_MakeFace(surface, 0.3, 2.5, 1.5, 4.5, 1e-7).Face(), 1,
               /*against_optimal=*/major >= 2.0);
  }
}

TEST(ClosedFormFaceBox, SpherePatchesAndCorners) {
  // A patch of a sphere turned off the axes: extremes inside the face and on its edges.
  gp_Ax2 axis(gp_Pnt(2, -1, 4), gp_Dir(0.4, 0.3, 1), gp_Dir(1, 0, -0.4));
  CheckFaces(BRepPrimAPI_MakeSphere(axis, 5, -0.4, 1.1, 2.0).Shape(), 1);
  // With its pole: upright, then turned.
  CheckFaces(BRepPrimAPI_MakeSphere(gp_Ax2(gp::Origin(), gp::DZ()), 3, 0.2, M_PI / 2, 1.5).Shape(),
             1);
  CheckFaces(BRepPrimAPI_MakeSphere(axis, 3, 0.2, M_PI / 2, 1.5).Shape(), 1);
  // The corners of a box whose edges are all rounded: eight sphere octants.
  TopoDS_Shape box = BRepPrimAPI_MakeBox(10, 8, 6).Shape();
  BRepFilletAPI_MakeFillet fillet(box);
  for (TopExp_Explorer it(box, TopAbs_EDGE); it.More(); it.Next())
    fillet.Add(1.5, TopoDS::Edge(it.Current()));
  CheckFaces(fillet.Shape(), 8);
}

TEST(ClosedFormFaceBox, OtherSurfacesGiveAVoidBox) {
  TopoDS_Shape box = BRepPrimAPI_MakeBox(1, 2, 3).Shape();
  for (TopExp_Explorer it(box, TopAbs_FACE); it.More(); it.Next())
    EXPECT_TRUE(ClosedFormFaceBox(TopoDS::Face(it.Current())).IsVoid());
}

// A bicubic B-spline patch over [0, 10] x [0, 8] whose middle poles rise to `height`, turned
// a little off the axes: a dome whose highest (or lowest) point is inside the face.
Handle(Geom_BSplineSurface) Dome(double height) {
  TColgp_Array2OfPnt poles(1, 5, 1, 5);
  for (int i = 1; i <= 5; ++i)
    for (int j = 1; j <= 5; ++j) {
      const double lift =
          (i > 1 && i < 5 && j > 1 && j < 5) ? height * (i == 3 && j == 3 ? 1.5 : 1) : 0;
      poles(i, j) = gp_Pnt(2.5 * (i - 1), 2.0 * (j - 1), lift + 0.3 * i * j / 5);
    }
  TColStd_Array1OfReal knots(1, 2);
  knots(1) = 0, knots(2) = 1;
  TColStd_Array1OfInteger mults(1, 2);
  mults(1) = mults(2) = 5;
  Handle(Geom_BSplineSurface) dome =
      new Geom_BSplineSurface(poles, knots, knots, mults, mults, 4, 4);
  gp_Trsf turn;
  turn.SetRotation(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(1, 2, 0.5)), 0.2);
  dome->Transform(turn);
  return dome;
}

// SampledFaceBox enlarges interior extremes by Precision::Confusion(), as AddOptimal does.
void CheckSampled(const TopoDS_Face& face, bool against_optimal) {
  CheckBox(face, SampledFaceBox(face), /*slack=*/1e-6, against_optimal);
}

TEST(SampledFaceBox, BSplineDomeWithInteriorExtremes) {
  for (double height : {6.0, -5.0, 0.5}) {
    SCOPED_TRACE(height);
    CheckSampled(BRepBuilderAPI_MakeFace(Dome(height), 0, 1, 0, 1, 1e-7).Face(),
                 /*against_optimal=*/true);
    // Part of its parameter range: the extremes move to the boundary or stay inside.
    CheckSampled(BRepBuilderAPI_MakeFace(Dome(height), 0.1, 0.45, 0.2, 0.9, 1e-7).Face(),
                 /*against_optimal=*/true);
  }
}

TEST(SampledFaceBox, HoleCutOverTheDomesTop) {
  // The top of the dome cut away by a hole: the face's highest points are on the hole's rim,
  // not at the surface's interior extreme, which the face no longer has.
  TopoDS_Face face = BRepBuilderAPI_MakeFace(Dome(6.0), 0, 1, 0, 1, 1e-7).Face();
  double whole[6];
  SampledFaceBox(face).Get(whole[0], whole[1], whole[2], whole[3], whole[4], whole[5]);
  const gp_Pnt top = Dome(6.0)->Value(0.5, 0.5);
  TopoDS_Shape prism =
      BRepPrimAPI_MakeCylinder(gp_Ax2(top.Translated(gp_Vec(0, 0, -20)), gp::DZ()), 1.5, 40)
          .Shape();
  TopoDS_Shape cut = BRepAlgoAPI_Cut(face, prism).Shape();
  int faces = 0;
  for (TopExp_Explorer it(cut, TopAbs_FACE); it.More(); it.Next(), ++faces) {
    CheckSampled(TopoDS::Face(it.Current()), /*against_optimal=*/false);
    double c[6];
    SampledFaceBox(TopoDS::Face(it.Current())).Get(c[0], c[1], c[2], c[3], c[4], c[5]);
    EXPECT_LT(c[5], whole[5] - 0.1);  // the top went with the hole
  }
  EXPECT_EQ(faces, 1);
}

TEST(SampledFaceBox, RevolvedSplineProfile) {
  // A B-spline profile turned 200 degrees about a tilted axis: extremes inside the face along
  // the turn and along the profile.
  TColgp_Array1OfPnt points(1, 5);
  points(1) = gp_Pnt(2, 0, 0), points(2) = gp_Pnt(4, 0, 1), points(3) = gp_Pnt(5, 0, 3);
  points(4) = gp_Pnt(3.5, 0, 5), points(5) = gp_Pnt(2.5, 0, 6);
  Handle(Geom_BSplineCurve) profile = GeomAPI_PointsToBSpline(points).Curve();
  TopoDS_Edge edge = BRepBuilderAPI_MakeEdge(profile).Edge();
  const gp_Ax1 axis(gp_Pnt(0.5, -0.3, 0), gp_Dir(0.1, 0.2, 1));
  TopoDS_Shape revolved = BRepPrimAPI_MakeRevol(edge, axis, 200 * M_PI / 180).Shape();
  int faces = 0;
  for (TopExp_Explorer it(revolved, TopAbs_FACE); it.More(); it.Next(), ++faces)
    CheckSampled(TopoDS::Face(it.Current()), /*against_optimal=*/true);
  EXPECT_EQ(faces, 1);
}

TEST(SampledFaceBox, RuledAndClosedFormSurfacesGiveAVoidBox) {
  // Planes, cylinders and the like are boxed by their edges (AddOptimal's own way, cheap);
  // spheres and tori by ClosedFormFaceBox.
  TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(2, 5).Shape();
  for (TopExp_Explorer it(cylinder, TopAbs_FACE); it.More(); it.Next())
    EXPECT_TRUE(SampledFaceBox(TopoDS::Face(it.Current())).IsVoid());
  TopoDS_Shape sphere = BRepPrimAPI_MakeSphere(3).Shape();
  for (TopExp_Explorer it(sphere, TopAbs_FACE); it.More(); it.Next())
    EXPECT_TRUE(SampledFaceBox(TopoDS::Face(it.Current())).IsVoid());
}

}  // namespace
}  // namespace rdmesh
