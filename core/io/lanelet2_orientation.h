// The orientation check of Lanelet2 lanelets: whether Lanelet2's loader reads a lanelet's bounds
// as meant (used by the writer, the simulator's truth and the intersection builder), and the
// lanelet's outline. Part of core/io/lanelet2.h, which includes it.
#pragma once

#include "core/map/lane_map.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace lanemap::io {

// How Lanelet2's loader would read a lanelet: it aligns the two bounds as stored with
// lanelet2::geometry::align (the left bound is turned unless the middle point of the right bound
// lies on its right, then the right bound unless the middle point of the left lies on its left),
// and the lanelet's direction is theirs. A message when the aligned bounds run against each other
// or against the lanelet's centre line (its driving direction); empty when Lanelet2 reads it as
// meant. Long U-shaped lanelets and sharp connections between overlapping lane ends can fail.
std::string orientationProblem(const map::Lanelet& lanelet, const map::LineString& left,
                               const map::LineString& right);
// True when Lanelet2's loader would turn either bound as stored (both stored in the driving
// direction, as a lanelet's own bounds are; a line shared with an opposite lane is not). For such
// bounds orientationProblem can miss the misreading when a bound is short and its ends lie
// backwards (a connection around a tight corner whose inner lane ends overlap): turned, it still
// looks aligned by its ends. False when a bound is a single point (within 5 cm: a U-turn's inner
// bound), which gives align nothing to go by.
bool boundTurnedOnLoad(const map::LineString& left, const map::LineString& right);
// orientationProblem for every lanelet of the map. Empty when the map is consistent.
std::vector<std::string> orientationProblems(const map::LaneMap& map);

// The lanelet's outline for drawing and export: left bound forwards, then the right bound
// backwards (the right bound turned first if it runs against the left one, so an inconsistently
// oriented lanelet still gives a simple polygon). Not closed. Empty when a bound is missing.
std::vector<Eigen::Vector3d> laneletOutline(const map::LaneMap& map, const map::Lanelet& lanelet);

}  // namespace lanemap::io
