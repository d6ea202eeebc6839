// OpenStreetMap XML (core/osm readOsm, libosmium's XML parser). Input: an .osm file. Properties:
// only OsmError escapes; every way kept is drivable, has >= 2 nodes, and all its nodes are known.
#include "core/osm/osm_data.h"
#include "fuzz/fuzz_util.h"

#ifndef LANEMAP_FUZZ_OSM_SUFFIX
#define LANEMAP_FUZZ_OSM_SUFFIX ".osm"
#endif

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lanemap::osm;
  const std::string path = lanemap::fuzz::scratchFile(data, size, "osm", LANEMAP_FUZZ_OSM_SUFFIX);
  try {
    const OsmData d = readOsm(path);
    FUZZ_CHECK(!d.ways.empty());
    for (const Way& w : d.ways) {
      FUZZ_CHECK(isDrivableWay(w.tags));
      FUZZ_CHECK(w.nodes.size() >= 2);
      for (int64_t n : w.nodes) {
        const auto it = d.nodes.find(n);
        FUZZ_CHECK(it != d.nodes.end());
        FUZZ_CHECK(std::isfinite(it->second.lat) && std::isfinite(it->second.lon));
      }
    }
  } catch (const OsmError&) {
  }
  return 0;
}
