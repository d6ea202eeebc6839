// Tests of atomic file writing (core/io/atomic_file.h): content lands completely, a reader that
// opened the old file keeps reading the old content (the file is replaced, not rewritten in
// place), no temporary file is left behind, failures name the path. And reading a whole file
// (core/io/read_file.h).
#include "core/io/atomic_file.h"
#include "core/io/read_file.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace lanemap::io {
namespace {

// The file's scratch folder (tests/common/temp_dir.h), made on first use and removed at exit.
const lanemap::testing::TempDir& scratch() {
  static const lanemap::testing::TempDir dir("io-atomic");
  return dir;
}
std::filesystem::path tempDir() { return scratch().path(); }

std::string readAll(std::istream& in) {
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ReadFile, GivesEveryByteOfAFileOfKnownSize) {
  std::string bytes(3 * 1024 * 1024 + 7, '\0');  // binary, NULs included, over a buffer's size
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>((i * 131u) % 251u);
  const lanemap::testing::TempDir dir("io-read");  // its own: AtomicFile tests count their folder's files
  const std::string path = dir.str("blob.bin");
  writeFileAtomically(path, bytes);
  const std::optional<std::string> got = readFile(path);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->size(), bytes.size());
  EXPECT_TRUE(*got == bytes);
  writeFileAtomically(path, std::string());
  ASSERT_TRUE(readFile(path).has_value());
  EXPECT_TRUE(readFile(path)->empty());
}

TEST(ReadFile, StreamsAFileWithoutAKnownSize) {
  // /proc files report size 0: the content is streamed instead.
  const std::optional<std::string> got = readFile("/proc/self/status");
  ASSERT_TRUE(got.has_value());
  EXPECT_NE(got->find("Pid:"), std::string::npos);
}

TEST(ReadFile, MissingFileOrFolderIsNullopt) {
  const lanemap::testing::TempDir dir("io-read");
  EXPECT_FALSE(readFile(dir.str("no-such-file")).has_value());
  EXPECT_FALSE(readFile(dir.path().string()).has_value());  // a folder has no content to read
}

TEST(AtomicFile, ReplacesContentAndLeavesNoTemporaryFile) {
  std::filesystem::create_directories(tempDir());
  const std::string path = (tempDir() / "map.osm").string();
  const std::string first(100000, 'a');
  writeFileAtomically(path, first);
  std::ifstream old_reader(path);  // opened before the replacement
  ASSERT_TRUE(old_reader.good());

  const std::string second = "second version\n";
  writeFileAtomically(path, second);
  std::ifstream new_reader(path);
  EXPECT_EQ(readAll(new_reader), second);
  // The old reader still sees the complete first version: the file was renamed over, not
  // truncated and rewritten.
  EXPECT_EQ(readAll(old_reader), first);

  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(tempDir())) {
    ++files;
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
  EXPECT_EQ(files, 1u);
}

TEST(AtomicFile, BinaryContent) {
  std::filesystem::create_directories(tempDir());
  const std::string path = (tempDir() / "bytes.bin").string();
  const unsigned char bytes[] = {0, 1, 2, 255, 0, 7};
  writeFileAtomically(path, bytes, sizeof(bytes));
  EXPECT_EQ(std::filesystem::file_size(path), sizeof(bytes));
  std::ifstream in(path, std::ios::binary);
  const std::string back = readAll(in);
  ASSERT_EQ(back.size(), sizeof(bytes));
  EXPECT_EQ(static_cast<unsigned char>(back[3]), 255);
}

TEST(AtomicFile, FailuresNameThePath) {
  const std::string path = (tempDir() / "no_such_folder" / "map.osm").string();
  try {
    writeFileAtomically(path, "x");
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_THROW(writeFileAtomically("", "x"), IoError);
  // Renaming onto a folder fails; the temporary file must be gone afterwards.
  std::filesystem::create_directories(tempDir() / "a_folder" / "inside");
  const std::string folder = (tempDir() / "a_folder").string();
  EXPECT_THROW(writeFileAtomically(folder, "x"), IoError);
  for (const auto& e : std::filesystem::directory_iterator(tempDir())) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
}

}  // namespace
}  // namespace lanemap::io
