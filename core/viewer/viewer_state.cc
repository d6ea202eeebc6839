// The live map viewer's state (see viewer_state.h).
#include "core/viewer/viewer_state.h"

#include "core/bev/bev_render.h"
#include "core/geo/local_frame.h"
#include "core/io/geojson.h"
#include "core/io/lanelet2.h"
#include "core/mapping/map_assembler.h"

#include <algorithm>
#include <cmath>

namespace lanemap::viewer {
namespace {

using nlohmann::json;

double round6(double v) { return std::round(v * 1e7) / 1e7; }

// A JSON number, or null for NaN/inf (JSON has no NaN).
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// Polyline shifted `d` metres to the right of its direction (per-vertex normals, averaged).
std::vector<Eigen::Vector2d> offsetRight(const std::vector<Eigen::Vector2d>& pts, double d) {
  if (pts.size() < 2 || d == 0.0) return pts;
  std::vector<Eigen::Vector2d> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    Eigen::Vector2d t = Eigen::Vector2d::Zero();
    if (i > 0) t += (pts[i] - pts[i - 1]).normalized();
    if (i + 1 < pts.size()) t += (pts[i + 1] - pts[i]).normalized();
    if (t.norm() < 1e-9) t = (pts[std::min(i + 1, pts.size() - 1)] - pts[i > 0 ? i - 1 : 0]).normalized();
    t.normalize();
    out[i] = pts[i] + d * Eigen::Vector2d(t.y(), -t.x());
  }
  return out;
}

std::string tag(const osm::Tags& tags, const char* key) {
  auto it = tags.find(key);
  return it == tags.end() ? std::string() : it->second;
}

}  // namespace

bool isLossCounter(const std::string& name) {
  static const char* kLoss[] = {"frames_dropped", "frames_late",  "frames_queue_full", "frames_out_of_order",
                                "frames_no_pose", "roads_failed", "roads_write_failed", "frames_failed",
                                "frames_decode_error"};
  for (const char* k : kLoss) {
    if (name == k) return true;
  }
  return false;
}

const char* toString(Coverage c) {
  switch (c) {
    case Coverage::kNeverDriven: return "never_driven";
    case Coverage::kDriven: return "driven";
    case Coverage::kMapped: return "mapped";
  }
  return "never_driven";
}

ViewerState::ViewerState(std::shared_ptr<const skeleton::Skeleton> skeleton, std::vector<osm::Restriction> restrictions,
                         intersections::IntersectionOptions intersection_options, ViewerOptions options)
    : skeleton_(std::move(skeleton)), restrictions_(std::move(restrictions)),
      intersection_options_(std::move(intersection_options)), options_(options) {
  if (!skeleton_) throw std::invalid_argument("ViewerState: no skeleton");
  assembler_ = std::make_unique<mapping::MapAssembler>(*skeleton_, intersection_options_, restrictions_);
  const auto& o = skeleton_->frame().origin();
  assembled_.origin_lat = o.lat;
  assembled_.origin_lon = o.lon;
  assembled_.origin_alt = o.alt;
}

void ViewerState::onPose(int64_t utime, double lat, double lon, double heading_rad) {
  if (!std::isfinite(lat) || !std::isfinite(lon) || std::abs(lat) > 90.0 || std::abs(lon) > 180.0) return;
  const Eigen::Vector3d enu = skeleton_->frame().toEnu(lat, lon, 0.0);
  std::lock_guard<std::mutex> lock(mutex_);
  have_pose_ = true;
  pose_utime_ = utime;
  lat_ = lat;
  lon_ = lon;
  heading_ = std::isfinite(heading_rad) ? heading_rad : 0.0;
  ++poses_;
  const Eigen::Vector2d p = enu.head<2>();
  if (trail_.empty() || (p - last_trail_enu_).norm() >= options_.trail_spacing_m) {
    trail_.push_back({round6(lon), round6(lat)});
    last_trail_enu_ = p;
    while (trail_.size() > options_.max_trail_points) {
      trail_.pop_front();
      ++trail_first_;
    }
  }
  ++version_;
}

void ViewerState::onRoadEntered(int64_t road_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  open_road_ = road_id;
  if (skeleton_->road(road_id) && driven_.insert(road_id).second) ++coverage_version_;
  ++version_;
}

void ViewerState::onRoadClosed(int64_t road_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (open_road_ == road_id) open_road_ = -1;
  if (skeleton_->road(road_id)) {
    closed_.insert(road_id);
    if (driven_.insert(road_id).second) ++coverage_version_;
  }
  ++version_;
}

void ViewerState::setBev(int64_t road_id, const bev::BevGrid& grid) {
  if (grid.cellBounds().isEmpty()) throw bev::BevError("BEV grid of road " + std::to_string(road_id) + " is empty");
  setBevPicture(road_id, bev::bevPicture(grid, std::max(1, options_.bev_max_px)), false);
}

bool ViewerState::setOpenRoadBev(int64_t road_id, const bev::BevPicture& picture) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // A picture of a road the car has left (it came late, or the road was closed meanwhile) would
    // hide the closed road's full BEV or the next road's.
    if (open_road_ >= 0 && road_id != open_road_) return false;
    if (closed_.count(road_id) && bev_road_ == road_id && !bev_open_) return false;
  }
  setBevPicture(road_id, picture, true);
  return true;
}

void ViewerState::setBevPicture(int64_t road_id, const bev::BevPicture& picture, bool open) {
  if (picture.png.empty() || picture.enu.isEmpty()) throw bev::BevError("empty BEV picture of road " + std::to_string(road_id));
  const geo::LatLonAlt sw = skeleton_->frame().toWgs84(Eigen::Vector3d(picture.enu.min().x(), picture.enu.min().y(), 0.0));
  const geo::LatLonAlt ne = skeleton_->frame().toWgs84(Eigen::Vector3d(picture.enu.max().x(), picture.enu.max().y(), 0.0));
  std::lock_guard<std::mutex> lock(mutex_);
  bev_png_.assign(picture.png.begin(), picture.png.end());
  bev_road_ = road_id;
  bev_open_ = open;
  bev_south_ = sw.lat;
  bev_west_ = sw.lon;
  bev_north_ = ne.lat;
  bev_east_ = ne.lon;
  ++bev_version_;
  ++version_;
}

void ViewerState::setRoadLanes(int64_t road_id, map::LaneMap lanes) {
  const auto& o = skeleton_->frame().origin();
  if (std::abs(lanes.origin_lat - o.lat) > 1e-12 || std::abs(lanes.origin_lon - o.lon) > 1e-12 ||
      std::abs(lanes.origin_alt - o.alt) > 1e-6) {
    const geo::LocalFrame src(geo::LatLonAlt{lanes.origin_lat, lanes.origin_lon, lanes.origin_alt});
    auto move = [&](Eigen::Vector3d& p) { p = skeleton_->frame().toEnu(src.toWgs84(p)); };
    for (auto& l : lanes.lines) for (auto& p : l.points) move(p);
    for (auto& ll : lanes.lanelets) for (auto& p : ll.centre) move(p);
    lanes.origin_lat = o.lat;
    lanes.origin_lon = o.lon;
    lanes.origin_alt = o.alt;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  const bool had = assembler_->roads().count(road_id) > 0;
  assembler_->setRoad(road_id, std::move(lanes));
  if (!had && skeleton_->road(road_id)) ++coverage_version_;
  assembleLocked();
  ++version_;
}

void ViewerState::assembleLocked() {
  assembled_ = assembler_->map();  // the intersections at the new road's ends rebuilt, the rest kept
  ++map_version_;
}

void ViewerState::onStatus(const ProcessStatus& status, double now_s) {
  if (status.process.empty()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  Tracked& t = processes_[status.process];
  int64_t losses = 0;
  for (const auto& [k, v] : status.counters) {
    if (isLossCounter(k)) losses += v;
  }
  // A restarted process starts its counters at 0 again: only growth counts.
  if (t.messages > 0 && losses > t.losses && status.pid == t.status.pid) t.last_loss_growth_s = now_s;
  t.losses = losses;
  t.status = status;
  t.received_s = now_s;
  ++t.messages;
  ++version_;
}

nlohmann::json ViewerState::processesLocked(double now_s) const {
  json out = json::array();
  for (const auto& [name, t] : processes_) {
    const ProcessStatus& s = t.status;
    const double age = now_s - t.received_s;
    std::vector<std::string> why;
    if (age > options_.status_stale_s) why.push_back("no STATUS for " + std::to_string(static_cast<int>(age)) + " s");
    if (now_s - t.last_loss_growth_s <= options_.loss_window_s) why.push_back("dropping");
    if (s.cpu_fraction >= options_.cpu_behind_fraction) why.push_back("CPU saturated");
    auto q = s.counters.find("queue_length");
    if (q != s.counters.end() && q->second > options_.queue_behind) why.push_back("queue " + std::to_string(q->second));
    std::string reason;
    for (const auto& w : why) reason += (reason.empty() ? "" : ", ") + w;
    json counters = json::object();
    for (const auto& [k, v] : s.counters) counters[k] = v;
    out.push_back(json{{"process", name},
                       {"host", s.host},
                       {"pid", s.pid},
                       {"state", s.state},
                       {"cpu", number(s.cpu_fraction)},
                       {"latency_p50_ms", number(s.latency_p50_ms)},
                       {"latency_p99_ms", number(s.latency_p99_ms)},
                       {"drops", t.losses},
                       {"age_s", std::round(age * 10.0) / 10.0},
                       {"behind", !why.empty()},
                       {"reason", reason},
                       {"counters", counters}});
  }
  return out;
}

Coverage ViewerState::coverageLocked(int64_t road_id) const {
  if (assembler_->roads().count(road_id)) return Coverage::kMapped;
  if (driven_.count(road_id)) return Coverage::kDriven;
  return Coverage::kNeverDriven;
}

Coverage ViewerState::coverage(int64_t road_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return coverageLocked(road_id);
}

nlohmann::json ViewerState::stateValue(double now_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  json car = nullptr;
  if (have_pose_) {
    car = json{{"lat", round6(lat_)}, {"lon", round6(lon_)}, {"heading", heading_}, {"utime", pose_utime_}, {"poses", poses_}};
  }
  json bev = nullptr;
  if (bev_version_ > 0) {
    bev = json{{"road_id", bev_road_}, {"version", bev_version_}, {"open", bev_open_},
               {"bounds", json::array({json::array({bev_south_, bev_west_}), json::array({bev_north_, bev_east_})})}};
  }
  size_t road_lanes = 0, connections = 0;
  json lanes_by_road = json::object();
  for (const auto& ll : assembled_.lanelets) {
    if (ll.kind == map::LaneletKind::kRoad) {
      ++road_lanes;
      const std::string key = std::to_string(ll.road_id);
      lanes_by_road[key] = lanes_by_road.value(key, 0) + 1;
    } else {
      ++connections;
    }
  }
  size_t driven = 0, mapped = 0, never = 0;
  for (const auto& r : skeleton_->roads()) {
    switch (coverageLocked(r.id)) {
      case Coverage::kMapped: ++mapped; break;
      case Coverage::kDriven: ++driven; break;
      case Coverage::kNeverDriven: ++never; break;
    }
  }
  json closed = json::array();
  for (int64_t id : closed_) closed.push_back(id);
  return json{{"version", version_},
              {"car", car},
              {"trail_count", trail_first_ + static_cast<int64_t>(trail_.size())},
              {"open_road", open_road_},
              {"closed_roads", closed},
              {"bev", bev},
              {"map", {{"version", map_version_}, {"roads", assembler_->roads().size()}, {"road_lanes", road_lanes},
                       {"connections", connections}, {"lanes_by_road", lanes_by_road}}},
              {"coverage", {{"version", coverage_version_}, {"driven", driven}, {"mapped", mapped}, {"never_driven", never}}},
              {"processes", processesLocked(now_s)}};
}

std::string ViewerState::stateJson(double now_s) { return stateValue(now_s).dump(); }

std::string ViewerState::skeletonGeoJson() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (skeleton_cache_version_ == coverage_version_ && !skeleton_cache_.empty()) return skeleton_cache_;
  json features = json::array();
  for (const auto& r : skeleton_->roads()) {
    const auto pts = offsetRight(r.polyline, r.reverse_id >= 0 ? options_.two_way_offset_m : 0.0);
    json coords = json::array();
    for (const auto& p : pts) {
      const geo::LatLonAlt g = skeleton_->frame().toWgs84(Eigen::Vector3d(p.x(), p.y(), 0.0));
      coords.push_back(json::array({round6(g.lon), round6(g.lat)}));
    }
    features.push_back(json{{"type", "Feature"},
                            {"geometry", {{"type", "LineString"}, {"coordinates", coords}}},
                            {"properties",
                             {{"road_id", r.id},
                              {"way_id", r.way_id},
                              {"name", tag(r.tags, "name")},
                              {"highway", tag(r.tags, "highway")},
                              {"lanes", tag(r.tags, "lanes")},
                              {"from", r.from},
                              {"to", r.to},
                              {"length_m", std::round(r.length * 10.0) / 10.0},
                              {"coverage", toString(coverageLocked(r.id))}}}});
  }
  skeleton_cache_ = json{{"type", "FeatureCollection"}, {"features", features}}.dump();
  skeleton_cache_version_ = coverage_version_;
  return skeleton_cache_;
}

std::string ViewerState::lanesGeoJson() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (lanes_cache_version_ != map_version_ || lanes_cache_.empty()) {
    lanes_cache_ = io::toGeoJson(assembled_).dump();
    lanes_cache_version_ = map_version_;
  }
  return lanes_cache_;
}

std::string ViewerState::lanelet2Xml() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (assembled_.lanelets.empty()) return "";
  if (lanelet2_cache_version_ != map_version_ || lanelet2_cache_.empty()) {
    io::Lanelet2WriteOptions wo;
    wo.check_orientation = false;  // show what there is; the lane mapper's own file is the checked one
    lanelet2_cache_ = io::toLanelet2Xml(assembled_, wo, "viewer map");
    lanelet2_cache_version_ = map_version_;
  }
  return lanelet2_cache_;
}

std::string ViewerState::bevPng() {
  std::lock_guard<std::mutex> lock(mutex_);
  return bev_png_;
}

nlohmann::json ViewerState::trail(int64_t from) {
  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t start = std::max(from, trail_first_);
  json pts = json::array();
  for (int64_t i = start - trail_first_; i < static_cast<int64_t>(trail_.size()); ++i) {
    pts.push_back(json::array({trail_[static_cast<size_t>(i)][0], trail_[static_cast<size_t>(i)][1]}));
  }
  return json{{"from", std::min<int64_t>(start, trail_first_ + static_cast<int64_t>(trail_.size()))}, {"points", pts}};
}

uint64_t ViewerState::version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

size_t ViewerState::roadLaneCount(int64_t road_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  size_t n = 0;
  for (const auto& ll : assembled_.lanelets) {
    if (ll.kind == map::LaneletKind::kRoad && ll.road_id == road_id) ++n;
  }
  return n;
}

size_t ViewerState::mappedRoadCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return assembler_->roads().size();
}

}  // namespace lanemap::viewer
