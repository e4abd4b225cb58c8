// The checks that refuse a STEP file before OCCT transfers it: they catch what crashes OCCT and
// refuse no real model.

#include "model/step_precheck.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "model/model.h"
#include "model/model_readers.h"
#include "rdmesh/engine.h"

namespace rdmesh {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
}

// tests/data/axom_sliced_cylinder.step with `from` replaced by `to` (which must be there).
std::string SlicedCylinder(const std::string& from, const std::string& to) {
  std::string bytes = ReadBytes(fs::path(RDMESH_TEST_DATA) / "axom_sliced_cylinder.step");
  size_t at = bytes.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? bytes : bytes.replace(at, from.size(), to);
}

TEST(StepPrecheckTest, RefusesOrientedEdgeCycles) {
  const std::string oe29 = "#29=ORIENTED_EDGE('',*,*,#50,.T.);";
  const std::string oe30 = "#30=ORIENTED_EDGE('',*,*,#48,.F.);";
  EXPECT_EQ(StepCrashReason(SlicedCylinder(oe29, oe29)), "");

  std::string self = SlicedCylinder(oe29, "#29 = ORIENTED_EDGE ( 'a,b)', *, *, #29, .T. ) ;");
  EXPECT_NE(StepCrashReason(self).find("ORIENTED_EDGE #29 is its own edge_element"),
            std::string::npos);

  std::string pair = SlicedCylinder(oe29, "#29=ORIENTED_EDGE('',*,*,#30,.T.);");
  pair.replace(pair.find(oe30), oe30.size(), "#30=ORIENTED_EDGE('',*,*,#29,.F.);");
  EXPECT_NE(StepCrashReason(pair), "");

  // An ORIENTED_EDGE of an ORIENTED_EDGE of an EDGE_CURVE ends: OCCT recurses once more.
  std::string chain = SlicedCylinder(oe29, "#29=ORIENTED_EDGE('',*,*,#30,.T.);");
  EXPECT_EQ(StepCrashReason(chain), "");

  Result<std::shared_ptr<const Model>> model = LoadModelFromBytes(self, ModelFormat::kStep, "self");
  ASSERT_FALSE(model.ok());
  EXPECT_EQ(model.status().code(), StatusCode::kParseError);
  EXPECT_NE(model.status().message().find("cannot read 'self': ORIENTED_EDGE #29"),
            std::string::npos);
}

// Found by scripts/fuzz_smoke.sh: a file missing the lines of its EDGE_CURVEs (a part cut out,
// the trailer kept). OCCT 7.6 keeps an unresolved reference as a record number, which can land on
// an ORIENTED_EDGE: the same endless recursion as a cycle. Without the crash the model loaded with
// an infinite bounding box. tests/data/fuzz/crash_reader_missing_edges.step is such a file.
TEST(StepPrecheckTest, RefusesOrientedEdgeOfUndefinedEdge) {
  std::string bytes = ReadBytes(fs::path(RDMESH_TEST_DATA) / "cq_red_cube_blue_cylinder.step");
  const std::string edge = "#210 = EDGE_CURVE( '', #233, #234, #235, .T. );\n";
  ASSERT_EQ(StepCrashReason(bytes), "");
  size_t at = bytes.find(edge);
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(StepCrashReason(std::string(bytes).erase(at, edge.size())),
            "ORIENTED_EDGE #146 names #210 as its edge_element, and the file does not define it");
  // A record OCCT's parser drops ("KEYWORD," instead of "KEYWORD(") defines nothing: found by
  // CI's scripts/fuzz_smoke.sh (tests/data/fuzz/crash_reader_malformed_keyword.step).
  std::string malformed = bytes;
  malformed.replace(at, 12, "#210 = EDG,_");
  EXPECT_EQ(StepCrashReason(malformed),
            "ORIENTED_EDGE #146 names #210 as its edge_element, and the file does not define it");
  // Defined further on, or as a complex instance: fine.
  std::string moved = std::string(bytes).erase(at, edge.size());
  moved.replace(moved.find("ENDSEC;", moved.find("DATA;")), 0,
                "#210 = ( EDGE_CURVE( '', #233, #234, #235, .T. ) );\n");
  EXPECT_EQ(StepCrashReason(moved), "");
}

// Ids defined twice: OCCT resolves a reference to the nearest record of that id, so a cycle can
// hide behind a later definition (found by scripts/fuzz_smoke.sh as a CrossOver of two seeds).
TEST(StepPrecheckTest, RefusesDuplicateIds) {
  const std::string oe29 = "#29=ORIENTED_EDGE('',*,*,#50,.T.);";
  std::string hidden = SlicedCylinder(
      oe29, "#29=ORIENTED_EDGE('',*,*,#30,.T.);\n#30=ORIENTED_EDGE('',*,*,#29,.F.);\n" + oe29);
  EXPECT_EQ(StepCrashReason(hidden), "entity #29 is defined more than once");
  // The same text in a string or a comment is no definition.
  EXPECT_EQ(StepCrashReason(SlicedCylinder(oe29, oe29 + "/* #29=ORIENTED_EDGE */")), "");
  EXPECT_EQ(StepCrashReason(SlicedCylinder(oe29, "/* #29=ORIENTED_EDGE */" + oe29)), "");
  // A string left open before them hides both definitions from a scan that skips strings (the
  // quotes pair up one off from there on): found by CI's scripts/fuzz_smoke.sh, and OCCT died on
  // tests/data/fuzz/crash_duplicate_id_broken_string.step with SIGSEGV.
  const std::string loop28 = "#28=EDGE_LOOP('',(#43,#44,#45,#46));";
  std::string broken = SlicedCylinder(loop28, "#28=EDGE_LOOP(''',(#43,#44,#45,#46));");
  broken.replace(broken.find(oe29), oe29.size(),
                 "#29=ORIENTED_EDGE('',*,*,#30,.T.);\n#30=ORIENTED_EDGE('',*,*,#29,.F.);\n" + oe29);
  EXPECT_EQ(StepCrashReason(broken), "entity #29 is defined more than once");
}

TEST(StepPrecheckTest, RefusesAbsurdNesting) {
  const std::string loop = "#24=EDGE_LOOP('',(#29,#30,#31,#32));";
  auto nested = [&loop](int depth, const std::string& inner) {
    return SlicedCylinder(loop, "#900=FOO(" + std::string(depth - 1, '(') + inner +
                                    std::string(depth - 1, ')') + ");\n" + loop);
  };
  EXPECT_EQ(StepCrashReason(nested(kMaxStepNesting, "1")), "");
  EXPECT_NE(StepCrashReason(nested(kMaxStepNesting + 1, "1")).find("nested more than"),
            std::string::npos);
  // Parentheses in strings and comments do not count.
  std::string many(3 * kMaxStepNesting, '(');
  EXPECT_EQ(StepCrashReason(nested(3, "'" + many + "'")), "");
  EXPECT_EQ(StepCrashReason(nested(3, "/*" + many + "*/ 1")), "");
}

TEST(StepPrecheckTest, RefusesInfiniteNumbers) {
  const std::string point = "#190=CARTESIAN_POINT('',(0.,-10.,0.));";
  auto with_x = [&point](const std::string& x) {
    return SlicedCylinder(point, "#190=CARTESIAN_POINT('" + x + "',(" + x + ",-10.,0.));");
  };
  EXPECT_EQ(StepCrashReason(with_x("1.E+300")), "");
  EXPECT_EQ(StepCrashReason(with_x("-1.5E-320")), "");  // underflows to a subnormal: harmless
  EXPECT_EQ(StepCrashReason(with_x("0.")), "");
  EXPECT_NE(
      StepCrashReason(with_x("1.E+999")).find("a CARTESIAN_POINT coordinate (1.E+999) is beyond"),
      std::string::npos);
  EXPECT_NE(StepCrashReason(with_x("-2.5e309")).find("-2.5e309"), std::string::npos);
  // Only numbers count, not keywords; and only in points.
  EXPECT_EQ(StepCrashReason(SlicedCylinder(point, "#190=CARTESIAN_POINT('',(0.,-10.,0.)),E999;")),
            "");
  EXPECT_EQ(StepCrashReason(SlicedCylinder(point, point + "#9000=DIRECTION('',(1.E+999,0.,0.));")),
            "");
}

// libFuzzer's find (scripts/fuzz_smoke.sh): a copied part of the file left a string open, so
// a scan that skips strings saw the infinite point as quoted text; OCCT's parser did not.
TEST(StepPrecheckTest, BrokenStringHidesNothing) {
  const std::string point = "#190=CARTESIAN_POINT('',(0.,-10.,0.));";
  std::string bytes = SlicedCylinder(point, "#190=CARTESIAN_POINT('',(1.E+999,-10.,0.));");
  const std::string context =
      "#80=PRODUCT_DEFINITION_CONTEXT('3D Mechanical Parts',#153,'design');";
  bytes.replace(bytes.find(context), context.size(), "#80=PRODUCT_DEFINITION_CONTEXT('3D;");
  EXPECT_NE(StepCrashReason(bytes).find("1.E+999"), std::string::npos);
}

// The CAx-IF case: a shape representation listing an item of a type OCCT 7.6 does not know.
// The parser complains ("Entity has illegal type"), and the transfer is fine.
TEST(StepPrecheckTest, UnknownItemTypeIsAccepted) {
  std::string bytes = ReadBytes(fs::path(RDMESH_TEST_DATA) / "cq_red_cube_blue_cylinder.step");
  const std::string items = "ADVANCED_BREP_SHAPE_REPRESENTATION( 'blue_cylinder', ( #57, #58 )";
  size_t at = bytes.find(items);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, items.size(),
                "ADVANCED_BREP_SHAPE_REPRESENTATION( 'blue_cylinder', ( #57, "
                "#58, #9000 )");
  bytes.replace(bytes.find("ENDSEC;", bytes.find("DATA;")), 0,
                "#9000 = NEW_AP242_ITEM( 'x', #57 );\n");
  EXPECT_TRUE(CheckStepBytes(bytes, "unknown_item.step").ok());
  Result<std::shared_ptr<const Model>> model =
      LoadModelFromBytes(bytes, ModelFormat::kStep, "unknown_item.step");
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  EXPECT_EQ(GetModelInfo(**model).faces, 9);
}

// Every bundled and corpus model passes the checks (the corpus is skipped where absent).
TEST(StepPrecheckTest, RefusesNoRealModel) {
  std::vector<fs::path> files;
  for (const fs::path& dir : {fs::path(RDMESH_TEST_DATA), fs::path(RDMESH_SHARED_DIR) / "corpus"}) {
    if (!fs::is_directory(dir)) continue;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
      std::string ext = entry.path().extension().string();
      if (ext == ".step" || ext == ".stp") files.push_back(entry.path());
    }
  }
  int bundled = 0;
  for (const fs::path& file : files) {
    bundled += file.parent_path() == fs::path(RDMESH_TEST_DATA);
    std::string bytes = ReadBytes(file);
    EXPECT_EQ(StepCrashReason(bytes), "") << file;
    Status status = CheckStepBytes(bytes, file.filename().string());
    EXPECT_TRUE(status.ok()) << status.ToString();
  }
  EXPECT_GE(bundled, 4) << "tests/data must hold its STEP models";
}

}  // namespace
}  // namespace rdmesh
