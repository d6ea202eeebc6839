// buildWorld: lays out the lane-level world on an OSM skeleton (the vocabulary and the parts:
// core/sim/world_build.h). This file: the order of the jobs.
#include "core/sim/world_builder.h"

#include "core/sim/world_build.h"

namespace lanemap::sim {

namespace world_build {

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
  for (auto& xs : xss_) buildCrossSection(xs);
  for (const auto& in : sk_.intersections()) buildIntersection(in);
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
