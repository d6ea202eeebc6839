// What the live map viewer (lanemap-viewer, processes/viewer) shows, with no LCM: the car and its
// trail, the skeleton's roads coloured by coverage, the BEV of the road being driven (the BEV
// builder's picture, about once a second) or of the last road it handed over, the mapped lanes (every road's lanes plus the intersections built between them,
// core/mapping as the lane mapper does) and the health of every process from STATUS. The process
// feeds it from LCM (or from a finished map store); the HTTP server (http_server.h) reads it.
// Thread-safe: one mutex; the JSON, GeoJSON, Lanelet2 and PNG outputs are cached per version, so
// a page polling every second costs a string copy, not a rebuild.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/bev/bev_render.h"
#include "core/intersections/intersections.h"
#include "core/map/lane_map.h"
#include "core/mapping/map_assembler.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace lanemap::viewer {

struct ViewerOptions {
  double trail_spacing_m = 1.0;         // a pose closer than this to the last trail point is not kept
  size_t max_trail_points = 20000;      // oldest points dropped beyond this
  double status_stale_s = 3.0;          // a process whose last STATUS is older is "behind"
  double loss_window_s = 10.0;          // ... and one whose loss counters grew within this window
  double cpu_behind_fraction = 0.95;    // ... and one using this much of a core
  int64_t queue_behind = 10;            // ... and one with a queue_length above this
  int bev_max_px = 1024;                // longest side of the BEV picture
  double two_way_offset_m = 2.0;        // a two-way road's directions drawn this far to their right
};

// Counters whose growth means a process lost work (frames, roads): drops in the panel.
bool isLossCounter(const std::string& name);

struct ProcessStatus {
  std::string process, host, state;
  int pid = 0;
  std::map<std::string, int64_t> counters;
  double latency_p50_ms = 0.0, latency_p99_ms = 0.0;  // NaN when the process has no samples
  double cpu_fraction = 0.0;
};

// Coverage of one atomic road on the skeleton layer.
enum class Coverage { kNeverDriven, kDriven, kMapped };
const char* toString(Coverage c);

class ViewerState {
 public:
  ViewerState(std::shared_ptr<const skeleton::Skeleton> skeleton, std::vector<osm::Restriction> restrictions = {},
              intersections::IntersectionOptions intersection_options = {}, ViewerOptions options = {});

  const skeleton::Skeleton& skeleton() const { return *skeleton_; }

  // POSE: WGS84 degrees, heading in radians (ENU, 0 = east, counter-clockwise).
  void onPose(int64_t utime, double lat, double lon, double heading_rad);
  // ROAD_EVENT: the car entered a road (it becomes the open road and counts as driven), or
  // reached the intersection that closes it.
  void onRoadEntered(int64_t road_id);
  void onRoadClosed(int64_t road_id);
  // BEV_ROAD: the grid the builder wrote for a road (rendered to a PNG with unobserved cells
  // transparent, north up, placed by its ENU bounds). Throws BevError on an empty grid.
  void setBev(int64_t road_id, const bev::BevGrid& grid);
  // BEV_OPEN: the BEV builder's picture of the road being driven (about once a second). Shown
  // unless it is of another road than the open one, or of a closed road whose full BEV is shown
  // (a late picture): then false. Throws BevError on an empty picture.
  bool setOpenRoadBev(int64_t road_id, const bev::BevPicture& picture);
  // LANE_MAP: the lanes of one road (replacing that road's earlier lanes), in any ENU origin: they
  // are moved into the skeleton's frame when the origin differs.
  void setRoadLanes(int64_t road_id, map::LaneMap lanes);
  // STATUS; now_s: the receiving clock (seconds, monotonic), used for staleness and loss windows.
  void onStatus(const ProcessStatus& status, double now_s);

  // Outputs. stateJson: {version, car, trail_count, open_road, bev {road_id, version, open, bounds}, map {roads, road_lanes,
  // connections, version}, coverage {driven, mapped, never_driven, version}, processes [...]}.
  std::string stateJson(double now_s);
  nlohmann::json stateValue(double now_s);
  // The skeleton's atomic roads, one LineString each (WGS84), properties road_id, way_id, name,
  // highway, from, to, lanes (the OSM tag, "" when none), coverage.
  std::string skeletonGeoJson();
  // io::toGeoJson of the assembled map (roads + intersections).
  std::string lanesGeoJson();
  // The assembled map as Lanelet2 OSM (io::toLanelet2Xml); "" when nothing is mapped yet.
  std::string lanelet2Xml();
  // The last BEV picture (PNG bytes); "" when none.
  std::string bevPng();
  // Trail points [lon, lat] from index `from` on (indices count every point ever kept).
  nlohmann::json trail(int64_t from);

  // Bumped on every change that a page must redraw for.
  uint64_t version() const;
  // Lanelets of a road in the assembled map (tests, status line).
  size_t roadLaneCount(int64_t road_id) const;
  size_t mappedRoadCount() const;
  Coverage coverage(int64_t road_id) const;

 private:
  void setBevPicture(int64_t road_id, const bev::BevPicture& picture, bool open);
  void assembleLocked();
  Coverage coverageLocked(int64_t road_id) const;
  nlohmann::json processesLocked(double now_s) const;

  std::shared_ptr<const skeleton::Skeleton> skeleton_;
  std::vector<osm::Restriction> restrictions_;
  intersections::IntersectionOptions intersection_options_;
  ViewerOptions options_;

  mutable std::mutex mutex_;
  uint64_t version_ = 1;
  // car
  bool have_pose_ = false;
  int64_t pose_utime_ = 0;
  double lat_ = 0, lon_ = 0, heading_ = 0;
  int64_t poses_ = 0;
  std::deque<std::array<double, 2>> trail_;  // lon, lat
  int64_t trail_first_ = 0;                  // index of trail_.front()
  Eigen::Vector2d last_trail_enu_ = Eigen::Vector2d::Zero();
  // roads
  int64_t open_road_ = -1;
  std::set<int64_t> driven_, closed_;
  uint64_t coverage_version_ = 1;
  std::string skeleton_cache_;
  uint64_t skeleton_cache_version_ = 0;
  // lanes
  std::unique_ptr<mapping::MapAssembler> assembler_;  // the roads' lanes, intersections kept as built
  map::LaneMap assembled_;
  uint64_t map_version_ = 0;
  std::string lanes_cache_, lanelet2_cache_;
  uint64_t lanes_cache_version_ = 0, lanelet2_cache_version_ = 0;
  // BEV
  int64_t bev_road_ = -1;
  bool bev_open_ = false;  // the picture is of the open road (BEV_OPEN), not a closed road's grid
  uint64_t bev_version_ = 0;
  std::string bev_png_;
  double bev_south_ = 0, bev_west_ = 0, bev_north_ = 0, bev_east_ = 0;
  // STATUS
  struct Tracked {
    ProcessStatus status;
    double received_s = 0.0;
    int64_t losses = 0;
    double last_loss_growth_s = -1e18;
    int messages = 0;
  };
  std::map<std::string, Tracked> processes_;
};

}  // namespace lanemap::viewer
