// The width and height a JPEG or PNG says it has, read from its header without decoding it, so a
// message whose image lies about its size (a 65535 x 65535 JPEG in a 2 kB message) is rejected
// before cv::imdecode allocates for it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

namespace lanemap::io {

struct ImageSize {
  int width = 0, height = 0;
};

// From the first SOFn marker of a JPEG (baseline, progressive, lossless ...); nullopt when the data
// does not start with SOI or no SOF marker is found within the bytes given.
std::optional<ImageSize> jpegSize(const uint8_t* data, std::size_t size);
// From a PNG's IHDR chunk (bytes 16..23); nullopt when the signature or IHDR is missing.
std::optional<ImageSize> pngSize(const uint8_t* data, std::size_t size);

}  // namespace lanemap::io
