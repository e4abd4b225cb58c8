// Levels of detail (engine/src/run/levels.cpp): the levels are sorted coarsest first and checked,
// and each level of MeshModelLevels is the mesh of a single MeshModel run at its deviation.

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

TEST(LevelsTest, ResolveSortsCoarsestFirst) {
  auto levels = ResolveLevels({1e-3, 1e-2, 1e-4}, MeshOptions());
  ASSERT_TRUE(levels.ok()) << levels.status().ToString();
  EXPECT_EQ(*levels, (std::vector<double>{1e-2, 1e-3, 1e-4}));
}

TEST(LevelsTest, ResolveRefusesBadLevels) {
  MeshOptions plain;
  MeshOptions absolute;
  absolute.max_deviation = 0.1;
  MeshOptions budget;
  budget.max_triangles = 1000;
  MeshOptions relative;  // even at the default's value: the levels replace it
  relative.max_deviation_rel = kDefaultMaxDeviationRel;
  const std::vector<std::pair<std::vector<double>, MeshOptions>> bad = {
      {{}, plain},
      {{1e-2, 1e-2}, plain},
      {{1e-2, 0.0}, plain},
      {{1e-2, -1e-3}, plain},
      {{0.6}, plain},
      {{1e-8}, plain},
      {{1e-2, 1e-3, 1e-4, 2e-4, 3e-4, 4e-4, 5e-4, 6e-4, 7e-4}, plain},
      {{1e-2}, absolute},
      {{1e-2}, budget},
      {{1e-2}, relative},
  };
  for (const auto& [levels, options] : bad) {
    auto resolved = ResolveLevels(levels, options);
    EXPECT_FALSE(resolved.ok()) << levels.size() << " levels";
    if (!resolved.ok()) EXPECT_EQ(resolved.status().code(), StatusCode::kInvalidArgument);
  }
}

TEST(LevelsTest, ResolveNamesTheSetRelativeDeviation) {
  MeshOptions relative;
  relative.max_deviation_rel = 1e-3;
  auto resolved = ResolveLevels({1e-2, 1e-3}, relative);
  ASSERT_FALSE(resolved.ok());
  EXPECT_NE(resolved.status().message().find("max_deviation_rel"), std::string::npos)
      << resolved.status().message();
  EXPECT_TRUE(ResolveLevels({1e-2, 1e-3}, MeshOptions()).ok());
}

TEST(LevelsTest, LevelOptionsReplaceOnlyTheDeviation) {
  MeshOptions options;
  options.max_deviation_rel = 5e-3;
  options.max_edge_length = 2.0;
  options.face_ids = {1, 3};
  MeshOptions level = LevelOptions(options, 1e-4);
  EXPECT_EQ(level.max_deviation, 0.0);
  EXPECT_EQ(level.max_deviation_rel, 1e-4);
  EXPECT_EQ(level.max_edge_length, 2.0);
  EXPECT_EQ(level.face_ids, options.face_ids);
}

TEST(LevelsTest, EachLevelIsTheSingleRun) {
  auto model = LoadData("pyocc_eight_cyl.stp");
  ASSERT_TRUE(model);
  MeshOptions options;
  options.threads = 2;
  const std::vector<double> levels = {2e-2, 2e-3, 5e-4};
  std::vector<int> started;
  std::vector<MeshResult> results;
  LevelCallbacks callbacks;
  callbacks.started = [&](int level) { started.push_back(level); };
  callbacks.done = [&](int level, MeshResult result) {
    EXPECT_EQ(level, static_cast<int>(results.size()));
    results.push_back(std::move(result));
    return Status::Ok();
  };
  Status st = MeshModelLevels(*model, options, levels, nullptr, callbacks);
  ASSERT_TRUE(st.ok()) << st.ToString();
  EXPECT_EQ(started, (std::vector<int>{0, 1, 2}));
  ASSERT_EQ(results.size(), levels.size());
  for (size_t i = 0; i < levels.size(); ++i) {
    auto single = MeshModel(*model, LevelOptions(options, levels[i]));
    ASSERT_TRUE(single.ok());
    EXPECT_EQ(results[i].mesh.xyz, single->mesh.xyz) << "level " << i;
    EXPECT_EQ(results[i].mesh.triangles, single->mesh.triangles) << "level " << i;
    EXPECT_EQ(results[i].mesh.triangle_face, single->mesh.triangle_face) << "level " << i;
    EXPECT_EQ(results[i].edges.size(), single->edges.size()) << "level " << i;
    EXPECT_DOUBLE_EQ(results[i].summary.requested_deviation,
                     levels[i] * GetModelInfo(*model).diagonal);
    if (i > 0) EXPECT_LT(results[i - 1].mesh.triangle_count(), results[i].mesh.triangle_count());
  }
}

TEST(LevelsTest, ErrorOfDoneStopsTheRun) {
  auto model = LoadData("axom_sliced_cylinder.step");
  ASSERT_TRUE(model);
  int done = 0;
  LevelCallbacks callbacks;
  callbacks.done = [&](int, MeshResult) {
    ++done;
    return Status(StatusCode::kResourceExhausted, "enough");
  };
  Status st = MeshModelLevels(*model, MeshOptions(), {1e-2, 1e-3}, nullptr, callbacks);
  EXPECT_EQ(st.code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(done, 1);
}

TEST(LevelsTest, CancelledContextStopsBeforeTheNextLevel) {
  auto model = LoadData("axom_sliced_cylinder.step");
  ASSERT_TRUE(model);
  Context context;
  int done = 0;
  LevelCallbacks callbacks;
  callbacks.done = [&](int, MeshResult) {
    ++done;
    context.Cancel();
    return Status::Ok();
  };
  Status st = MeshModelLevels(*model, MeshOptions(), {1e-2, 1e-3}, &context, callbacks);
  EXPECT_EQ(st.code(), StatusCode::kCancelled);
  EXPECT_EQ(done, 1);
}

}  // namespace
}  // namespace rdmesh
