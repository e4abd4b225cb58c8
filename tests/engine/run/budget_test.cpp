// The triangle budget (budget.h): the search over pipeline runs (pipeline.h) returns the mesh of
// one run, within the budget and not far below it, never finer than a max_deviation floor, and
// says so when no mesh fits.
#include "run/budget.h"

#include <gtest/gtest.h>

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <string>

#include "model/model.h"
#include "rdmesh/engine.h"
#include "run/pipeline.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

// The mesh of one pipeline run at `deviation`, which a budget result must equal bit for bit.
Mesh RunAt(const Model& model, const MeshOptions& options, double deviation) {
  Result<MeshResult> run = MeshAtDeviation(model, options, deviation, nullptr);
  EXPECT_TRUE(run.ok()) << run.status().ToString();
  return run.ok() ? run->mesh : Mesh();
}

TEST(BudgetTest, SphereMeshFitsNotFarBelowTheBudgetAndIsOneRunsMesh) {
  auto model = LoadShape(BRepPrimAPI_MakeSphere(1.0).Shape(), "sphere");
  ASSERT_TRUE(model);
  for (int64_t budget : {300, 3000}) {
    MeshOptions options;
    options.max_triangles = budget;
    Result<MeshResult> r = MeshWithinBudget(*model, options, nullptr);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_LE(r->summary.triangles, budget);
    EXPECT_GE(r->summary.triangles, budget / 2) << "the search stopped far below the budget";
    Mesh same = RunAt(*model, options, r->summary.requested_deviation);
    EXPECT_EQ(r->mesh.triangles, same.triangles) << "budget " << budget;
    EXPECT_EQ(r->mesh.xyz, same.xyz) << "budget " << budget;
  }
}

TEST(BudgetTest, MaxDeviationIsAFloor) {
  auto model = LoadShape(BRepPrimAPI_MakeSphere(1.0).Shape(), "sphere");
  ASSERT_TRUE(model);
  MeshOptions options;
  options.max_triangles = 1'000'000;  // far more than the floor needs
  options.max_deviation = 1e-2;
  Result<MeshResult> r = MeshWithinBudget(*model, options, nullptr);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(r->summary.requested_deviation, 1e-2);
  EXPECT_EQ(r->mesh.triangles, RunAt(*model, options, 1e-2).triangles);
}

TEST(BudgetTest, NoMeshFitsIsResourceExhausted) {
  // A box's coarsest mesh has two triangles a face.
  auto model = LoadShape(BRepPrimAPI_MakeBox(2, 1, 1).Shape(), "box");
  ASSERT_TRUE(model);
  MeshOptions options;
  options.max_triangles = 4;
  Result<MeshResult> r = MeshWithinBudget(*model, options, nullptr);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(r.status().message().find("no mesh fits in 4 triangles"), std::string::npos)
      << r.status().message();
  EXPECT_NE(r.status().message().find("has 12"), std::string::npos) << r.status().message();
}

}  // namespace
}  // namespace rdmesh
