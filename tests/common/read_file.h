// The tests' one way to read a whole file: its bytes as they are on disk (binary), or an empty
// string when it cannot be opened (a test that needs the file asserts on what it reads; a test that
// polls for a file a child process writes reads "" until it is there).
#pragma once

#include <fstream>
#include <iterator>
#include <string>

namespace lanemap::testing {

inline std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace lanemap::testing
