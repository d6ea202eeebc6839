// Lanelet2 OSM (core/io/lanelet2 readLanelet2File). Input: a Lanelet2 .osm file (seeds: slices of
// the Karlsruhe mapping example). Properties: only Lanelet2Error (an IoError) escapes; every
// lanelet's bounds exist in the map; all coordinates are finite; what was read writes back
// (toLanelet2Xml) or is refused with a Lanelet2Error, never a crash.
#include "core/io/lanelet2.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lanemap;
  const std::string path = fuzz::scratchFile(data, size, "lanelet2", ".osm");
  io::Lanelet2File file;
  try {
    file = io::readLanelet2File(path, 49.005, 8.42);
  } catch (const io::Lanelet2Error&) {
    return 0;
  }
  const map::LaneMap& m = file.map;
  for (const map::LineString& l : m.lines) {
    for (const auto& p : l.points) FUZZ_CHECK(p.allFinite());
  }
  for (const map::Lanelet& ll : m.lanelets) {
    FUZZ_CHECK(m.line(ll.left_id) != nullptr);
    FUZZ_CHECK(m.line(ll.right_id) != nullptr);
    for (const auto& p : ll.centre) FUZZ_CHECK(p.allFinite());
  }
  try {
    const std::string xml = io::toLanelet2Xml(m);
    FUZZ_CHECK(!xml.empty());
  } catch (const io::Lanelet2Error&) {
  }
  return 0;
}
