// buildWorld: lays out the lane-level world on an OSM skeleton (the vocabulary and the parts:
// core/sim/world_build.h). This file: the order of the jobs.
#include "core/sim/world_builder.h"

#include "core/sim/world_build.h"

#include <algorithm>
#include <limits>
#include <string>

namespace lanemap::sim {

namespace world_build {

// A road's OSM level: its `layer` (an integer, clamped to -5..5), else 1 on a bridge and -1 in a
// tunnel (bridge=yes, viaduct, ...; tunnel=yes, building_passage, ...; "no" is none), else 0.
int osmLevel(const skeleton::AtomicRoad& road) {
  const auto tag = [&](const char* k) -> std::string {
    const auto it = road.tags.find(k);
    return it == road.tags.end() ? std::string() : it->second;
  };
  const std::string layer = tag("layer");
  if (!layer.empty()) {
    try {
      size_t used = 0;
      const int v = std::stoi(layer, &used);
      if (used == layer.size()) return std::clamp(v, -5, 5);
    } catch (const std::exception&) {
    }
  }
  const std::string bridge = tag("bridge"), tunnel = tag("tunnel");
  if (!bridge.empty() && bridge != "no") return 1;
  if (!tunnel.empty() && tunnel != "no") return -1;
  return 0;
}

std::unique_ptr<SimWorld::Impl> Builder::run() {
  if (sk_.roads().empty()) throw std::runtime_error("buildWorld: the skeleton has no road");
  const auto& origin = sk_.frame().origin();
  truth().origin_lat = origin.lat;
  truth().origin_lon = origin.lon;
  truth().origin_alt = origin.alt;
  makeTerrain();
  groupCrossSections();
  // Smoothing over about the road's half width: the lanes of a hairpin tighter than the road's
  // width still fold on its inner side (a known limit, see the Monaco test).
  for (auto& xs : xss_) xs.line = RefLine(xs.ref->polyline, 1.0, std::clamp(xs.halfWidth(), 3.0, 8.0));
  computeNodeInfo();
  // Paint levels: a road's OSM level; an intersection's, the lowest of its roads' (where a bridge
  // comes down to the roads at its end, the junction is on both levels: seen from the road below
  // it must not vanish with the bridge).
  for (auto& xs : xss_) {
    fill_level_ = o_.osm_layers ? osmLevel(*xs.ref) : 0;
    impl_->road_level[xs.ref->id] = fill_level_;
    if (xs.rev) impl_->road_level[xs.rev->id] = fill_level_;
    buildCrossSection(xs);
  }
  for (const auto& in : sk_.intersections()) {
    fill_level_ = std::numeric_limits<int>::max();
    for (const auto* ids : {&in.incoming, &in.outgoing}) {
      for (int64_t id : *ids) {
        if (const auto* r = sk_.road(id)) fill_level_ = std::min(fill_level_, o_.osm_layers ? osmLevel(*r) : 0);
      }
    }
    if (fill_level_ == std::numeric_limits<int>::max()) fill_level_ = 0;
    impl_->node_level[in.id] = fill_level_;
    buildIntersection(in);
  }
  fill_level_ = 0;
  shareOpposedIntersectionBounds();
  placeObstacles();
  for (auto& cw : truth().crosswalks) cw.id = nextId();
  fillStats();
  impl_->finalize();
  return std::move(impl_);
}

void Builder::fillStats() {
  WorldStats& st = impl_->stats;
  st.lines = truth().lines.size();
  st.turn_pockets = 0;
  double km = 0.0;
  for (const auto& xs : xss_) {
    for (int k = 0; k < 2; ++k) st.turn_pockets += xs.side[k].pocket ? 1 : 0;
  }
  for (const auto& l : truth().lanelets) {
    if (l.kind != LaneletKind::kRoad) continue;
    for (size_t i = 1; i < l.centre.size(); ++i) km += (l.centre[i] - l.centre[i - 1]).head<2>().norm();
  }
  st.driving_lane_km = km / 1000.0;
}

}  // namespace world_build

std::unique_ptr<SimWorld> buildWorld(const skeleton::Skeleton& skeleton, const WorldOptions& options,
                                     const std::vector<osm::Restriction>& restrictions) {
  options.validate();
  world_build::Builder b(skeleton, options, restrictions);
  return std::make_unique<SimWorld>(b.run());
}

}  // namespace lanemap::sim
