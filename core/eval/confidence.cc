#include "core/eval/confidence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

namespace lanemap::eval {

ConfidenceReport confidenceBands(const EvalReport& report, const map::LaneMap& built, const std::vector<double>& edges) {
  ConfidenceReport out;
  std::vector<double> e{0.0};
  for (double x : edges) {
    if (x > e.back() && x < 1.0) e.push_back(x);
  }
  e.push_back(1.0);
  for (size_t i = 0; i + 1 < e.size(); ++i) out.bands.push_back(ConfidenceBand{e[i], e[i + 1], {}, {}});
  const size_t truth = report.truth_lanes.size();
  for (auto& b : out.bands) b.recall.total = truth;
  // Each built lane's band (-1: unrated).
  std::vector<int> band(report.built_lanes.size(), -1);
  for (size_t i = 0; i < report.built_lanes.size(); ++i) {
    double sum = 0.0;
    int n = 0;
    for (int64_t id : report.built_lanes[i].lanelets) {
      const auto* ll = built.lanelet(id);
      if (ll && ll->confidence) {
        sum += *ll->confidence;
        ++n;
      }
    }
    if (n == 0) {
      ++out.unrated;
      continue;
    }
    const double c = std::clamp(sum / n, 0.0, 1.0);
    int k = static_cast<int>(out.bands.size()) - 1;
    while (k > 0 && c < out.bands[static_cast<size_t>(k)].lo) --k;
    band[i] = k;
    ++out.bands[static_cast<size_t>(k)].precision.total;
  }
  for (const auto& m : report.matches) {
    if (!m.detected || m.built < 0 || static_cast<size_t>(m.built) >= band.size() || band[static_cast<size_t>(m.built)] < 0) continue;
    auto& b = out.bands[static_cast<size_t>(band[static_cast<size_t>(m.built)])];
    ++b.precision.hits;
    ++b.recall.hits;
  }
  return out;
}

nlohmann::json toJson(const ConfidenceReport& c) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json bands = nlohmann::json::array();
  for (const auto& b : c.bands) {
    bands.push_back({{"lo", b.lo}, {"hi", b.hi}, {"built", b.precision.total}, {"detected", b.precision.hits},
                     {"precision", num(b.precision.value())}, {"recall", num(b.recall.value())}});
  }
  return {{"bands", bands}, {"unrated", c.unrated}};
}

std::string summary(const ConfidenceReport& c) {
  std::string out;
  char line[160];
  for (size_t i = 0; i < c.bands.size(); ++i) {
    const auto& b = c.bands[i];
    std::snprintf(line, sizeof(line), "lanes with confidence in [%.2f, %.2f%s: %zu built, P %.3f, R %.3f\n", b.lo, b.hi,
                  i + 1 == c.bands.size() ? "]" : ")", b.precision.total, b.precision.value(), b.recall.value());
    out += line;
  }
  if (c.unrated) out += std::to_string(c.unrated) + " built lanes without a confidence\n";
  return out;
}

}  // namespace lanemap::eval
