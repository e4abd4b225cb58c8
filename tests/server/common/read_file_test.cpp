#include "common/read_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace rdmesh::server {
namespace {
namespace fs = std::filesystem;

TEST(ReadFileTest, ReadFileLimited) {
  const fs::path base =
      fs::temp_directory_path() / ("rdmesh_read_file_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string file = (base / "a.step").string();
  std::ofstream(file) << "ISO-10303-21;";
  Result<std::string> bytes = ReadFileLimited(file, 100);
  ASSERT_TRUE(bytes.ok());
  EXPECT_EQ(*bytes, "ISO-10303-21;");
  EXPECT_EQ(ReadFileLimited(file, 5).status().code(), StatusCode::kResourceExhausted);
  fs::remove_all(base);
}

}  // namespace
}  // namespace rdmesh::server
