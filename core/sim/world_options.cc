// WorldOptions from YAML (config/sim_world.yaml) and the lane tag rules: lanes per direction and
// class default lane widths of an OSM way.
#include "core/sim/world_builder.h"

#include "core/config/yaml_reader.h"
#include "core/osm/turn_lanes.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace lanemap::sim {

namespace {

int parseCount(const std::string& v) {
  if (v.empty()) return -1;
  char* end = nullptr;
  const long n = std::strtol(v.c_str(), &end, 10);
  if (end == v.c_str() || n <= 0 || n > 12) return -1;
  return static_cast<int>(n);
}

std::string tag(const osm::Tags& t, const std::string& k) {
  const auto it = t.find(k);
  return it == t.end() ? std::string() : it->second;
}

// Lanes per direction by road class when the way has no lane tags.
int classDefaultPerDirection(const std::string& highway, bool oneway) {
  if (highway == "motorway" || highway == "trunk" || highway == "primary") return 2;
  if (highway == "secondary") return oneway ? 2 : 1;
  return 1;  // tertiary, residential, unclassified, service, links, living streets, ...
}

}  // namespace

WorldOptions WorldOptions::fromYaml(const YAML::Node& node) {
  try {
    const config::YamlReader r(node);
    WorldOptions o = fromYaml(r);
    r.finish();
    return o;
  } catch (const config::ConfigError& e) {
    throw WorldConfigError(std::string("world config: ") + e.what());
  }
}

WorldOptions WorldOptions::fromYaml(const config::YamlReader& r) {
  WorldOptions o;
  r.read("seed", o.seed);
  r.read("flat", o.flat);
  r.read("right_hand_traffic", o.right_hand_traffic);
  r.read("osm_layers", o.osm_layers);
  const auto lanes = r.section("lanes");
  lanes.read("default_width_m", o.default_lane_width_m);
  lanes.read("width_jitter_m", o.lane_width_jitter_m);
  lanes.read("width_min_m", o.lane_width_min_m);
  lanes.read("width_max_m", o.lane_width_max_m);
  const auto irr = r.section("irregularities");
  irr.read("parking_lane", o.p_parking_lane);
  irr.read("bike_lane", o.p_bike_lane);
  irr.read("bus_bay", o.p_bus_bay);
  irr.read("turn_pocket", o.p_turn_pocket);
  irr.read("faded_marking", o.p_faded_marking);
  irr.read("missing_marking", o.p_missing_marking);
  irr.read("crosswalk", o.p_crosswalk);
  irr.read("stop_line", o.p_stop_line);
  irr.read("sidewalk", o.p_sidewalk);
  irr.read("parked_car_occupancy", o.parked_car_occupancy);
  irr.read("building", o.p_building);
  const auto surf = r.section("surface");
  surf.read("crown_slope", o.crown_slope);
  surf.read("max_grade", o.max_grade);
  surf.read("bump_amplitude_m", o.bump_amplitude_m);
  surf.read("curb_height_m", o.curb_height_m);
  const auto raster = r.section("raster");
  raster.read("tile_size_m", o.tile_size_m);
  raster.read("tile_resolution_m", o.tile_resolution_m);
  raster.read("height_resolution_m", o.height_resolution_m);
  raster.read("tile_cache_size", o.tile_cache_size);
  try {
    o.validate();
  } catch (const WorldConfigError& e) {
    r.failHere(e.what());
  }
  return o;
}

WorldOptions WorldOptions::fromYamlFile(const std::string& path) {
  try {
    const auto r = config::YamlReader::loadFile(path);
    WorldOptions o = fromYaml(r);
    r.finish();
    return o;
  } catch (const config::ConfigError& e) {
    throw WorldConfigError(std::string("world config: ") + e.what());
  }
}

void WorldOptions::validate() const {
  auto prob = [](const char* name, double p) {
    if (!(p >= 0.0 && p <= 1.0)) {
      std::ostringstream m;
      m << "world config: " << name << " = " << p << " is not a probability in [0, 1]";
      throw WorldConfigError(m.str());
    }
  };
  prob("parking_lane", p_parking_lane);
  prob("bike_lane", p_bike_lane);
  prob("bus_bay", p_bus_bay);
  prob("turn_pocket", p_turn_pocket);
  prob("faded_marking", p_faded_marking);
  prob("missing_marking", p_missing_marking);
  prob("crosswalk", p_crosswalk);
  prob("stop_line", p_stop_line);
  prob("sidewalk", p_sidewalk);
  prob("parked_car_occupancy", parked_car_occupancy);
  prob("building", p_building);
  auto range = [](const char* name, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi)) {
      std::ostringstream m;
      m << "world config: " << name << " = " << v << " is outside [" << lo << ", " << hi << "]";
      throw WorldConfigError(m.str());
    }
  };
  range("lanes.width_min_m", lane_width_min_m, 2.0, 5.0);
  range("lanes.width_max_m", lane_width_max_m, lane_width_min_m, 5.0);
  range("lanes.width_jitter_m", lane_width_jitter_m, 0.0, 1.0);
  range("lanes.default_width_m", default_lane_width_m, 0.0, 5.0);
  range("surface.crown_slope", crown_slope, 0.0, 0.06);
  range("surface.max_grade", max_grade, 0.0, 0.10);
  range("surface.bump_amplitude_m", bump_amplitude_m, 0.0, 0.1);
  range("surface.curb_height_m", curb_height_m, 0.0, 0.3);
  range("raster.tile_size_m", tile_size_m, 8.0, 512.0);
  range("raster.tile_resolution_m", tile_resolution_m, 0.01, 0.5);
  range("raster.height_resolution_m", height_resolution_m, tile_resolution_m, 2.0);
  range("raster.tile_cache_size", tile_cache_size, 1, 4096);
  if (tile_size_m / tile_resolution_m > 8192) {
    throw WorldConfigError("world config: raster.tile_size_m / tile_resolution_m exceeds 8192 pixels");
  }
}

LaneCounts laneCountsFor(const osm::Tags& tags, bool oneway) {
  const std::string highway = tag(tags, "highway");
  const int lanes = parseCount(tag(tags, "lanes"));
  int fwd = parseCount(tag(tags, "lanes:forward"));
  int bwd = parseCount(tag(tags, "lanes:backward"));
  LaneCounts c;
  if (oneway) {
    // All lanes go one way; lanes, else turn:lanes (its entries are the lanes), else the class.
    int n = lanes;
    if (n < 0) n = osm::turnLaneCount(tag(tags, "turn:lanes"));
    // oneway=-1 roads may tag their lanes as backward.
    if (n < 0) n = std::max(fwd, bwd);
    if (n < 0) n = classDefaultPerDirection(highway, true);
    c.forward = n;
    c.backward = 0;
    return c;
  }
  if (fwd < 0) fwd = osm::turnLaneCount(tag(tags, "turn:lanes:forward"));
  if (bwd < 0) bwd = osm::turnLaneCount(tag(tags, "turn:lanes:backward"));
  if (lanes > 0) {
    if (fwd < 0 && bwd > 0) fwd = lanes - bwd;
    if (bwd < 0 && fwd > 0) bwd = lanes - fwd;
    if (fwd < 0 && bwd < 0) {
      fwd = (lanes + 1) / 2;  // an odd count gives the extra lane to forward
      bwd = lanes / 2;
    }
  }
  const int def = classDefaultPerDirection(highway, false);
  c.forward = fwd > 0 ? fwd : def;
  c.backward = bwd > 0 ? bwd : def;  // a two-way road has at least one lane each way
  return c;
}

double defaultLaneWidth(const std::string& highway) {
  const std::string h = highway.size() > 5 && highway.substr(highway.size() - 5) == "_link"
                            ? highway.substr(0, highway.size() - 5)
                            : highway;
  if (h == "motorway" || h == "trunk") return 3.6;
  if (h == "primary") return 3.5;
  if (h == "secondary") return 3.35;
  if (h == "tertiary") return 3.25;
  if (h == "residential" || h == "unclassified") return 3.1;
  return 3.0;  // service, living_street, road, ...
}

}  // namespace lanemap::sim
