// Map evaluation (see evaluate.h for every definition): prepares both maps (chaining.cc), matches
// their lanes and scores pairs, graph and roads through the matching (matching.cc), the Chamfer AP
// (chamfer_ap.cc) and the regulatory elements (regulatory.cc); the report is in report.cc.
#include "core/eval/evaluate.h"
#include "core/eval/evaluate_internal.h"
#include "core/io/lanelet2.h"
#include "core/osm/coordinate_guard.h"

#include <osmium/io/reader.hpp>
#include <osmium/io/xml_input.hpp>
#include <osmium/osm/node.hpp>

#include <cstdlib>
#include <limits>
#include <stdexcept>

namespace lanemap::eval {

double Ratio::value() const {
  return total == 0 ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(hits) / static_cast<double>(total);
}

using Eigen::Vector2d;
using internal::Prepared;

EvalReport evaluate(const map::LaneMap& truth_map, const map::LaneMap& built_map, const EvalOptions& o) {
  const Prepared truth = internal::prepareMap(truth_map, o);
  const Prepared built = internal::prepareMap(built_map, o);
  EvalReport r;
  for (const auto& l : truth.lanes) r.truth_lanes.push_back(l.info);
  for (const auto& l : built.lanes) r.built_lanes.push_back(l.info);
  r.truth_intersection_lanelets = truth.intersection_lanelets;
  r.built_intersection_lanelets = built.intersection_lanelets;
  r.repaired_polygons = truth.repaired + built.repaired;

  const std::vector<int> match_of_built = internal::matchLanes(truth, built, o, r);
  internal::scorePairs(truth, built, match_of_built, o, r);
  internal::scoreGraph(truth, built, match_of_built, r);
  internal::scoreChamferAp(truth, built, o, r);
  internal::scoreRoads(truth, built, r);
  r.regulatory = scoreRegulatory(truth_map, built_map, o.regulatory);
  return r;
}

geo::LatLonAlt lanelet2Origin(const std::string& path) {
  // lanemap's files: the writer's origin, from the map's sidecar (core/io/lanelet2.h).
  if (const auto o = io::lanelet2WriterOrigin(path)) return {o->lat, o->lon, 0.0};
  osm::refuseExponentCoordinate<io::Lanelet2Error>(path, "cannot read Lanelet2 map '" + path + "'");  // libosmium overflows on it
  osmium::io::Reader reader(path, osmium::osm_entity_bits::node);
  while (osmium::memory::Buffer buffer = reader.read()) {
    for (const auto& node : buffer.select<osmium::Node>()) {
      if (!node.location().valid()) continue;
      const double lat = node.location().lat(), lon = node.location().lon();
      const char* lx_tag = node.tags()["local_x"];
      const char* ly_tag = node.tags()["local_y"];
      const std::string lx = lx_tag ? lx_tag : "", ly = ly_tag ? ly_tag : "";
      reader.close();
      geo::LatLonAlt o{lat, lon, 0.0};
      if (lx.empty() || ly.empty()) return o;
      char* ex = nullptr;
      char* ey = nullptr;
      const Vector2d target(std::strtod(lx.c_str(), &ex), std::strtod(ly.c_str(), &ey));
      if (*ex != '\0' || *ey != '\0' || !target.allFinite()) return o;
      // The origin whose ENU frame puts this node at (local_x, local_y): a few fixed-point steps.
      for (int it = 0; it < 5; ++it) {
        const geo::LocalFrame f(o);
        const Vector2d p = f.toEnu(lat, lon, 0.0).head<2>();
        const Vector2d err = p - target;
        if (err.norm() < 1e-4) break;
        o = f.toWgs84(Eigen::Vector3d(err.x(), err.y(), 0.0));
        o.alt = 0.0;
      }
      return o;
    }
  }
  reader.close();
  throw std::runtime_error("no node with a location in '" + path + "'");
}

}  // namespace lanemap::eval
