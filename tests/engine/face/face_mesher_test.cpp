// The face mesher's reasons for a face meshed over its criteria, and what it leaves folded.
#include "face/face_mesher.h"

#include <gtest/gtest.h>

#include <string>

#include "domain_fixture.h"
#include "model/model.h"
#include "rdmesh/engine.h"

namespace rdmesh {
namespace {

const char kBeyond[] = "beyond that, some triangles could not be refined";

TEST(FaceMesherTest, BrepReasonNamesTheBrepsOffsets) {
  const std::string reason = BrepReason(0.00381, 0.00761, 0.00589, 0.00761);
  EXPECT_EQ(reason,
            "the B-rep prevents the requested deviation 0.00381: its edge tolerance is up to "
            "0.00589 and its edges lie up to 0.00761 off its surface");
}

TEST(FaceMesherTest, BrepReasonSaysWhenTheMissIsMoreThanTheBrepExplains) {
  // Request 0.00381, edges 0.00581 off: up to 0.00962 is the B-rep's.
  EXPECT_EQ(BrepReason(0.00381, 0.00581, 0.00414, 0.0096).find(kBeyond), std::string::npos);
  EXPECT_EQ(BrepReason(0.00381, 0.00581, 0.00414, 0).find(kBeyond), std::string::npos);
  const std::string over = BrepReason(0.00381, 0.00581, 0.00414, 0.121);
  EXPECT_NE(over.find("its edges lie up to 0.00581 off its surface; " + std::string(kBeyond)),
            std::string::npos)
      << over;
  EXPECT_NE(over.find("without folding (up to 0.121)"), std::string::npos) << over;
  // A coarse tolerance explains as much as a gap does.
  EXPECT_EQ(BrepReason(0.00067, 0.0003, 0.00886, 0.009).find(kBeyond), std::string::npos);
  EXPECT_NE(BrepReason(0.00067, 0.0003, 0.00886, 0.01).find(kBeyond), std::string::npos);
}

// Triangles whose normal points against the surface normals at their corners.
int FoldedTriangles(const FaceMesh& f) {
  int folded = 0;
  for (int64_t t = 0; t < f.triangle_count(); ++t) {
    const int32_t* c = &f.triangles[3 * t];
    double e[2][3], n[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
      e[0][i] = f.xyz[3 * c[1] + i] - f.xyz[3 * c[0] + i];
      e[1][i] = f.xyz[3 * c[2] + i] - f.xyz[3 * c[0] + i];
      for (int k = 0; k < 3; ++k) n[i] += f.normals[3 * c[k] + i];
    }
    const double cross[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1],
                             e[0][2] * e[1][0] - e[0][0] * e[1][2],
                             e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    folded += cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2] < 0;
  }
  return folded;
}

// KiCad's Crystal_HC33-U: faces 3 and 12 are surfaces of revolution whose profile circle
// crosses their axis, so each pinches to a point inside the face and turns inside out there.
// Meshed as if they had no singular lines (FaceJob::singular_lines unset), refinement leaves
// triangles across the pinch folded; flips after it undo them (22 folded without the flips).
TEST(FaceMesherTest, FlipsUndoFoldsThatRefinementLeaves) {
  Context context;
  Result<std::shared_ptr<const Model>> model =
      LoadModel(std::string(RDMESH_TEST_DATA) + "/kicad/Crystal_HC33-U_Horizontal.step", &context);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  const Model& m = **model;
  const double deviation = 1e-3 * GetModelInfo(m).diagonal;
  const FacePcurves pcurves = testing::Pcurves(m);
  const std::vector<EdgeGrid> grids = testing::Grids(m, deviation);
  FaceJob job;
  job.criteria.max_deviation = deviation;
  job.max_triangles = 1'000'000;
  int folded = 0, over = 0;
  for (int face : {3, 12}) {
    std::vector<NodeRef> refs;
    const FaceMesh f = MeshFace(m, pcurves, face, grids, job, nullptr, &refs);
    ASSERT_EQ(f.status, FaceStatus::kOk) << f.reason;
    EXPECT_EQ(f.surface_type, SurfaceType::kRevolution);
    folded += FoldedTriangles(f);
    over += f.reason.find("could not be refined") != std::string::npos;
  }
  EXPECT_EQ(over, 2);  // the folds are there to undo
  EXPECT_EQ(folded, 0);
}

// The same file as a run meshes it: the pinches are singular lines, kept out of the triangles,
// so nothing folds and no face is left over its criteria.
TEST(FaceMesherTest, SingularLinesLeaveNothingToUndo) {
  Context context;
  Result<std::shared_ptr<const Model>> model =
      LoadModel(std::string(RDMESH_TEST_DATA) + "/kicad/Crystal_HC33-U_Horizontal.step", &context);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  MeshOptions options;
  options.max_deviation_rel = 1e-3;
  Result<MeshResult> result = MeshModel(**model, options);
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  int folded = 0;
  for (const FaceMesh& f : result->faces) {
    EXPECT_EQ(f.reason, "") << "face " << f.face_id;
    folded += FoldedTriangles(f);
  }
  EXPECT_EQ(folded, 0);
}

}  // namespace
}  // namespace rdmesh
