#include "core/io/read_file.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace lanemap::io {

std::optional<std::string> readFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || fs::is_directory(st)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  const uintmax_t size = fs::is_regular_file(st) ? fs::file_size(path, ec) : 0;
  if (!ec && size > 0) {  // a file of known size: one read
    std::string out(static_cast<size_t>(size), '\0');
    if (in.read(out.data(), static_cast<std::streamsize>(size)) && in.peek() == std::char_traits<char>::eof())
      return out;
    in.clear();  // it changed size while read: stream it from the start
    in.seekg(0);
  }
  std::string out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return std::nullopt;
  return out;
}

}  // namespace lanemap::io
