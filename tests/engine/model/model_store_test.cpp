// The parsed-model store: a model loaded from it meshes byte-identically to the one parsed from
// its file; damaged entries are discarded and parsed again, never trusted; the directory stays
// within its limit; names, colours and instances survive.

#include "rdmesh/model_store.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepTools.hxx>
#include <Quantity_Color.hxx>
#include <TCollection_AsciiString.hxx>
#include <TDF_ChildIterator.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include "model/model.h"
#include "rdmesh/engine.h"

namespace rdmesh {
namespace {

std::string TempDir(const std::string& name) {
  std::string dir = ::testing::TempDir() + "/model_store_" + name + "_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string DataFile(const std::string& name) { return std::string(RDMESH_TEST_DATA) + "/" + name; }

/// The mesh of a model at the default options, as the bytes of `path` (.msh or .glb): one byte
/// differing fails a comparison.
std::string MeshBytes(const Model& model, const std::string& path) {
  MeshOptions options;
  options.threads = 2;
  Result<MeshResult> result = MeshModel(model, options);
  EXPECT_TRUE(result.ok()) << result.status().message();
  if (!result.ok()) return "";
  EXPECT_TRUE(WriteMesh(model, *result, path).ok());
  return ReadAll(path);
}

/// Every named or coloured shape label of the document, as "name: colour" lines.
std::set<std::string> NamesAndColours(const Model& model) {
  std::set<std::string> lines;
  if (model.doc.IsNull()) return lines;
  Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(model.doc->Main());
  Handle(XCAFDoc_ColorTool) colours = XCAFDoc_DocumentTool::ColorTool(model.doc->Main());
  TDF_LabelSequence labels;
  shapes->GetShapes(labels);
  for (int i = 1; i <= labels.Length(); ++i) {
    TDF_LabelSequence subshapes;
    shapes->GetSubShapes(labels(i), subshapes);
    subshapes.Prepend(labels(i));
    for (const TDF_Label& label : subshapes) {
      std::string line;
      Handle(TDataStd_Name) name;
      if (label.FindAttribute(TDataStd_Name::GetID(), name))
        line = TCollection_AsciiString(name->Get()).ToCString();
      Quantity_Color colour;
      for (XCAFDoc_ColorType type : {XCAFDoc_ColorGen, XCAFDoc_ColorSurf, XCAFDoc_ColorCurv}) {
        if (colours->GetColor(label, type, colour)) {
          char rgb[64];
          std::snprintf(rgb, sizeof(rgb), " colour %d %.3f %.3f %.3f", static_cast<int>(type),
                        colour.Red(), colour.Green(), colour.Blue());
          line += rgb;
        }
      }
      if (!line.empty()) lines.insert(line);
    }
  }
  return lines;
}

class ModelStoreTest : public ::testing::TestWithParam<const char*> {};

// The STEP path (LoadModel, no store), the first load through the store (a parse that writes the
// entry) and the second (a read of the entry) give the same model and the same mesh bytes.
TEST_P(ModelStoreTest, StoredModelMeshesIdentically) {
  const std::string file = DataFile(GetParam());
  Result<std::shared_ptr<const Model>> parsed = LoadModel(file);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  const std::string dir = TempDir("same");
  ModelStore store(dir + "/store", 0);
  StoreOutcome first, second;
  Result<std::shared_ptr<const Model>> written = store.LoadFile(file, nullptr, &first);
  ASSERT_TRUE(written.ok()) << written.status().message();
  EXPECT_FALSE(first.from_store);
  EXPECT_TRUE(first.problem.empty()) << first.problem;
  EXPECT_TRUE(std::filesystem::exists(dir + "/store/" + first.key + ".rdm"));
  // Another store object on the same directory stands for another process.
  Result<std::shared_ptr<const Model>> stored =
      ModelStore(dir + "/store", 0).LoadFile(file, nullptr, &second);
  ASSERT_TRUE(stored.ok()) << stored.status().message();
  EXPECT_TRUE(second.from_store) << second.problem;
  EXPECT_EQ(first.key, second.key);

  const ModelInfo a = GetModelInfo(**parsed);
  const ModelInfo b = GetModelInfo(**stored);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.format, b.format);
  EXPECT_EQ(a.length_unit, b.length_unit);
  EXPECT_EQ(a.unit_scale_mm, b.unit_scale_mm);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(a.instances, b.instances);
  EXPECT_EQ(a.unique_faces, b.unique_faces);
  EXPECT_EQ(a.part_names, b.part_names);
  EXPECT_EQ(a.bbox, b.bbox);
  EXPECT_EQ(a.diagonal, b.diagonal);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.solids, b.solids);
  EXPECT_EQ(a.shells, b.shells);
  EXPECT_EQ(a.surface_types, b.surface_types);
  EXPECT_EQ(a.closed, b.closed);
  // Stored with the entry, bit for bit.
  EXPECT_EQ((*parsed)->face_area, (*stored)->face_area);
  EXPECT_EQ((*parsed)->max_edge_tolerance, (*stored)->max_edge_tolerance);
  EXPECT_EQ(NamesAndColours(**parsed), NamesAndColours(**stored));
  for (const char* extension : {".msh", ".glb"}) {
    const std::string from_file = MeshBytes(**parsed, dir + "/file" + extension);
    const std::string from_store = MeshBytes(**stored, dir + "/store" + extension);
    const std::string from_first = MeshBytes(**written, dir + "/first" + extension);
    EXPECT_FALSE(from_file.empty());
    EXPECT_TRUE(from_file == from_store)
        << GetParam() << extension << " differs (kept in " << dir << ")";
    EXPECT_TRUE(from_file == from_first)
        << GetParam() << extension << " differs (kept in " << dir << ")";
  }
  if (!HasFailure()) std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(BundledModels, ModelStoreTest,
                         ::testing::Values("axom_sliced_cylinder.step",
                                           "cq_red_cube_blue_cylinder.step", "nist_mbe_pmi_11.stp",
                                           "pyocc_eight_cyl.stp"));

// Two parses of one file write the same payload: replicas that parse a model at once agree.
TEST(ModelStore, PayloadIsDeterministic) {
  const std::string bytes = ReadAll(DataFile("pyocc_eight_cyl.stp"));
  Result<CanonicalModel> a = ParseCanonical(bytes, ModelFormat::kStep, "", "a", "a", nullptr);
  Result<CanonicalModel> b = ParseCanonical(bytes, ModelFormat::kStep, "", "b", "b", nullptr);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_GT(a->payload.size(), 1000u);
  EXPECT_TRUE(a->payload == b->payload);
}

TEST(ModelStore, KeepsNamesColoursAndInstances) {
  const std::string file = DataFile("cq_red_cube_blue_cylinder.step");
  const std::string dir = TempDir("colours");
  ModelStore store(dir, 0);
  ASSERT_TRUE(store.LoadFile(file, nullptr, nullptr).ok());
  StoreOutcome outcome;
  Result<std::shared_ptr<const Model>> stored = store.LoadFile(file, nullptr, &outcome);
  ASSERT_TRUE(stored.ok());
  ASSERT_TRUE(outcome.from_store);
  const std::set<std::string> lines = NamesAndColours(**stored);
  // The file's two named parts, one red and one blue (colours on their faces).
  bool red = false, blue = false;
  for (const std::string& line : lines) {
    double r = 0, g = 0, b = 0;
    const std::size_t at = line.find(" colour ");
    if (at == std::string::npos) continue;
    ASSERT_EQ(std::sscanf(line.c_str() + at, " colour %*d %lf %lf %lf", &r, &g, &b), 3) << line;
    red = red || (r > 0.5 && g < 0.2 && b < 0.2);
    blue = blue || (b > 0.4 && r < 0.1 && g < 0.2);
  }
  std::string all;
  for (const std::string& line : lines) all += line + "\n";
  EXPECT_TRUE(red) << all;
  EXPECT_TRUE(blue) << all;
  EXPECT_EQ(GetModelInfo(**stored).part_names.size(), 2u) << all;
  std::filesystem::remove_all(dir);
}

// BREP models have no document: their payload is a BinTools shape.
TEST(ModelStore, BrepModelsRoundTrip) {
  const std::string dir = TempDir("brep");
  const std::string file = dir + "/cylinder.brep";
  ASSERT_TRUE(BRepTools::Write(BRepPrimAPI_MakeCylinder(5.0, 12.0).Shape(), file.c_str()));
  ModelStore store(dir + "/store", 0);
  StoreOutcome first, second;
  Result<std::shared_ptr<const Model>> parsed = store.LoadFile(file, nullptr, &first);
  Result<std::shared_ptr<const Model>> stored = store.LoadFile(file, nullptr, &second);
  ASSERT_TRUE(parsed.ok() && stored.ok());
  EXPECT_FALSE(first.from_store);
  EXPECT_TRUE(second.from_store) << second.problem;
  EXPECT_EQ(GetModelInfo(**stored).format, "brep");
  EXPECT_TRUE(MeshBytes(**parsed, dir + "/a.msh") == MeshBytes(**stored, dir + "/b.msh"));
  std::filesystem::remove_all(dir);
}

// A truncated or corrupted entry is reported, deleted, parsed again and written again.
TEST(ModelStore, DamagedEntriesAreParsedAgain) {
  const std::string file = DataFile("axom_sliced_cylinder.step");
  const std::string dir = TempDir("damaged");
  ModelStore store(dir, 0);
  StoreOutcome outcome;
  ASSERT_TRUE(store.LoadFile(file, nullptr, &outcome).ok());
  const std::string path = dir + "/" + outcome.key + ".rdm";
  const std::string good = ReadAll(path);
  ASSERT_GT(good.size(), 1000u);
  const std::string reference = MeshBytes(**LoadModel(file), dir + "/reference.msh");

  std::string flipped = good;
  flipped[flipped.size() - 100] ^= 0x5a;
  const struct {
    const char* what;
    std::string bytes;
    const char* problem;
  } kDamages[] = {
      {"truncated", good.substr(0, good.size() * 2 / 3), "truncated"},
      {"one byte flipped", flipped, "checksum"},
      {"header only", good.substr(0, good.find("\n\n") + 1), "truncated"},
      {"not an entry", "ISO-10303-21;\n", "not an rdmesh entry"},
      {"empty", "", "not an rdmesh entry"},
  };
  for (const auto& damage : kDamages) {
    SCOPED_TRACE(damage.what);
    std::ofstream(path, std::ios::binary | std::ios::trunc) << damage.bytes;
    Result<std::shared_ptr<const Model>> model = store.LoadFile(file, nullptr, &outcome);
    ASSERT_TRUE(model.ok()) << model.status().message();
    EXPECT_FALSE(outcome.from_store);
    EXPECT_NE(outcome.problem.find(damage.problem), std::string::npos) << outcome.problem;
    EXPECT_TRUE(MeshBytes(**model, dir + "/again.msh") == reference);
    // Parsed again, the entry is whole again.
    EXPECT_TRUE(ReadAll(path) == good);
  }
  std::string problem;
  EXPECT_EQ(store.Load("absent", ModelFormat::kStep, "x", &problem), nullptr);
  EXPECT_TRUE(problem.empty());
  std::filesystem::remove_all(dir);
}

TEST(ModelStore, EvictsTheLeastRecentlyUsedPastTheLimit) {
  const std::string dir = TempDir("evict");
  const std::string base = ReadAll(DataFile("cq_red_cube_blue_cylinder.step"));
  // Three different files (a comment at the end) of the same model: three entries.
  auto variant = [&](const std::string& tag) { return base + "/* " + tag + " */\n"; };
  StoreOutcome a, b, c;
  ASSERT_TRUE(
      ModelStore(dir, 0).LoadOrParse(variant("a"), ModelFormat::kStep, "a.step", nullptr, &a).ok());
  const uint64_t entry = std::filesystem::file_size(dir + "/" + a.key + ".rdm");
  // Room for two entries: a, b, then a used again, then c evicts b (the least recently used).
  ModelStore store(dir, entry * 2 + entry / 2);
  ASSERT_TRUE(store.LoadOrParse(variant("b"), ModelFormat::kStep, "b.step", nullptr, &b).ok());
  const auto now = std::filesystem::file_time_type::clock::now();
  std::filesystem::last_write_time(dir + "/" + a.key + ".rdm", now - std::chrono::hours(2));
  std::filesystem::last_write_time(dir + "/" + b.key + ".rdm", now - std::chrono::hours(1));
  StoreOutcome again;
  ASSERT_TRUE(store.LoadOrParse(variant("a"), ModelFormat::kStep, "a.step", nullptr, &again).ok());
  ASSERT_TRUE(again.from_store);  // a is now the most recently used
  // A writer that died mid-write two hours ago left this.
  const std::string stale = dir + "/" + b.key + ".rdm.tmp.1.2";
  std::ofstream(stale) << "partial";
  std::filesystem::last_write_time(stale, now - std::chrono::hours(2));
  ASSERT_TRUE(store.LoadOrParse(variant("c"), ModelFormat::kStep, "c.step", nullptr, &c).ok());
  EXPECT_TRUE(std::filesystem::exists(dir + "/" + a.key + ".rdm"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/" + b.key + ".rdm"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/" + c.key + ".rdm"));
  EXPECT_FALSE(std::filesystem::exists(stale));
  uint64_t total = 0;
  for (const auto& item : std::filesystem::directory_iterator(dir)) total += item.file_size();
  EXPECT_LE(total, store.limit_bytes());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rdmesh
