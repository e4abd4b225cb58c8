// The parsed-model store: a model loaded from it meshes byte-identically to the one parsed from
// its file; damaged entries are discarded, never trusted; the directory stays within its limit.

#include "rdmesh/model_store.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "model.h"
#include "rdmesh/engine.h"

namespace rdmesh {
namespace {

std::string TempDir(const std::string& name) {
  std::string dir = ::testing::TempDir() + "/model_store_" + name + "_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  return dir;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// The .msh of a model at 1e-3, as text (one byte differing fails the comparison).
std::string MeshText(const Model& model, const std::string& path) {
  MeshOptions options;
  options.threads = 2;
  Result<MeshResult> result = MeshModel(model, options);
  EXPECT_TRUE(result.ok()) << result.status().message();
  if (!result.ok()) return "";
  EXPECT_TRUE(WriteMesh(model, *result, path).ok());
  return ReadAll(path);
}

class ModelStoreTest : public ::testing::TestWithParam<const char*> {};

TEST_P(ModelStoreTest, StoredModelMeshesIdentically) {
  const std::string file = std::string(RDMESH_TEST_DATA) + "/" + GetParam();
  Result<std::shared_ptr<const Model>> parsed = LoadModel(file);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  const std::string dir = TempDir("same");
  ModelStore store(dir, 0);
  Status saved = store.Save("key", **parsed);
  ASSERT_TRUE(saved.ok()) << saved.message();
  std::string problem;
  std::shared_ptr<const Model> stored = store.Load("key", &problem);
  ASSERT_NE(stored, nullptr) << problem;
  const ModelInfo a = GetModelInfo(**parsed);
  const ModelInfo b = GetModelInfo(*stored);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.format, b.format);
  EXPECT_EQ(a.length_unit, b.length_unit);
  EXPECT_EQ(a.unit_scale_mm, b.unit_scale_mm);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(a.instances, b.instances);
  EXPECT_EQ(a.part_names, b.part_names);
  EXPECT_EQ(a.bbox, b.bbox);
  for (const char* extension : {".msh", ".glb"}) {
    const std::string from_file = MeshText(**parsed, dir + "/a" + extension);
    const std::string from_store = MeshText(*stored, dir + "/b" + extension);
    EXPECT_FALSE(from_file.empty());
    EXPECT_TRUE(from_file == from_store)
        << GetParam() << extension << " differs (kept in " << dir << ")";
  }
  if (!HasFailure()) std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(BundledModels, ModelStoreTest,
                         ::testing::Values("axom_sliced_cylinder.step",
                                           "cq_red_cube_blue_cylinder.step", "nist_mbe_pmi_11.stp",
                                           "pyocc_eight_cyl.stp"));

TEST(ModelStore, DamagedEntriesAreDiscarded) {
  Result<std::shared_ptr<const Model>> parsed =
      LoadModel(std::string(RDMESH_TEST_DATA) + "/axom_sliced_cylinder.step");
  ASSERT_TRUE(parsed.ok());
  const std::string dir = TempDir("damaged");
  ModelStore store(dir, 0);
  ASSERT_TRUE(store.Save("k", **parsed).ok());
  const std::string path = dir + "/k.rdm";
  const std::string good = ReadAll(path);
  std::string problem;

  // Truncated: a crash mid-copy, a full disk.
  std::ofstream(path, std::ios::binary) << good.substr(0, good.size() * 2 / 3);
  EXPECT_EQ(store.Load("k", &problem), nullptr);
  EXPECT_NE(problem.find("truncated"), std::string::npos) << problem;
  EXPECT_FALSE(std::filesystem::exists(path));

  // One byte flipped in the payload.
  std::string flipped = good;
  flipped[flipped.size() - 100] ^= 0x5a;
  std::ofstream(path, std::ios::binary) << flipped;
  EXPECT_EQ(store.Load("k", &problem), nullptr);
  EXPECT_NE(problem.find("checksum"), std::string::npos) << problem;
  EXPECT_FALSE(std::filesystem::exists(path));

  // Not an entry at all.
  std::ofstream(path, std::ios::binary) << "ISO-10303-21;\n";
  EXPECT_EQ(store.Load("k", &problem), nullptr);
  EXPECT_FALSE(problem.empty());

  // Absent: null, and no problem to report.
  EXPECT_EQ(store.Load("absent", &problem), nullptr);
  EXPECT_TRUE(problem.empty());
  std::filesystem::remove_all(dir);
}

TEST(ModelStore, EvictsTheLeastRecentlyUsedPastTheLimit) {
  Result<std::shared_ptr<const Model>> parsed =
      LoadModel(std::string(RDMESH_TEST_DATA) + "/cq_red_cube_blue_cylinder.step");
  ASSERT_TRUE(parsed.ok());
  const std::string dir = TempDir("evict");
  ModelStore unlimited(dir, 0);
  ASSERT_TRUE(unlimited.Save("a", **parsed).ok());
  const uint64_t entry = std::filesystem::file_size(dir + "/a.rdm");
  // Room for two entries: a, b, then a used again, then c evicts b (the least recently used).
  ModelStore store(dir, entry * 2 + entry / 2);
  ASSERT_TRUE(store.Save("b", **parsed).ok());
  std::filesystem::last_write_time(
      dir + "/a.rdm", std::filesystem::file_time_type::clock::now() - std::chrono::hours(2));
  std::filesystem::last_write_time(
      dir + "/b.rdm", std::filesystem::file_time_type::clock::now() - std::chrono::hours(1));
  std::string problem;
  ASSERT_NE(store.Load("a", &problem), nullptr) << problem;  // a is now the most recent
  ASSERT_TRUE(store.Save("c", **parsed).ok());
  EXPECT_TRUE(std::filesystem::exists(dir + "/a.rdm"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/b.rdm"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/c.rdm"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rdmesh
