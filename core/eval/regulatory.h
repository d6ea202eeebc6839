// Scores of a built map's stop lines, crosswalks, regulatory elements and lane-change permissions
// against the truth (issue 15), both map::LaneMap in one ENU frame; part of eval::evaluate.
//
// Definitions (xy plane):
// - Stop lines: every line of type kStopLine. A built stop line's distance to a truth one is the
//   distance of its midpoint to the truth line (so a bar over one lane of a three-lane approach
//   counts by its offset along the road, not by where along the bar it lies); it matches within
//   stop_line_match_m, one-to-one, greedily nearest first. precision = matched / built, recall =
//   matched / truth, error_m = mean distance over the matched pairs (0.3 m off: error 0.3).
// - Crosswalks: position = the centroid of its four corners (first and last points of both
//   edges); matched like stop lines within crosswalk_match_m.
// - Regulatory elements: per matched stop line pair, whether the rule at it agrees (the kind of
//   the element whose stop line it is, or none on both sides): rules.accuracy.
// - Lane-change permission: the lines shared by two lanes of one direction (the right bound of
//   one lanelet and the left bound of another, as the Lanelet2 writer tags lane_change) carry
//   yes (dashed) or no (any other type). A truth shared line is matched to the nearest built
//   shared line within lane_change_match_m of its midpoint (distance to the built polyline);
//   accuracy = matched lines with the same permission / matched lines, coverage = matched / truth.
// Ratios with a zero denominator are NaN (JSON null).
#pragma once

#include "core/map/lane_map.h"

#include <nlohmann/json.hpp>

#include <cstddef>

namespace lanemap::eval {

struct RegulatoryOptions {
  double stop_line_match_m = 2.0;
  double crosswalk_match_m = 3.0;
  double lane_change_match_m = 0.75;
};

struct MatchScore {
  size_t truth = 0, built = 0, matched = 0;
  double error_sum_m = 0.0;
  double precision() const;  // matched / built
  double recall() const;     // matched / truth
  double error_m() const;    // mean error over matched
};

struct RegulatoryScores {
  MatchScore stop_lines, crosswalks;
  size_t rules_compared = 0, rules_agreeing = 0;  // over matched stop lines
  size_t lane_change_truth = 0, lane_change_matched = 0, lane_change_correct = 0;
  double ruleAccuracy() const;
  double laneChangeAccuracy() const;  // correct / matched
  double laneChangeCoverage() const;  // matched / truth
};

RegulatoryScores scoreRegulatory(const map::LaneMap& truth, const map::LaneMap& built,
                                 const RegulatoryOptions& options = {});

// {stop_lines: {truth, built, matched, precision, recall, error_m}, crosswalks: {...},
//  rules: {compared, agreeing, accuracy}, lane_change: {truth, matched, correct, accuracy, coverage}}
nlohmann::json toJson(const RegulatoryScores& s);

}  // namespace lanemap::eval
