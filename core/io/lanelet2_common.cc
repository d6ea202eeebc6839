// What the Lanelet2 reader and writer share: the coordinate convention of lanemap's OSM files,
// the sidecar's name and its hash (see lanelet2.h for the conventions).

#include "core/io/lanelet2.h"
#include "core/io/lanelet2_internal.h"
#include "core/io/read_file.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>

namespace lanemap::io {

namespace lanelet2_internal {

uint64_t fnv1a64(std::string_view bytes) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string readAll(const std::string& path) { return readFile(path).value_or(std::string()); }

std::string sidecarHashOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char buf[128] = {};
  in.read(buf, sizeof(buf) - 1);
  static const std::regex re(R"re(^\{"osm_fnv1a64":"([0-9a-f]{16})")re");
  std::cmatch m;
  if (!std::regex_search(buf, m, re)) return {};
  return m[1].str();
}

}  // namespace lanelet2_internal

geo::LatLonAlt enuToLatLonEle(const geo::LocalFrame& frame, const Eigen::Vector3d& enu) {
  geo::LatLonAlt p = frame.toWgs84(enu);
  p.alt = frame.origin().alt + enu.z();
  return p;
}

Eigen::Vector3d latLonEleToEnu(const geo::LocalFrame& frame, double lat, double lon, double ele) {
  // Find the ellipsoidal height h at which the vertical through lat/lon has ENU z = target.
  // dz/dh = cos(angle between the two verticals) ~ 1, so a few fixed-point steps converge.
  const double target_z = ele - frame.origin().alt;
  double h = ele;
  Eigen::Vector3d p = frame.toEnu(lat, lon, h);
  for (int i = 0; i < 4 && std::abs(p.z() - target_z) > 1e-9; ++i) {
    h += target_z - p.z();
    p = frame.toEnu(lat, lon, h);
  }
  p.z() = target_z;
  return p;
}

std::string lanelet2SidecarPath(const std::string& osm_path) {
  const std::filesystem::path p(osm_path);
  if (p.extension() == ".osm") return (p.parent_path() / (p.stem().string() + ".lanemap.json")).string();
  return osm_path + ".lanemap.json";
}

}  // namespace lanemap::io
