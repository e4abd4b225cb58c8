// The shortcut past ShapeFix_Shape's shell and solid stages (model/step/finish.h): where it
// answers true, OCCT's stages return the shape as it was; where they would change it, false.
#include <gtest/gtest.h>

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRep_Builder.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Shape.hxx>
#include <ShapeFix_Shell.hxx>
#include <ShapeFix_Solid.hxx>
#include <ShapeFix_Wire.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pnt.hxx>
#include <vector>

#include "core/parallel.h"
#include "model/step/finish.h"

namespace rdmesh::step {
namespace {

// ShapeFix_Shape as the reader's FinishItem sets it up for items whose faces are fixed.
TopoDS_Shape OcctStages(const TopoDS_Shape& shape) {
  Handle(ShapeFix_Shape) fix = new ShapeFix_Shape;
  fix->Init(shape);
  fix->SetPrecision(1e-7);
  fix->SetMaxTolerance(1.);
  fix->FixFaceTool()->FixWireTool()->FixSameParameterMode() = Standard_False;
  fix->FixSolidTool()->CreateOpenSolidMode() = Standard_False;
  fix->FixShellTool()->FixFaceMode() = 0;
  fix->FixSameParameterMode() = 0;
  fix->FixVertexTolMode() = 0;
  fix->Perform();
  return fix->Shape();
}

// A new shell of `faces`, in order.
TopoDS_Shell ShellOf(const std::vector<TopoDS_Shape>& faces) {
  BRep_Builder builder;
  TopoDS_Shell shell;
  builder.MakeShell(shell);
  for (const TopoDS_Shape& face : faces) builder.Add(shell, face);
  return shell;
}

TopoDS_Solid SolidOf(const TopoDS_Shape& shell) {
  BRep_Builder builder;
  TopoDS_Solid solid;
  builder.MakeSolid(solid);
  builder.Add(solid, shell);
  return solid;
}

std::vector<TopoDS_Shape> FacesOf(const TopoDS_Shape& shape) {
  std::vector<TopoDS_Shape> faces;
  for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) faces.push_back(ex.Current());
  return faces;
}

TopoDS_Shape Box(double x = 0.) {
  return BRepPrimAPI_MakeBox(gp_Pnt(x, 0., 0.), 1., 2., 3.).Solid();
}

class StepFinishTest : public ::testing::Test {
 protected:
  ParallelRunner runner_{2};
};

TEST_F(StepFinishTest, ClosedSolidsAreLeftAsOcctLeavesThem) {
  const TopoDS_Shape box = Box();
  const TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(gp_Ax2(), 1., 2.).Solid();
  for (const TopoDS_Shape& shape : {box, cylinder}) {
    EXPECT_TRUE(OcctStages(shape).IsEqual(shape));
    EXPECT_TRUE(ShellAndSolidStagesWithoutChange(shape, runner_));
    TopoDS_Iterator shell(shape);
    EXPECT_TRUE(shell.Value().Closed());  // ShapeFix_Solid found it closed and said so
  }
}

TEST_F(StepFinishTest, InsideOutSolidIsRefused) {
  // The box's shell reversed: the solid holds the infinite point, and OCCT reverses it back.
  TopoDS_Iterator shell(Box());
  const TopoDS_Shape inside_out = SolidOf(shell.Value().Reversed());
  EXPECT_FALSE(OcctStages(inside_out).IsEqual(inside_out));
  EXPECT_FALSE(ShellAndSolidStagesWithoutChange(inside_out, runner_));
}

TEST_F(StepFinishTest, FaceOrientedAgainstItsNeighboursIsRefused) {
  std::vector<TopoDS_Shape> faces = FacesOf(Box());
  faces[2].Reverse();
  const TopoDS_Shape solid = SolidOf(ShellOf(faces));
  EXPECT_FALSE(OcctStages(solid).IsEqual(solid));
  EXPECT_FALSE(ShellAndSolidStagesWithoutChange(solid, runner_));
}

TEST_F(StepFinishTest, DisconnectedFacesAreRefused) {
  // Two boxes' faces in one shell: OCCT splits it in two.
  std::vector<TopoDS_Shape> faces = FacesOf(Box());
  for (const TopoDS_Shape& face : FacesOf(Box(5.))) faces.push_back(face);
  const TopoDS_Shape shell = ShellOf(faces);
  EXPECT_FALSE(OcctStages(shell).IsEqual(shell));
  EXPECT_FALSE(ShellAndSolidStagesWithoutChange(shell, runner_));
}

TEST_F(StepFinishTest, OpenShellOfASolidIsRefused) {
  // ShapeFix_Solid makes no open solids: it puts the shell in the solid's place.
  std::vector<TopoDS_Shape> faces = FacesOf(Box());
  faces.pop_back();
  const TopoDS_Shape solid = SolidOf(ShellOf(faces));
  EXPECT_FALSE(OcctStages(solid).IsEqual(solid));
  EXPECT_FALSE(ShellAndSolidStagesWithoutChange(solid, runner_));
}

TEST_F(StepFinishTest, OpenShellIsKeptAndMarkedOpen) {
  std::vector<TopoDS_Shape> faces = FacesOf(Box());
  faces.pop_back();
  TopoDS_Shape ours = ShellOf(faces), theirs = ShellOf(faces);
  ours.Closed(true);
  theirs.Closed(true);
  EXPECT_TRUE(OcctStages(theirs).IsEqual(theirs));
  EXPECT_FALSE(theirs.Closed());
  EXPECT_TRUE(ShellAndSolidStagesWithoutChange(ours, runner_));
  EXPECT_FALSE(ours.Closed());
}

TEST_F(StepFinishTest, CompoundOfSolidsIsLeftAsOcctLeavesIt) {
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  builder.Add(compound, Box());
  builder.Add(compound, Box(5.));
  EXPECT_TRUE(OcctStages(compound).IsEqual(compound));
  EXPECT_TRUE(ShellAndSolidStagesWithoutChange(compound, runner_));
  // One inside-out solid in it is enough to refuse the whole.
  TopoDS_Iterator shell(Box(10.));
  builder.Add(compound, SolidOf(shell.Value().Reversed()));
  EXPECT_FALSE(ShellAndSolidStagesWithoutChange(compound, runner_));
}

}  // namespace
}  // namespace rdmesh::step
