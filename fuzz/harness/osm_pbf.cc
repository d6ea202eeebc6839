// OpenStreetMap PBF (core/osm readOsm, libosmium's PBF decoder: zlib blobs, string tables,
// delta-coded ids). The osm_xml harness with a .osm.pbf file name.
#define LANEMAP_FUZZ_OSM_SUFFIX ".osm.pbf"
#include "osm_xml.cc"
