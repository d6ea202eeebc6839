// The map skeleton M0 of METHOD.md section 0: a directed graph of atomic roads E_ij (one per
// direction of travel between intersections I_i and I_j) and intersections with their ROI polygon,
// in local ENU metres.
#pragma once

#include "core/geo/local_frame.h"
#include "core/osm/osm_data.h"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace lanemap::skeleton {

struct Intersection {
  int64_t id = 0;                      // OSM id of its (representative) junction node
  std::vector<int64_t> osm_nodes;      // junction nodes merged into it (dual carriageways)
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> roi;    // ROI polygon, counter-clockwise (METHOD.md section 0)
  bool dead_end = false;               // a way end that meets no other road
  std::vector<int64_t> incoming;       // atomic road ids ending here
  std::vector<int64_t> outgoing;       // atomic road ids starting here
};

struct AtomicRoad {
  int64_t id = 0;                      // stable for a given OSM file
  int64_t way_id = 0;                  // the OSM way it lies on
  int64_t from = 0;                    // intersection id of I_i
  int64_t to = 0;                      // intersection id of I_j
  bool along_way = true;               // direction of travel follows the way's node order
  int64_t reverse_id = -1;             // the opposite direction's atomic road, -1 if one-way
  std::vector<int64_t> osm_nodes;      // in the driving direction, junction to junction
  std::vector<Eigen::Vector2d> polyline;  // ENU, in the driving direction, junction to junction
  double length = 0.0;                 // of the polyline, metres
  double s_begin = 0.0;                // arc length where the road leaves I_i's ROI
  double s_end = 0.0;                  // arc length where it enters I_j's ROI
  osm::Tags tags;                      // the way's tags (lanes*, turn:lanes*, width, oneway, ...)
};

struct RoadMatch {
  int64_t road_id = -1;
  double distance = 0.0;     // metres from the polyline
  double s = 0.0;            // arc length of the closest point
  double heading_error = 0.0;  // radians, pose heading minus road heading, in [-pi, pi]
};

struct SkeletonOptions {
  double junction_merge_radius_m = 12.0;  // junction nodes closer than this become one intersection
  std::optional<geo::LatLonAlt> origin;   // default: centre of the data's bounds
  // ROI extent along each incident road (METHOD.md section 0, see skeleton.cc roiExtent): the road
  // node closest to the junction, unless closer than roi_min_node_distance_m or absent, then
  // max(half road width, roi_default_extent_m); at most max(that, roi_max_extent_m) and never
  // beyond the road's midpoint.
  double roi_min_node_distance_m = 3.0;
  double roi_default_extent_m = 6.0;
  double roi_max_extent_m = 15.0;
  double index_cell_m = 20.0;  // cell size of the grid index over road segments and ROIs
};

// nearestRoads with a heading ranks by distance + kHeadingWeightMPerRad * |heading_error|: the two
// directions of a two-way road are equally far, the one that agrees with the heading wins; a
// perpendicular road must be about 3 m closer to beat the one the car drives along.
inline constexpr double kHeadingWeightMPerRad = 2.0;

// Crossing-number point-in-polygon test (ROI polygons).
bool pointInPolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p);

class Skeleton {
 public:
  // Throws osm::OsmError when the data has no drivable way or the graph cannot be built.
  static Skeleton build(const osm::OsmData& data, const SkeletonOptions& options = {});

  const geo::LocalFrame& frame() const { return frame_; }
  const std::vector<Intersection>& intersections() const { return intersections_; }
  const std::vector<AtomicRoad>& roads() const { return roads_; }
  const AtomicRoad* road(int64_t id) const;
  const Intersection* intersection(int64_t id) const;

  // Point on a road's polyline at arc length s (clamped), and its unit tangent.
  Eigen::Vector2d pointAt(const AtomicRoad& road, double s) const;
  Eigen::Vector2d tangentAt(const AtomicRoad& road, double s) const;

  // Roads within max_distance of p, best first: by distance, or with a heading (radians, ENU,
  // 0 = east, counter-clockwise) by distance + kHeadingWeightMPerRad * |heading_error|.
  std::vector<RoadMatch> nearestRoads(const Eigen::Vector2d& p, double max_distance,
                                      std::optional<double> heading = std::nullopt) const;
  // p projected on one road: distance, arc length s of the closest point, and the heading error
  // when a heading is given. road_id = -1 for an unknown road.
  RoadMatch project(int64_t road_id, const Eigen::Vector2d& p,
                    std::optional<double> heading = std::nullopt) const;
  // The intersection whose ROI contains p, or nullptr.
  const Intersection* intersectionContaining(const Eigen::Vector2d& p) const;

 private:
  explicit Skeleton(const geo::LocalFrame& frame) : frame_(frame) {}
  geo::LocalFrame frame_;
  std::vector<Intersection> intersections_;
  std::vector<AtomicRoad> roads_;
  struct Index;
  std::shared_ptr<const Index> index_;  // spatial index over road segments
};

}  // namespace lanemap::skeleton
