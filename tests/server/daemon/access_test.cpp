#include "daemon/access.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "rdmesh/sha256.h"

namespace rdmesh::server {
namespace {
namespace fs = std::filesystem;

class DataRootTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() / ("rdmesh_access_" + std::to_string(::getpid()));
    fs::remove_all(base_);
    fs::create_directories(base_ / "root" / "parts");
    std::ofstream(base_ / "root" / "parts" / "a.step") << "ISO-10303-21;";
    std::ofstream(base_ / "secret.step") << "outside";
    fs::create_symlink(base_ / "secret.step", base_ / "root" / "link.step");
  }
  void TearDown() override { fs::remove_all(base_); }
  std::string root() const { return (base_ / "root").string(); }
  fs::path base_;
};

TEST_F(DataRootTest, FilesUnderTheRootResolve) {
  Result<std::string> path = ResolveUnderRoot(root(), "parts/a.step");
  ASSERT_TRUE(path.ok()) << path.status().ToString();
  EXPECT_EQ(fs::path(*path), fs::canonical(base_ / "root" / "parts" / "a.step"));
  Result<std::string> absolute = ResolveUnderRoot(root(), *path);
  EXPECT_TRUE(absolute.ok());
  Result<std::string> dotted = ResolveUnderRoot(root(), "parts/../parts/./a.step");
  EXPECT_TRUE(dotted.ok());
}

TEST_F(DataRootTest, NothingOutsideTheRoot) {
  for (const std::string& outside :
       {std::string("../secret.step"), std::string("parts/../../secret.step"),
        (base_ / "secret.step").string(), std::string("/etc/passwd"), std::string("link.step")}) {
    Result<std::string> path = ResolveUnderRoot(root(), outside);
    EXPECT_FALSE(path.ok()) << outside;
    EXPECT_EQ(path.status().code(), StatusCode::kPermissionDenied) << outside;
  }
}

TEST_F(DataRootTest, MissingFilesAndDirectories) {
  EXPECT_EQ(ResolveUnderRoot(root(), "parts/none.step").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(ResolveUnderRoot(root(), "parts").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ResolveUnderRoot(root(), "").status().code(), StatusCode::kInvalidArgument);
}

TEST_F(DataRootTest, TokenFile) {
  const fs::path file = base_ / "token";
  std::ofstream(file) << "  s3cret-token\n";
  Result<std::string> token = ReadTokenFile(file.string());
  ASSERT_TRUE(token.ok());
  EXPECT_EQ(*token, "s3cret-token");
  std::ofstream(base_ / "empty") << "\n";
  EXPECT_EQ(ReadTokenFile((base_ / "empty").string()).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(ReadTokenFile((base_ / "none").string()).status().code(), StatusCode::kIoError);
}

TEST(BearerTokenTest, OnlyTheExactHeaderMatches) {
  EXPECT_TRUE(BearerTokenMatches("Bearer abc123", "abc123"));
  EXPECT_FALSE(BearerTokenMatches("Bearer abc124", "abc123"));
  EXPECT_FALSE(BearerTokenMatches("Bearer abc1234", "abc123"));
  EXPECT_FALSE(BearerTokenMatches("abc123", "abc123"));
  EXPECT_FALSE(BearerTokenMatches("", "abc123"));
  EXPECT_FALSE(BearerTokenMatches("Bearer ", ""));
}

TEST(Sha256Test, KnownVectors) {
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_TRUE(IsSha256Hex(Sha256Hex("abc")));
  EXPECT_FALSE(IsSha256Hex("BA7816BF8F01CFEA414140DE5DAE2223B00361A396177A9CB410FF61F20015AD"));
  EXPECT_FALSE(IsSha256Hex("abc"));
}

}  // namespace
}  // namespace rdmesh::server
