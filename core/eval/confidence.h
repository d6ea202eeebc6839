// Lane precision and recall per confidence band (issue 14): whether the map's per-lane confidence
// (map::Lanelet::confidence, core/mapping/lane_confidence.h) means something — high-confidence
// lanes should be right more often than low ones.
// - A built lane's confidence is the mean of its lanelets' (lanelets without one are ignored; a
//   lane with none is in no band: `unrated`).
// - Per band [lo, hi) (the last one closed at 1): precision = built lanes of the band that are
//   detections / built lanes of the band; recall = truth lanes detected by a built lane of the
//   band / all truth lanes (so the bands' recalls add up to the lane recall of the rated lanes).
#pragma once

#include "core/eval/evaluate.h"
#include "core/map/lane_map.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace lanemap::eval {

struct ConfidenceBand {
  double lo = 0.0, hi = 1.0;
  Ratio precision;  // detections / built lanes in the band
  Ratio recall;     // truth lanes found by the band's lanes / truth lanes
};

struct ConfidenceReport {
  std::vector<ConfidenceBand> bands;
  size_t unrated = 0;  // built lanes without a confidence
};

// Bands between consecutive `edges` (0 and 1 added): {0.5, 0.8} -> [0, 0.5), [0.5, 0.8), [0.8, 1].
ConfidenceReport confidenceBands(const EvalReport& report, const map::LaneMap& built,
                                 const std::vector<double>& edges = {0.5, 0.8});
// {"bands": [{"lo", "hi", "built", "detected", "precision", "recall"}...], "unrated"}; NaN -> null.
nlohmann::json toJson(const ConfidenceReport& c);
// One line per band.
std::string summary(const ConfidenceReport& c);

}  // namespace lanemap::eval
