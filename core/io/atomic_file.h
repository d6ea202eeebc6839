// Atomic file writing for every writer of lanemap: the content goes to `<path>.tmp.<pid>` in the
// same folder, is flushed to disk (fsync), and is renamed over `path`. A reader (or a crash) sees
// either the old complete file or the new complete file, never a half-written map.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace lanemap::io {

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes `content` to `path` atomically (temporary file in the same folder, fsync, rename, fsync
// of the folder). The folder must exist. Throws IoError naming the path on any failure; the
// temporary file is removed then.
void writeFileAtomically(const std::string& path, std::string_view content);

// Binary variant for encoded images and the like.
void writeFileAtomically(const std::string& path, const void* data, size_t size);

}  // namespace lanemap::io
