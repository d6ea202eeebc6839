// Reading a whole file into memory in one read: the BEV grids (megabytes each), the Lanelet2 maps
// and their sidecars (a city's truth is some 150 MB), the checks' small files.
#pragma once

#include <optional>
#include <string>

namespace lanemap::io {

// The file's bytes, read in one go when its size is known (a regular file), else streamed (a pipe,
// /proc). std::nullopt when it cannot be opened or read, or is a folder.
std::optional<std::string> readFile(const std::string& path);

}  // namespace lanemap::io
