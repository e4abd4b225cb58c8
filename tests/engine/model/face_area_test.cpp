// ClosedFormFaceArea against OCCT's Gauss integration (BRepGProp::SurfaceProperties).

#include "model/face_area.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <GProp_GProps.hxx>
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

}  // namespace
}  // namespace rdmesh
