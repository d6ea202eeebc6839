#include "core/mapping/coverage.h"

#include "core/bev/bev_grid.h"
#include "core/bev/bev_store.h"
#include "core/intersections/curve.h"
#include "core/intersections/intersections.h"
#include "core/io/lanelet2.h"
#include "core/skeleton/road_direction.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

namespace lanemap::mapping {

const char* toString(RoadState s) {
  switch (s) {
    case RoadState::kNeverDriven: return "never_driven";
    case RoadState::kDriven: return "driven";
    case RoadState::kPartial: return "partial";
    case RoadState::kMapped: return "mapped";
  }
  return "?";
}

int CityCoverage::count(RoadState s) const {
  return static_cast<int>(std::count_if(roads.begin(), roads.end(), [&](const RoadCoverage& r) { return r.state == s; }));
}

namespace {

// A road's lanes from its road lanelets: their count, mean confidence, and the station a partial
// road was mapped to (when any lanelet is partial).
void setLanes(RoadCoverage& c, const std::vector<const map::Lanelet*>& lanelets) {
  std::set<int> lanes;
  double conf_sum = 0.0, station = 0.0;
  int rated = 0;
  bool partial = false;
  for (const auto* ll : lanelets) {
    if (ll->kind != map::LaneletKind::kRoad) continue;
    lanes.insert(ll->index_from_left);
    if (ll->confidence) {
      conf_sum += *ll->confidence;
      ++rated;
    }
    if (ll->partial) {
      partial = true;
      station = std::max(station, ll->partial->station_m);
    }
  }
  c.lanes = static_cast<int>(lanes.size());
  if (rated > 0) c.confidence = conf_sum / rated;
  if (c.lanes > 0) {
    c.state = partial ? RoadState::kPartial : RoadState::kMapped;
    c.mapped_m = partial ? std::clamp(station, 0.0, c.length_m) : c.length_m;
  }
}

// The city's totals from its roads, and the roads in id order.
void totalAndSort(CityCoverage& out) {
  for (const auto& c : out.roads) {
    out.total_m += c.length_m;
    out.mapped_m += c.mapped_m;
  }
  std::sort(out.roads.begin(), out.roads.end(), [](const RoadCoverage& a, const RoadCoverage& b) { return a.road_id < b.road_id; });
}

}  // namespace

CityCoverage cityCoverage(const skeleton::Skeleton& sk, const std::string& store) {
  namespace fs = std::filesystem;
  const auto grids = bev::roadFiles((fs::path(store) / "bev").string(), ".bev");
  const auto partial_grids = bev::roadFiles((fs::path(store) / "bev" / "partial").string(), ".bev");
  const auto lane_files = bev::roadFiles((fs::path(store) / "lanes").string(), ".osm");
  const auto& origin = sk.frame().origin();
  io::Lanelet2ReadOptions ro;
  ro.origin_alt = origin.alt;
  // Without per-road files (lanemap-offline's output folder): the whole map, by road id.
  map::LaneMap whole;
  std::map<int64_t, std::vector<const map::Lanelet*>> whole_by_road;
  std::string whole_problem;
  if (lane_files.empty()) {
    std::error_code ec;
    for (const char* name : {"lane_map.osm", "map.osm"}) {
      const fs::path path = fs::path(store) / name;
      if (!fs::is_regular_file(path, ec)) continue;
      try {
        whole = io::readLanelet2(path.string(), origin.lat, origin.lon, ro);
      } catch (const std::exception& e) {
        whole_problem = e.what();
      }
      break;
    }
    for (const auto& ll : whole.lanelets) whole_by_road[ll.road_id].push_back(&ll);
  }
  CityCoverage out;
  for (const auto& road : sk.roads()) {
    RoadCoverage c;
    c.road_id = road.id;
    c.from = road.from;
    c.to = road.to;
    c.length_m = road.length;
    for (const auto* files : {&grids, &partial_grids}) {
      const auto it = files->find(road.id);
      if (it == files->end()) continue;
      try {
        const auto h = bev::BevGrid::readHeader(it->second);
        c.traversals += h.traversals;
        c.frames += h.frames;
      } catch (const std::exception& e) {
        c.problems.push_back(e.what());
      }
    }
    if (c.frames > 0) c.state = RoadState::kDriven;
    if (const auto it = lane_files.find(road.id); it != lane_files.end()) {
      try {
        const map::LaneMap m = io::readLanelet2(it->second, origin.lat, origin.lon, ro);
        std::vector<const map::Lanelet*> lanelets;
        for (const auto& ll : m.lanelets) lanelets.push_back(&ll);
        setLanes(c, lanelets);
      } catch (const std::exception& e) {
        c.problems.push_back(e.what());
      }
    } else if (const auto w = whole_by_road.find(road.id); w != whole_by_road.end()) {
      setLanes(c, w->second);
    }
    out.roads.push_back(std::move(c));
  }
  totalAndSort(out);
  if (!whole_problem.empty()) out.problems.push_back(whole_problem);
  return out;
}

namespace {

struct Planner {
  const skeleton::Skeleton& sk;
  double speed;
  int lookahead;
  std::map<int64_t, std::vector<const skeleton::AtomicRoad*>> out_of;  // intersection -> roads leaving it
  std::map<int64_t, double> left;                                      // road -> unmapped length left

  double seconds(const skeleton::AtomicRoad& r) const { return r.length / speed; }
  double gain(int64_t road) const {
    const auto it = left.find(road);
    return it == left.end() ? 0.0 : it->second;
  }

  // The roads one may take after `prev` (nullptr: at the start): those leaving its end, but no
  // U-turn (a driver avoids them; no map has them, METHOD.md 5): not straight back, nor a heading
  // change beyond the intersection builder's default uturn_min_deg (150 degrees), measured as it
  // measures turns: a hairpin onto another road, which neither the mapper nor the simulator's
  // world connects.
  template <class F>
  void next(int64_t at, const skeleton::AtomicRoad* prev, F&& f) const {
    static const intersections::IntersectionOptions kJunction;
    const auto it = out_of.find(at);
    if (it == out_of.end()) return;
    for (const auto* r : it->second) {
      if (prev && prev->reverse_id == r->id) continue;
      if (prev && std::abs(intersections::headingChange(skeleton::directionAtJunction(sk, *prev, true, kJunction.road_tangent_m),
                                                        skeleton::directionAtJunction(sk, *r, false, kJunction.road_tangent_m))) >
                      kJunction.uturn_min_deg * M_PI / 180.0) {
        continue;
      }
      f(r);
    }
  }

  // The best path of up to `depth` roads from `at` within `budget` s: (gain, time, first road).
  void search(int64_t at, const skeleton::AtomicRoad* prev, int depth, double budget, double gain_so_far, double time_so_far,
              const skeleton::AtomicRoad* first, std::set<int64_t>& used, double& best_gain, double& best_time,
              const skeleton::AtomicRoad*& best_first) const {
    if (first && (gain_so_far > best_gain + 1e-9 || (std::abs(gain_so_far - best_gain) <= 1e-9 && gain_so_far > 0 && time_so_far < best_time))) {
      best_gain = gain_so_far;
      best_time = time_so_far;
      best_first = first;
    }
    if (depth == 0) return;
    next(at, prev, [&](const skeleton::AtomicRoad* r) {
      const double t = time_so_far + seconds(*r);
      if (t > budget) return;
      const bool fresh = used.insert(r->id).second;
      search(r->to, r, depth - 1, budget, gain_so_far + (fresh ? gain(r->id) : 0.0), t, first ? first : r, used, best_gain, best_time,
             best_first);
      if (fresh) used.erase(r->id);
    });
  }

  // The quickest way (no U-turns: a search over roads, not intersections) from `at`, arrived at by
  // `prev`, to a road with something left, that road included; empty when none is in reach.
  std::vector<const skeleton::AtomicRoad*> toNearestNew(int64_t at, const skeleton::AtomicRoad* prev, double budget) const {
    std::set<int64_t> done;
    std::map<int64_t, double> best;                      // road -> quickest time at its end so far
    std::map<int64_t, const skeleton::AtomicRoad*> via;  // road -> the road before it on that way
    std::set<std::pair<double, int64_t>> queue;
    next(at, prev, [&](const skeleton::AtomicRoad* r) {
      best[r->id] = seconds(*r);
      queue.insert({seconds(*r), r->id});
    });
    while (!queue.empty()) {
      const auto [t, id] = *queue.begin();
      queue.erase(queue.begin());
      if (t > budget) break;  // the queue is in time order: nothing further is in reach
      if (!done.insert(id).second) continue;
      const skeleton::AtomicRoad* r = sk.road(id);
      if (gain(r->id) > 0.0) {
        std::vector<const skeleton::AtomicRoad*> path{r};
        for (auto it = via.find(r->id); it != via.end(); it = via.find(it->second->id)) path.push_back(it->second);
        std::reverse(path.begin(), path.end());
        return path;
      }
      next(r->to, r, [&](const skeleton::AtomicRoad* n) {
        const double nt = t + seconds(*n);
        if (done.count(n->id) || (best.count(n->id) && best[n->id] <= nt)) return;
        best[n->id] = nt;
        via[n->id] = r;
        queue.insert({nt, n->id});
      });
    }
    return {};
  }
};

}  // namespace

CityCoverage readCoverageJson(const std::string& path, const skeleton::Skeleton& sk) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read coverage file '" + path + "'");
  const auto doc = nlohmann::json::parse(f, nullptr, false);
  if (doc.is_discarded() || !doc.contains("roads") || !doc["roads"].is_array()) {
    throw std::runtime_error("coverage file '" + path + "' is not lanemap-coverage --json output (no roads list)");
  }
  std::map<int64_t, RoadCoverage> listed;
  try {
    for (const auto& r : doc["roads"]) {
      RoadCoverage c;
      c.road_id = r.at("road_id").get<int64_t>();
      c.from = r.at("from").get<int64_t>();
      c.to = r.at("to").get<int64_t>();
      const auto state = r.at("state").get<std::string>();
      c.state = state == "mapped" ? RoadState::kMapped : state == "partial" ? RoadState::kPartial
                : state == "driven" ? RoadState::kDriven : RoadState::kNeverDriven;
      c.mapped_m = r.value("mapped_m", 0.0);
      c.traversals = r.value("traversals", 0);
      const auto* road = sk.road(c.road_id);
      if (!road || road->from != c.from || road->to != c.to) {
        throw std::runtime_error("road " + std::to_string(c.road_id) + " runs " + std::to_string(c.from) + " -> " + std::to_string(c.to) +
                                 " there, not so in this skeleton: the file was made from another OSM file or map config");
      }
      listed[c.road_id] = c;
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("coverage file '" + path + "': " + e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("coverage file '" + path + "': " + e.what());
  }
  CityCoverage out;
  for (const auto& road : sk.roads()) {
    RoadCoverage c;
    if (const auto it = listed.find(road.id); it != listed.end()) c = it->second;
    c.road_id = road.id;
    c.from = road.from;
    c.to = road.to;
    c.length_m = road.length;
    c.mapped_m = c.state == RoadState::kMapped ? road.length : std::clamp(c.mapped_m, 0.0, road.length);
    out.roads.push_back(c);
  }
  totalAndSort(out);
  return out;
}

int64_t coverageStart(const skeleton::Skeleton& sk, const CityCoverage& coverage, uint64_t seed) {
  std::vector<int64_t> out_of_dead_end, open, any;
  for (const auto& c : coverage.roads) {
    any.push_back(c.from);
    if (c.state == RoadState::kMapped || c.length_m - c.mapped_m <= 0.0) continue;
    open.push_back(c.from);
    const auto* at = sk.intersection(c.from);
    const auto* to = sk.intersection(c.to);
    if (at && at->dead_end && to && !to->dead_end) out_of_dead_end.push_back(c.from);
  }
  const auto& pick = !out_of_dead_end.empty() ? out_of_dead_end : !open.empty() ? open : any;
  if (pick.empty()) throw std::invalid_argument("no roads to start a drive on");
  return pick[std::mt19937_64(seed * 104729 + 3)() % pick.size()];
}

CoveragePlan planCoverage(const skeleton::Skeleton& sk, const CityCoverage& coverage, int64_t start, double seconds, double speed_mps,
                          int lookahead) {
  if (!sk.intersection(start)) throw std::invalid_argument("no intersection " + std::to_string(start) + " in the skeleton");
  if (!(speed_mps > 0.0)) throw std::invalid_argument("the planning speed must be > 0");
  Planner p{sk, speed_mps, std::max(1, lookahead), {}, {}};
  for (const auto& r : sk.roads()) p.out_of[r.from].push_back(&r);
  for (const auto& c : coverage.roads) {
    if (c.state != RoadState::kMapped && c.length_m - c.mapped_m > 0.0) p.left[c.road_id] = c.length_m - c.mapped_m;
  }
  CoveragePlan plan;
  plan.intersections.push_back(start);
  int64_t at = start;
  const skeleton::AtomicRoad* prev = nullptr;
  const auto drive = [&](const skeleton::AtomicRoad* r) {
    plan.roads.push_back(r->id);
    plan.intersections.push_back(r->to);
    plan.seconds += p.seconds(*r);
    plan.new_m += p.gain(r->id);
    p.left.erase(r->id);
    at = r->to;
    prev = r;
  };
  for (;;) {
    const double budget = seconds - plan.seconds;
    double best_gain = 0.0, best_time = 0.0;
    const skeleton::AtomicRoad* first = nullptr;
    std::set<int64_t> used;
    p.search(at, prev, p.lookahead, budget, 0.0, 0.0, nullptr, used, best_gain, best_time, first);
    if (first && best_gain > 0.0) {
      drive(first);
      continue;
    }
    const auto path = p.toNearestNew(at, prev, budget);
    if (path.empty()) break;
    for (const auto* r : path) drive(r);
  }
  // The time left is shorter than any road that would cover more: the drive ends on the road
  // leaving here that has the most left to cover, as far as the time goes (a partial road).
  const double budget = seconds - plan.seconds;
  const skeleton::AtomicRoad* last = nullptr;
  p.next(at, prev, [&](const skeleton::AtomicRoad* r) {
    if (p.gain(r->id) > 0.0 && (!last || p.gain(r->id) > p.gain(last->id))) last = r;
  });
  if (last && budget > 0.0) {
    const double share = std::min(1.0, budget / p.seconds(*last));
    plan.roads.push_back(last->id);
    plan.intersections.push_back(last->to);
    plan.seconds += share * p.seconds(*last);
    plan.new_m += share * p.gain(last->id);
  }
  return plan;
}

}  // namespace lanemap::mapping
