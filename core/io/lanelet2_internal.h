// Internals shared by the Lanelet2 reader (lanelet2_reader.cc), writer (lanelet2_writer.cc) and
// orientation check (lanelet2_orientation.cc). Not part of the public interface: include
// core/io/lanelet2.h.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace lanemap::io::lanelet2_internal {

constexpr int kSidecarVersion = 1;

// Lanelet2's geometry::align(left, right), which its OSM loader applies to every lanelet's bounds
// as they are stored: the left bound is inverted unless the middle point of the right bound lies
// on its right, then the right bound unless the middle point of the (aligned) left lies on its
// left. The lanelet's driving direction is the direction of the aligned bounds.
struct Alignment {
  bool invert_left = false, invert_right = false;
};
Alignment lanelet2Alignment(const std::vector<Eigen::Vector3d>& left, const std::vector<Eigen::Vector3d>& right);

// The sidecar's binding to its OSM file: the FNV-1a hash of the file's bytes, as 16 hex digits.
uint64_t fnv1a64(std::string_view bytes);
std::string hex64(uint64_t v);
std::string readAll(const std::string& path);
// The hash a sidecar names in its first bytes (empty: none).
std::string sidecarHashOf(const std::string& path);

}  // namespace lanemap::io::lanelet2_internal
