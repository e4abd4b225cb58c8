#include "daemon/model_index.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "rdmesh/sha256.h"

namespace rdmesh::server {
namespace {

namespace pb = ::rdmesh::v1;

class ModelIndexTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/model_index_" + std::to_string(getpid());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  /// A parse that describes any model as `faces` faces and counts its calls.
  ModelIndex::ParseFn Parse(int faces) {
    return [this, faces](const StoredModel& spooled, bool*) -> Result<pb::ModelInfo> {
      ++parses_;
      EXPECT_TRUE(std::filesystem::exists(spooled.path)) << spooled.path;
      pb::ModelInfo info;
      info.set_faces(faces);
      info.set_load_seconds(0.25);
      return info;
    };
  }

  std::string dir_;
  std::atomic<int> parses_{0};
};

TEST_F(ModelIndexTest, SpoolsParsesOnceAndFinds) {
  ModelIndex index(dir_, 1 << 20);
  bool cached = true;
  auto first =
      index.GetOrParse("ISO-10303-21;\nA", "a.step", ModelFormat::kAuto, Parse(3), &cached);
  ASSERT_TRUE(first.ok()) << first.status().message();
  EXPECT_FALSE(cached);
  EXPECT_EQ((*first)->id, Sha256Hex("ISO-10303-21;\nA"));
  EXPECT_EQ((*first)->format, ModelFormat::kStep);
  EXPECT_EQ((*first)->info.faces(), 3);
  EXPECT_EQ((*first)->load_seconds, 0.25);
  auto again =
      index.GetOrParse("ISO-10303-21;\nA", "other.step", ModelFormat::kAuto, Parse(3), &cached);
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(cached);
  EXPECT_EQ(parses_, 1);
  EXPECT_EQ(index.Find((*first)->id), *first);
  EXPECT_EQ(index.Find(Sha256Hex("nothing")), nullptr);
}

TEST_F(ModelIndexTest, ConcurrentUploadsOfTheSameBytesParseOnce) {
  ModelIndex index(dir_, 1 << 20);
  ModelIndex::ParseFn slow = [this](const StoredModel&, bool*) -> Result<pb::ModelInfo> {
    ++parses_;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    pb::ModelInfo info;
    info.set_faces(1);
    return info;
  };
  std::vector<std::thread> threads;
  std::atomic<int> ok{0};
  for (int i = 0; i < 4; ++i) {
    threads.emplace_back([&] {
      bool cached = false;
      if (index.GetOrParse("same bytes", "m.step", ModelFormat::kStep, slow, &cached).ok()) ++ok;
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(ok, 4);
  EXPECT_EQ(parses_, 1);
}

TEST_F(ModelIndexTest, AFailedParseLeavesNoSpoolFileAndACrashIsRefusedAfterwards) {
  ModelIndex index(dir_, 1 << 20);
  bool cached = false;
  ModelIndex::ParseFn fails = [this](const StoredModel&, bool* refuse) -> Result<pb::ModelInfo> {
    ++parses_;
    *refuse = false;
    return Status(StatusCode::kParseError, "not a valid STEP file");
  };
  EXPECT_FALSE(index.GetOrParse("bad", "bad.step", ModelFormat::kStep, fails, &cached).ok());
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
  EXPECT_FALSE(index.GetOrParse("bad", "bad.step", ModelFormat::kStep, fails, &cached).ok());
  EXPECT_EQ(parses_, 2);  // a plain parse error is tried again (a new server, new OCCT...)

  ModelIndex::ParseFn crashes = [this](const StoredModel&, bool* refuse) -> Result<pb::ModelInfo> {
    ++parses_;
    *refuse = true;
    return Status(StatusCode::kParseError, "the STEP reader crashed (SIGSEGV) on this model");
  };
  auto crashed = index.GetOrParse("evil", "evil.step", ModelFormat::kStep, crashes, &cached);
  ASSERT_FALSE(crashed.ok());
  auto refused = index.GetOrParse("evil", "again.step", ModelFormat::kStep, Parse(1), &cached);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kParseError);
  EXPECT_NE(refused.status().message().find("crashed (SIGSEGV) on this model before"),
            std::string::npos);
  EXPECT_EQ(parses_, 3);  // the refused bytes were not parsed again
  EXPECT_EQ(index.refused(), 1);
}

TEST_F(ModelIndexTest, EvictionDeletesTheLeastRecentlyUsedSpoolFiles) {
  ModelIndex index(dir_, 25);  // room for two 10-byte models
  bool cached = false;
  auto a = index.GetOrParse("aaaaaaaaaa", "a.step", ModelFormat::kStep, Parse(1), &cached);
  auto b = index.GetOrParse("bbbbbbbbbb", "b.step", ModelFormat::kStep, Parse(1), &cached);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NE(index.Find((*a)->id), nullptr);  // a is now the most recently used
  auto c = index.GetOrParse("cccccccccc", "c.step", ModelFormat::kStep, Parse(1), &cached);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(index.size(), 2);
  EXPECT_EQ(index.bytes(), 20u);
  EXPECT_EQ(index.Find((*b)->id), nullptr);
  EXPECT_FALSE(std::filesystem::exists((*b)->path));
  EXPECT_TRUE(std::filesystem::exists((*a)->path));
  EXPECT_TRUE(std::filesystem::exists((*c)->path));
}

}  // namespace
}  // namespace rdmesh::server
