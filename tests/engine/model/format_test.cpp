// Format detection: the engine's one rule (ResolveFormat), used by LoadModel, LoadModelFromBytes,
// the model store and the service.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "rdmesh/model_info.h"

namespace rdmesh {
namespace {

std::string ReadData(const std::string& name) {
  std::ifstream in(std::string(RDMESH_TEST_DATA) + "/" + name, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

TEST(FormatTest, FromExtension) {
  EXPECT_EQ(FormatFromExtension("a/b/Part.STEP"), ModelFormat::kStep);
  EXPECT_EQ(FormatFromExtension("part.stp"), ModelFormat::kStep);
  EXPECT_EQ(FormatFromExtension("part.igs"), ModelFormat::kIges);
  EXPECT_EQ(FormatFromExtension("part.iges"), ModelFormat::kIges);
  EXPECT_EQ(FormatFromExtension("part.brep"), ModelFormat::kBrep);
  EXPECT_EQ(FormatFromExtension("part.brp"), ModelFormat::kBrep);
  EXPECT_EQ(FormatFromExtension("part.txt"), ModelFormat::kAuto);
  EXPECT_EQ(FormatFromExtension("noextension"), ModelFormat::kAuto);
}

TEST(FormatTest, FromContentRecognisesStepBrepAndIges) {
  EXPECT_EQ(FormatFromContent(ReadData("cq_red_cube_blue_cylinder.step")), ModelFormat::kStep);
  EXPECT_EQ(FormatFromContent("\xEF\xBB\xBF  \nISO-10303-21;\n"), ModelFormat::kStep);
  EXPECT_EQ(FormatFromContent("DBRep_DrawableShape\n\nCASCADE Topology V1, (c) Matra-Datavision\n"),
            ModelFormat::kBrep);
  std::string iges(72, ' ');
  iges += "S      1\n";
  EXPECT_EQ(FormatFromContent(iges), ModelFormat::kIges);
  EXPECT_EQ(FormatFromContent("garbage"), ModelFormat::kAuto);
  // The STEP header must open the file: mentioned further on, it does not make a STEP file.
  EXPECT_EQ(FormatFromContent("/* ISO-10303-21 */\n"), ModelFormat::kAuto);
}

TEST(FormatTest, ResolveTakesTheFormatThenTheExtensionThenTheContent) {
  const std::string step = "ISO-10303-21;\n";
  EXPECT_EQ(ResolveFormat(ModelFormat::kIges, "part.step", step), ModelFormat::kIges);
  EXPECT_EQ(ResolveFormat(ModelFormat::kAuto, "part.brep", step), ModelFormat::kBrep);
  EXPECT_EQ(ResolveFormat(ModelFormat::kAuto, "upload", step), ModelFormat::kStep);
  EXPECT_EQ(ResolveFormat(ModelFormat::kAuto, "upload", "garbage"), ModelFormat::kAuto);
}

}  // namespace
}  // namespace rdmesh
