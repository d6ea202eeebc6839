#include "core/io/image_header.h"

namespace lanemap::io {

std::optional<ImageSize> jpegSize(const uint8_t* data, std::size_t size) {
  if (data == nullptr || size < 4 || data[0] != 0xFF || data[1] != 0xD8) return std::nullopt;
  std::size_t i = 2;
  while (i + 4 <= size) {
    if (data[i] != 0xFF) return std::nullopt;  // not at a marker: corrupt
    const uint8_t marker = data[i + 1];
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (marker == 0xD8 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length
      i += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) return std::nullopt;  // end of image / scan before SOF
    const std::size_t len = (static_cast<std::size_t>(data[i + 2]) << 8) | data[i + 3];
    if (len < 2) return std::nullopt;
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (len < 7 || i + 9 > size) return std::nullopt;
      ImageSize s;
      s.height = (data[i + 5] << 8) | data[i + 6];
      s.width = (data[i + 7] << 8) | data[i + 8];
      return s;
    }
    i += 2 + len;
  }
  return std::nullopt;
}

std::optional<ImageSize> pngSize(const uint8_t* data, std::size_t size) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (data == nullptr || size < 24) return std::nullopt;
  for (int k = 0; k < 8; ++k)
    if (data[k] != kSignature[k]) return std::nullopt;
  if (data[12] != 'I' || data[13] != 'H' || data[14] != 'D' || data[15] != 'R') return std::nullopt;
  auto be32 = [&](std::size_t o) {
    return (static_cast<uint32_t>(data[o]) << 24) | (static_cast<uint32_t>(data[o + 1]) << 16) |
           (static_cast<uint32_t>(data[o + 2]) << 8) | data[o + 3];
  };
  const uint32_t w = be32(16), h = be32(20);
  if (w == 0 || h == 0 || w > 0x7FFFFFFFu || h > 0x7FFFFFFFu) return std::nullopt;
  return ImageSize{static_cast<int>(w), static_cast<int>(h)};
}

}  // namespace lanemap::io
