// The car's path through each intersection it drives through (a driven passage,
// core/intersections/driven_passage.h), cut from its positions by the road tracker's events: from
// lead_m of driving before it reached the intersection (the end of the road it came from) until
// the tracker has it on the next road (exit_commit_m or so past that road's start). A passage
// shapes the junction's connections of that road pair. One place for lanemap-offline and the lane
// mapper, so both cut the same passages from the same poses.
#pragma once

#include "core/intersections/driven_passage.h"
#include "core/tracking/road_tracker.h"

#include <Eigen/Core>

#include <cstdint>
#include <deque>
#include <optional>

namespace lanemap::tracking {

struct PassageRecorderOptions {
  double spacing_m = 0.5;   // a position is kept once the car moved this far from the last kept one
  double lead_m = 15.0;     // kept from this much driving before the intersection was reached
  double max_length_m = 400.0;  // a passage longer than this (the car lingered, lost its way) is dropped
};

class PassageRecorder {
 public:
  explicit PassageRecorder(PassageRecorderOptions options = {}) : o_(options) {}

  // A position of the car (ENU in the skeleton's frame), in time order; non-finite ones are skipped.
  void addPosition(const Eigen::Vector2d& p);
  // The tracker's events in their order (after the position that caused them was added): the
  // passage completed by this event, if any (a kEnteredRoad right after the road before it
  // reached the intersection).
  std::optional<intersections::DrivenPassage> onEvent(const RoadEvent& e);

 private:
  PassageRecorderOptions o_;
  std::deque<Eigen::Vector2d> trail_;  // kept positions, oldest first
  std::deque<double> along_;            // cumulative distance of each kept position
  int64_t dropped_ = 0;                 // positions dropped off the front (indices stay absolute)
  struct Reached {
    int64_t road = -1, intersection = -1;
    int64_t first = 0;  // absolute index of the passage's first position
  };
  std::optional<Reached> reached_;
};

}  // namespace lanemap::tracking
