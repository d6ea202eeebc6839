#include "core/mapping/lane_confidence.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lanemap::mapping {

namespace {

// The share of a lane's line evidence that lies on its bounds (lane_confidence.h, `agreement`).
std::optional<double> lineAgreement(const bev::BevGrid& grid, const lanes::ExplorationResult& r, const lanes::Lane& l) {
  if (!r.frame) return std::nullopt;
  const double step = grid.resolution();
  const int half = static_cast<int>(std::round(kAgreementWindowM / step));
  double near = 0.0, all = 0.0;
  for (const auto* b : {&l.left, &l.right}) {
    std::vector<bev::Layer> layers;
    if (b->type == map::LineType::kDashed || b->type == map::LineType::kSolid) layers = {bev::Layer::kDashedLine, bev::Layer::kSolidLine};
    else if (b->type == map::LineType::kCurb) layers = {bev::Layer::kCurb};
    else continue;
    for (size_t k = 0; k < b->d.size() && k < l.waypoint_s.size(); ++k) {
      const Eigen::Vector2d p = r.frame->toEnu(l.waypoint_s[k], b->d[k]), n = r.frame->normal(l.waypoint_s[k]);
      for (int j = -half; j <= half; ++j) {
        double c = 0.0;
        const Eigen::Vector2d q = p + j * step * n;
        for (bev::Layer layer : layers) c += grid.count(q, layer);
        all += c;
        if (std::abs(j * step) <= kAgreementCoreM + 1e-9) near += c;
      }
    }
  }
  if (all <= 0.0) return std::nullopt;
  return near / all;
}

}  // namespace

std::vector<LaneConfidence> laneConfidences(const bev::BevGrid& grid, const lanes::ExplorationResult& r,
                                            const lanes::ExplorerOptions& o) {
  std::vector<LaneConfidence> out(r.lanes.size());
  double best_density = 0.0;
  std::vector<double> density(r.lanes.size(), 0.0);
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    const auto& l = r.lanes[i];
    density[i] = static_cast<double>(l.particle_samples) / std::max(1.0, l.s_end - l.s_begin);
    best_density = std::max(best_density, density[i]);
  }
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    const auto& l = r.lanes[i];
    LaneConfidence& c = out[i];
    size_t seen = 0, found = 0, probes = 0;
    for (size_t k = 0; k < l.waypoints.size(); ++k) {
      if (grid.count(l.waypoints[k], bev::Layer::kDrivable) > 0) ++seen;
      const double d = k < l.waypoint_s.size() ? l.centre.d(l.waypoint_s[k]) : 0.0;
      for (const auto* b : {&l.left, &l.right}) {
        if (k >= b->d.size()) continue;
        ++probes;
        if (std::abs(std::abs(b->d[k] - d) - o.default_half_width_m) > 1e-6) ++found;
      }
    }
    c.observed = l.waypoints.empty() ? 0.0 : static_cast<double>(seen) / l.waypoints.size();
    c.bounds = probes == 0 ? 0.0 : static_cast<double>(found) / probes;
    c.support = best_density > 0.0 ? density[i] / best_density : 0.0;
    c.repeat = 1.0 - std::pow(0.5, 1.0 + grid.agreement());
    c.agreement = lineAgreement(grid, r, l);
  }
  return out;
}

void setConfidence(map::LaneMap& lanes, const lanes::ExplorationResult& r, const std::vector<LaneConfidence>& confidence) {
  if (!r.frame) return;
  for (auto& ll : lanes.lanelets) {
    if (ll.kind != map::LaneletKind::kRoad || ll.centre.empty()) continue;
    const Eigen::Vector2d sd = r.frame->toFrenet(ll.centre[ll.centre.size() / 2].head<2>());
    double best = std::numeric_limits<double>::infinity();
    int lane = -1;
    for (size_t i = 0; i < r.lanes.size() && i < confidence.size(); ++i) {
      const auto& l = r.lanes[i];
      if (sd.x() < l.s_begin - 1.0 || sd.x() > l.s_end + 1.0) continue;
      const double e = std::abs(l.centre.d(std::clamp(sd.x(), l.s_begin, l.s_end)) - sd.y());
      if (e < best) {
        best = e;
        lane = static_cast<int>(i);
      }
    }
    if (lane >= 0) ll.confidence = std::clamp(confidence[static_cast<size_t>(lane)].value(), 0.0, 1.0);
  }
}

}  // namespace lanemap::mapping
