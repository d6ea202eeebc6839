#include "core/eval/regulatory.h"
#include "core/geo/polyline.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <tuple>
#include <unordered_map>

namespace lanemap::eval {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double ratio(size_t a, size_t b) { return b == 0 ? kNaN : static_cast<double>(a) / static_cast<double>(b); }

// One-to-one greedy matching of n_truth against n_built items by distance(i, j), nearest pairs
// first, within max_m.
template <typename Distance>
MatchScore matchNearest(size_t n_truth, size_t n_built, Distance distance, double max_m,
                        std::vector<std::pair<size_t, size_t>>* pairs = nullptr) {
  MatchScore s;
  s.truth = n_truth;
  s.built = n_built;
  std::vector<std::tuple<double, size_t, size_t>> cand;
  for (size_t i = 0; i < n_truth; ++i) {
    for (size_t j = 0; j < n_built; ++j) {
      const double d = distance(i, j);
      if (d < max_m) cand.emplace_back(d, i, j);
    }
  }
  std::sort(cand.begin(), cand.end());
  std::vector<bool> t_used(n_truth), b_used(n_built);
  for (const auto& [d, i, j] : cand) {
    if (t_used[i] || b_used[j]) continue;
    t_used[i] = b_used[j] = true;
    ++s.matched;
    s.error_sum_m += d;
    if (pairs) pairs->emplace_back(i, j);
  }
  return s;
}

std::vector<const map::LineString*> stopLinesOf(const map::LaneMap& m) {
  std::vector<const map::LineString*> s;
  for (const auto& l : m.lines) {
    if (l.type == map::LineType::kStopLine && l.points.size() >= 2) s.push_back(&l);
  }
  return s;
}

std::vector<Eigen::Vector2d> crosswalkCentres(const map::LaneMap& m) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& c : m.crosswalks) {
    if (c.left.empty() || c.right.empty()) continue;
    out.push_back(0.25 * (c.left.front() + c.left.back() + c.right.front() + c.right.back()).head<2>());
  }
  return out;
}

// The rule at a stop line: the kind of the element with that ref line; nullopt: none.
std::optional<map::RegulatoryKind> ruleAt(const map::LaneMap& m, int64_t stop_line) {
  for (const auto& r : m.regulatory_elements) {
    if (r.stop_line_id == stop_line) return r.kind;
  }
  return std::nullopt;
}

// Lines shared by two lanelets of one direction, and whether they permit a lane change.
std::vector<std::pair<const map::LineString*, bool>> sharedLines(const map::LaneMap& m) {
  std::unordered_map<int64_t, int> as_left, as_right;
  for (const auto& ll : m.lanelets) {
    ++as_left[ll.left_id];
    ++as_right[ll.right_id];
  }
  std::vector<std::pair<const map::LineString*, bool>> out;
  for (const auto& l : m.lines) {
    if (l.type == map::LineType::kStopLine || l.points.size() < 2) continue;
    if (as_left.count(l.id) && as_right.count(l.id)) out.emplace_back(&l, l.type == map::LineType::kDashed);
  }
  return out;
}

// The point halfway along a polyline.
Eigen::Vector2d midpointOf(const std::vector<Eigen::Vector3d>& pl) {
  const double total = geo::polylineLengthXy(pl);
  double s = 0.0;
  for (size_t i = 1; i < pl.size(); ++i) {
    const double seg = (pl[i] - pl[i - 1]).head<2>().norm();
    if (s + seg >= total / 2.0 && seg > 0.0) {
      const double t = (total / 2.0 - s) / seg;
      return (pl[i - 1] + t * (pl[i] - pl[i - 1])).head<2>();
    }
    s += seg;
  }
  return pl.front().head<2>();
}

}  // namespace

double MatchScore::precision() const { return ratio(matched, built); }
double MatchScore::recall() const { return ratio(matched, truth); }
double MatchScore::error_m() const { return matched == 0 ? kNaN : error_sum_m / static_cast<double>(matched); }
double RegulatoryScores::ruleAccuracy() const { return ratio(rules_agreeing, rules_compared); }
double RegulatoryScores::laneChangeAccuracy() const { return ratio(lane_change_correct, lane_change_matched); }
double RegulatoryScores::laneChangeCoverage() const { return ratio(lane_change_matched, lane_change_truth); }

RegulatoryScores scoreRegulatory(const map::LaneMap& truth, const map::LaneMap& built, const RegulatoryOptions& o) {
  RegulatoryScores s;
  const auto ts = stopLinesOf(truth), bs = stopLinesOf(built);
  std::vector<std::pair<size_t, size_t>> pairs;
  s.stop_lines = matchNearest(
      ts.size(), bs.size(),
      [&](size_t i, size_t j) {
        const Eigen::Vector2d mid = 0.5 * (bs[j]->points.front() + bs[j]->points.back()).head<2>();
        return geo::distanceToPolylineXy(ts[i]->points, mid);
      },
      o.stop_line_match_m, &pairs);
  for (const auto& [i, j] : pairs) {
    ++s.rules_compared;
    s.rules_agreeing += ruleAt(truth, ts[i]->id) == ruleAt(built, bs[j]->id);
  }
  const auto tc = crosswalkCentres(truth), bc = crosswalkCentres(built);
  s.crosswalks = matchNearest(
      tc.size(), bc.size(), [&](size_t i, size_t j) { return (tc[i] - bc[j]).norm(); }, o.crosswalk_match_m);

  const auto t_shared = sharedLines(truth), b_shared = sharedLines(built);
  s.lane_change_truth = t_shared.size();
  for (const auto& [line, yes] : t_shared) {
    const Eigen::Vector2d mid = midpointOf(line->points);
    double best = o.lane_change_match_m;
    std::optional<bool> found;
    for (const auto& [bline, byes] : b_shared) {
      const double d = geo::distanceToPolylineXy(bline->points, mid);
      if (d < best) {
        best = d;
        found = byes;
      }
    }
    if (!found) continue;
    ++s.lane_change_matched;
    s.lane_change_correct += *found == yes;
  }
  return s;
}

nlohmann::json toJson(const RegulatoryScores& s) {
  const auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  const auto match = [&](const MatchScore& m) {
    return nlohmann::json{{"truth", m.truth},        {"built", m.built},         {"matched", m.matched},
                          {"precision", num(m.precision())}, {"recall", num(m.recall())}, {"error_m", num(m.error_m())}};
  };
  return {{"stop_lines", match(s.stop_lines)},
          {"crosswalks", match(s.crosswalks)},
          {"rules", {{"compared", s.rules_compared}, {"agreeing", s.rules_agreeing}, {"accuracy", num(s.ruleAccuracy())}}},
          {"lane_change",
           {{"truth", s.lane_change_truth}, {"matched", s.lane_change_matched}, {"correct", s.lane_change_correct},
            {"accuracy", num(s.laneChangeAccuracy())}, {"coverage", num(s.laneChangeCoverage())}}}};
}

}  // namespace lanemap::eval
