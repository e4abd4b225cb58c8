#include "worker/model_cache.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "rdmesh/sha256.h"

namespace rdmesh::server {
namespace {

std::string ReadData(const std::string& name) {
  std::ifstream in(std::string(RDMESH_TEST_DATA) + "/" + name, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

TEST(ModelCacheTest, SameBytesAreParsedOnce) {
  const std::string bytes = ReadData("cq_red_cube_blue_cylinder.step");
  ASSERT_FALSE(bytes.empty());
  ModelCache cache(1 << 30);
  bool cached = true;
  auto first = cache.GetOrLoad(bytes, "cube.step", ModelFormat::kAuto, &cached);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_FALSE(cached);
  EXPECT_EQ((*first)->id, Sha256Hex(bytes));
  EXPECT_GT((*first)->info.faces, 0);
  EXPECT_EQ((*first)->file_bytes, bytes.size());

  auto second = cache.GetOrLoad(bytes, "other-name.step", ModelFormat::kAuto, &cached);
  ASSERT_TRUE(second.ok());
  EXPECT_TRUE(cached);
  EXPECT_EQ(second->get(), first->get());
  EXPECT_EQ(cache.Find((*first)->id).get(), first->get());
  EXPECT_EQ(cache.size(), 1);
  EXPECT_EQ(cache.bytes(), bytes.size());
}

TEST(ModelCacheTest, ConcurrentLoadsOfTheSameBytesShareOneModel) {
  const std::string bytes = ReadData("axom_sliced_cylinder.step");
  ModelCache cache(1 << 30);
  std::vector<std::shared_ptr<const CachedModel>> got(4);
  std::vector<std::thread> threads;
  for (int i = 0; i < 4; ++i) {
    threads.emplace_back([&, i] {
      bool cached = false;
      auto entry = cache.GetOrLoad(bytes, "cyl.step", ModelFormat::kAuto, &cached);
      if (entry.ok()) got[i] = *entry;
    });
  }
  for (std::thread& t : threads) t.join();
  for (const auto& entry : got) {
    ASSERT_NE(entry, nullptr);
    EXPECT_EQ(entry.get(), got[0].get());
  }
  EXPECT_EQ(cache.size(), 1);
}

TEST(ModelCacheTest, BadBytesAreErrorsAndNotCached) {
  ModelCache cache(1 << 30);
  bool cached = false;
  auto empty = cache.GetOrLoad("", "x.step", ModelFormat::kAuto, &cached);
  EXPECT_EQ(empty.status().code(), StatusCode::kParseError);
  auto garbage = cache.GetOrLoad(std::string(5000, '\x7f'), "x.step", ModelFormat::kAuto, &cached);
  EXPECT_FALSE(garbage.ok());
  const std::string bytes = ReadData("cq_red_cube_blue_cylinder.step");
  auto truncated =
      cache.GetOrLoad(bytes.substr(0, bytes.size() / 2), "half.step", ModelFormat::kAuto, &cached);
  EXPECT_FALSE(truncated.ok());
  EXPECT_NE(truncated.status().code(), StatusCode::kOk);
  EXPECT_EQ(cache.size(), 0);
}

TEST(ModelCacheTest, EvictsTheLeastRecentlyUsed) {
  const std::string a = ReadData("cq_red_cube_blue_cylinder.step");
  const std::string b = ReadData("axom_sliced_cylinder.step");
  const std::string c = ReadData("pyocc_eight_cyl.stp");
  ModelCache cache(a.size() + b.size() + c.size() - 1);  // room for two of the three
  bool cached = false;
  ASSERT_TRUE(cache.GetOrLoad(a, "a.step", ModelFormat::kAuto, &cached).ok());
  ASSERT_TRUE(cache.GetOrLoad(b, "b.step", ModelFormat::kAuto, &cached).ok());
  ASSERT_NE(cache.Find(Sha256Hex(a)), nullptr);  // a is now the most recently used
  ASSERT_TRUE(cache.GetOrLoad(c, "c.stp", ModelFormat::kAuto, &cached).ok());
  EXPECT_NE(cache.Find(Sha256Hex(a)), nullptr);
  EXPECT_EQ(cache.Find(Sha256Hex(b)), nullptr);
  EXPECT_NE(cache.Find(Sha256Hex(c)), nullptr);
  EXPECT_LE(cache.bytes(), cache.limit_bytes());
}

TEST(ModelCacheTest, KeepsTheNewestEntryEvenWhenItAlonePassesTheLimit) {
  const std::string a = ReadData("cq_red_cube_blue_cylinder.step");
  ModelCache cache(10);
  bool cached = false;
  ASSERT_TRUE(cache.GetOrLoad(a, "a.step", ModelFormat::kAuto, &cached).ok());
  EXPECT_NE(cache.Find(Sha256Hex(a)), nullptr);
  EXPECT_EQ(cache.size(), 1);
}

// Two workers (two caches) sharing one store: the second reads what the first parsed.
TEST(ModelCacheTest, WorkersShareTheStore) {
  const std::string bytes = ReadData("pyocc_eight_cyl.stp");
  const std::string dir = ::testing::TempDir() + "/model_cache_store_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  auto store = std::make_shared<const ModelStore>(dir, 0);
  ModelCache parsing(1 << 30, store), reading(1 << 30, store);
  bool cached = true;
  auto parsed = parsing.GetOrLoad(bytes, "eight.stp", ModelFormat::kAuto, &cached);
  ASSERT_TRUE(parsed.ok()) << parsed.status().ToString();
  EXPECT_FALSE((*parsed)->from_store);
  EXPECT_TRUE((*parsed)->store_problem.empty()) << (*parsed)->store_problem;
  auto read = reading.GetOrLoad(bytes, "eight.stp", ModelFormat::kAuto, &cached);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_FALSE(cached);  // not in this worker's memory
  EXPECT_TRUE((*read)->from_store);
  EXPECT_EQ((*read)->id, (*parsed)->id);
  EXPECT_EQ((*read)->info.faces, (*parsed)->info.faces);
  EXPECT_EQ((*read)->info.bbox, (*parsed)->info.bbox);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rdmesh::server
