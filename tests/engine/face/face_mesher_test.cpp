// The face mesher's reasons for a face meshed over its criteria.
#include "face/face_mesher.h"

#include <gtest/gtest.h>

#include <string>

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

}  // namespace
}  // namespace rdmesh
