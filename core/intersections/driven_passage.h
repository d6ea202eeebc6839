// The car's own path through an intersection (a driven passage) and what it says of the
// intersection lanelets' shape.
//
// METHOD.md section 5 joins an incoming lane to an outgoing lane by a Bezier curve through the
// intersection of their end tangents. Where the car drove from one road to the other, its poses
// trace how that movement really runs: around a roundabout that the OSM data draws as one node,
// wide or tight on a skewed junction. A passage is the car's positions from shortly before it
// reached the intersection (the end of the road it came from) until it was on the next road
// (core/tracking/passage_recorder.h records them from the road tracker's events).
//
// Its use (drivenCentre, displacementBetween, meanDisplacement): the passage is matched to the lane ends it passes, the in-lane end
// P0 and the out-lane start P2 each the nearest within max_offset_m; its stretch between the
// points nearest them, minus the offset at each end taken off linearly in arc length (the car does
// not drive exactly on a lane's centre line, and a drive's pose offset moves the whole path), runs
// from P0 exactly to P2 exactly. Its difference from the Bezier centre between the same ends, as a
// function of the normalised arc length u in [0, 1] (zero at both ends), is the displacement; the
// displacements of several passages of the same road pair are averaged. Every connection of that
// road pair (the lane the car drove and those beside it, which share their bounds) is its Bezier
// centre and bounds, each point moved by the displacement at its own u: the ends stay exactly
// where the road lanelets' are, as Lanelet2 requires. The car's path is a measurement of one lane;
// the lanes beside it turning with it are taken to turn the same way.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

namespace lanemap::intersections {

struct DrivenPassage {
  int64_t intersection_id = -1;      // the skeleton intersection driven through
  int64_t from_road = -1, to_road = -1;
  std::vector<Eigen::Vector2d> path;  // ENU (the skeleton's frame), in driving order
};

struct PassageOptions {
  double max_offset_m = 1.5;  // a passage belongs to a lane end it passes within this (0: passages unused)
  int samples = 41;           // the displacement is kept at this many u, evenly spaced
  // Smoothing of the displacement, in passes of a [1 2 1] / 4 filter (ends kept at zero), tried in
  // this order: a connection takes the first under which it is sound (the poses' noise can turn a
  // bound tighter than Lanelet2's validator accepts, curvature 0.5), else keeps its Bezier.
  std::vector<int> smoothing_passes = {0, 5, 20, 80};
  double step_m = 0.5;        // a line is moved at points at most this far apart (a chord gains points)
  bool pairs = true;          // the lanes driven correct the pairing rules of their road pair
  bool shift_in_lanes = true; // ... also where the rules pair another in lane with the driven out lane
};

// A displacement field over the normalised arc length u in [0, 1]; zero at both ends.
struct Displacement {
  std::vector<Eigen::Vector2d> at;  // at[k]: the displacement at u = k / (at.size() - 1)
  int passages = 0;                 // how many passages it averages
  Eigen::Vector2d operator()(double u) const;
  // The polyline with each point moved by the displacement at its own normalised arc length
  // (end points unchanged); a segment longer than step_m first gains points along it.
  std::vector<Eigen::Vector2d> apply(const std::vector<Eigen::Vector2d>& line, double step_m = 0.5) const;
  // The same after `passes` passes of a [1 2 1] / 4 filter (its ends stay zero).
  Displacement smoothed(int passes) const;
};

// The passage's path between the lane ends p0 (in-lane end) and p2 (out-lane start), offsets at the
// ends taken off linearly in arc length: starts at p0, ends at p2. nullopt when the path does not
// pass within options.max_offset_m of both, or passes p2 before p0.
std::optional<std::vector<Eigen::Vector2d>> drivenCentre(const std::vector<Eigen::Vector2d>& path, const Eigen::Vector2d& p0,
                                                         const Eigen::Vector2d& p2, const PassageOptions& options = {});

// The displacement of `driven` (drivenCentre) from `bezier` (the connection's centre polyline
// between the same ends), at options.samples values of u.
Displacement displacementBetween(const std::vector<Eigen::Vector2d>& driven, const std::vector<Eigen::Vector2d>& bezier,
                                 const PassageOptions& options = {});

// Point-wise mean of the displacements of the first one's size (each counted once, their passages
// summed); nullopt when there is none.
std::optional<Displacement> meanDisplacement(const std::vector<Displacement>& ds);

// Resamples a polyline at n points evenly spaced in arc length (ends kept).
std::vector<Eigen::Vector2d> resampleEvenly(const std::vector<Eigen::Vector2d>& line, int n);

}  // namespace lanemap::intersections
