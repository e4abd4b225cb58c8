// ClosedFormFaceArea and NaturalPatchArea against OCCT's Gauss integration
// (BRepGProp::SurfaceProperties).

#include "model/face_area.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <GProp_GProps.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <gp_Trsf.hxx>

namespace rdmesh {
namespace {

double GaussArea(const TopoDS_Face& face) {
  GProp_GProps props;
  BRepGProp::SurfaceProperties(face, props);
  return std::abs(props.Mass());
}

// Every face of `shape` has a closed-form area, equal to OCCT's within 1e-12; returns the count.
int CheckFaces(const TopoDS_Shape& shape) {
  int faces = 0;
  for (TopExp_Explorer it(shape, TopAbs_FACE); it.More(); it.Next(), ++faces) {
    const TopoDS_Face& face = TopoDS::Face(it.Current());
    const std::optional<double> area = ClosedFormFaceArea(face);
    EXPECT_TRUE(area.has_value()) << "face " << faces;
    if (area) EXPECT_NEAR(*area, GaussArea(face), 1e-12 * GaussArea(face)) << "face " << faces;
  }
  return faces;
}

TEST(ClosedFormFaceArea, BoxWithRoundHoleFarFromTheOrigin) {
  // Planar faces with a circle in them (a hole: the other way round), the hole's cylinder
  // between its seam's two pcurves, all placed far from the origin (the sum is taken about a
  // point of the face).
  gp_Trsf far;
  far.SetTranslation(gp_Vec(5000, -3000, 1200));
  TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 10, 8, 6).Shape();
  TopoDS_Shape pin = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(4, 3, -1), gp::DZ()), 1.3, 9).Shape();
  TopoDS_Shape holed = BRepAlgoAPI_Cut(box, pin).Shape().Moved(TopLoc_Location(far));
  EXPECT_EQ(CheckFaces(holed), 7);
}

TEST(ClosedFormFaceArea, PartialCylinderTurned) {
  gp_Trsf turn;
  turn.SetRotation(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(1, 2, 0.5)), 0.7);
  TopoDS_Shape part =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(2, -1, 0), gp_Dir(0.3, 0, 1)), 2.5, 4, 2.2).Shape();
  EXPECT_EQ(CheckFaces(part.Moved(TopLoc_Location(turn))), 5);
}

TEST(ClosedFormFaceArea, OtherSurfacesGiveNothing) {
  TopoDS_Shape sphere = BRepPrimAPI_MakeSphere(3).Shape();
  for (TopExp_Explorer it(sphere, TopAbs_FACE); it.More(); it.Next())
    EXPECT_FALSE(ClosedFormFaceArea(TopoDS::Face(it.Current())).has_value());
}

// A bicubic patch of 3 x 2 spans, uneven knots, its poles on a wavy sheet.
Handle(Geom_BSplineSurface) WavyPatch() {
  TColgp_Array2OfPnt poles(1, 6, 1, 5);
  for (int i = 1; i <= 6; ++i)
    for (int j = 1; j <= 5; ++j)
      poles(i, j) = gp_Pnt(i * 1.7, j * 1.3 + 0.2 * i, std::sin(0.9 * i) * std::cos(1.3 * j) * 2);
  TColStd_Array1OfReal uknots(1, 4), vknots(1, 3);
  TColStd_Array1OfInteger umults(1, 4), vmults(1, 3);
  const double us[] = {0, 0.3, 1.1, 2}, vs[] = {-1, 0.4, 3};
  for (int i = 1; i <= 4; ++i) uknots(i) = us[i - 1], umults(i) = i == 1 || i == 4 ? 4 : 1;
  for (int j = 1; j <= 3; ++j) vknots(j) = vs[j - 1], vmults(j) = j == 1 || j == 3 ? 4 : 1;
  return new Geom_BSplineSurface(poles, uknots, vknots, umults, vmults, 3, 3);
}

// OCCT's adaptive integration to a relative error of 1e-12 (its default rule reads the torus
// below 0.5% short of 4 pi^2 R r, the adaptive one 1e-9 short).
double AdaptiveArea(const TopoDS_Face& face) {
  GProp_GProps props;
  BRepGProp::SurfaceProperties(face, props, 1e-12);
  return std::abs(props.Mass());
}

TEST(NaturalPatchArea, WholePatchesMatchOcct) {
  // The wavy patch, and a torus as a periodic B-spline (its faces' wire has a seam each way).
  const Handle(Geom_Surface) torus = GeomConvert::SurfaceToBSplineSurface(
      new Geom_ToroidalSurface(gp_Ax3(gp_Pnt(1, 2, 3), gp_Dir(0.2, 0.1, 1)), 5, 1.5));
  for (const Handle(Geom_Surface) & surface : {Handle(Geom_Surface)(WavyPatch()), torus}) {
    const TopoDS_Face face = BRepBuilderAPI_MakeFace(surface, 1e-7).Face();
    const std::optional<double> area = NaturalPatchArea(face);
    ASSERT_TRUE(area.has_value());
    EXPECT_NEAR(*area, AdaptiveArea(face), 1e-8 * AdaptiveArea(face));
  }
  const TopoDS_Face face = BRepBuilderAPI_MakeFace(torus, 1e-7).Face();
  EXPECT_NEAR(*NaturalPatchArea(face), 4 * M_PI * M_PI * 5 * 1.5, 1e-13 * 296);
}

TEST(NaturalPatchArea, PartsOfAPatchGiveNothing) {
  // A sub-rectangle (its iso-lines inside the bounds), and the patch with a hole cut through it:
  // both left to OCCT.
  const Handle(Geom_BSplineSurface) patch = WavyPatch();
  EXPECT_FALSE(
      NaturalPatchArea(BRepBuilderAPI_MakeFace(patch, 0.2, 1.5, -0.5, 2, 1e-7).Face()).has_value());
  const TopoDS_Face whole = BRepBuilderAPI_MakeFace(patch, 1e-7).Face();
  const TopoDS_Shape pin =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(5, 4, -10), gp::DZ()), 0.8, 20).Shape();
  int faces = 0;
  for (TopExp_Explorer it(BRepAlgoAPI_Cut(whole, pin).Shape(), TopAbs_FACE); it.More();
       it.Next(), ++faces)
    EXPECT_FALSE(NaturalPatchArea(TopoDS::Face(it.Current())).has_value());
  EXPECT_EQ(faces, 1);
  EXPECT_FALSE(ClosedFormFaceArea(whole).has_value());
}

}  // namespace
}  // namespace rdmesh
