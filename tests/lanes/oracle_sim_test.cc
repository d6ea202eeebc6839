// Lane exploration on the simulator's West Oakland world with an oracle BEV (the truth labels
// painted as a perfect segmentation + projection would accumulate them, tests/lanes/oracle_bev.h):
// isolates the exploration from the camera path. Per road: lane count against the truth lanelets
// of the road at stations every 5 m, and each explored lane's centre-line RMS against the nearest
// truth centre line; printed and asserted.
#include "core/io/lanelet2.h"
#include "core/lanes/explorer.h"
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "processes/framework/process.h"
#include "tests/common/sim_drive.h"
#include "tests/lanes/oracle_bev.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>

namespace {

using namespace lanemap;
using namespace lanemap::lanes;

double pointToPolyline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector3d>& line, bool* interior) {
  double best = INFINITY;
  *interior = false;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector2d a = line[i].head<2>(), b = line[i + 1].head<2>();
    const Eigen::Vector2d ab = b - a;
    const double t = (p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12);
    const double dist = (a + std::clamp(t, 0.0, 1.0) * ab - p).norm();
    if (dist < best) {
      best = dist;
      const bool before = i == 0 && t < 0.0, after = i + 2 == line.size() && t > 1.0;
      *interior = !before && !after;
    }
  }
  return best;
}

struct RoadScore {
  int64_t road = -1;
  double length = 0;
  int stations = 0, count_agree = 0;
  int truth_max = 0, found_max = 0;
  std::vector<double> lane_rms;
};

class OracleSim : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = new osm::OsmData(osm::readOsm(lanemap::testing::dataPath("osm/west-oakland.osm")));
    sk_ = new skeleton::Skeleton(skeleton::Skeleton::build(*data_));
    auto wopt = sim::WorldOptions::fromYaml(loadYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/sim_world.yaml"));
    world_ = sim::buildWorld(*sk_, wopt).release();
  }
  static void TearDownTestSuite() {
    delete world_;
    delete sk_;
    delete data_;
  }

  static RoadScore score(const skeleton::AtomicRoad& road, const ExplorerOptions& opt) {
    const bev::BevGrid grid = lanes::testing::paintOracle(*world_, road);
    const ExplorationResult res = exploreRoad(grid, RoadGeometry::fromSkeleton(road), opt);
    RoadScore sc;
    sc.road = road.id;
    sc.length = road.s_end - road.s_begin;
    std::vector<const map::Lanelet*> truth;
    for (const auto& ll : world_->truth().lanelets) {
      if (ll.kind == map::LaneletKind::kRoad && ll.road_id == road.id) truth.push_back(&ll);
    }
    // Lane count at stations: truth lanelets whose centre spans the station (in the road frame).
    std::vector<std::pair<double, double>> span;
    for (const auto* ll : truth) {
      double a = INFINITY, b = -INFINITY;
      for (const auto& p : ll->centre) {
        const double s = res.frame->toFrenet(p.head<2>()).x();
        a = std::min(a, s);
        b = std::max(b, s);
      }
      span.push_back({a, b});
    }
    for (double s = road.s_begin + 10.0; s <= road.s_end - 10.0; s += 5.0) {
      int t = 0;
      for (const auto& [a, b] : span) t += s >= a && s <= b;
      const int f = res.laneCountAt(s);
      ++sc.stations;
      sc.count_agree += t == f;
      sc.truth_max = std::max(sc.truth_max, t);
      sc.found_max = std::max(sc.found_max, f);
    }
    for (const Lane& lane : res.lanes) {
      double sq = 0;
      int n = 0;
      for (const auto& p : lane.waypoints) {
        double best = INFINITY;
        bool best_interior = false;
        for (const auto* ll : truth) {
          bool interior;
          const double d = pointToPolyline(p, ll->centre, &interior);
          if (d < best) {
            best = d;
            best_interior = interior;
          }
        }
        if (!best_interior || !std::isfinite(best)) continue;
        sq += best * best;
        ++n;
      }
      sc.lane_rms.push_back(n ? std::sqrt(sq / n) : INFINITY);
    }
    std::printf("road %3lld (%s, %.0f m): truth lanes <= %d, found <= %d, count right at %d/%d stations, RMS:",
                static_cast<long long>(road.id), road.tags.count("highway") ? road.tags.at("highway").c_str() : "?",
                sc.length, sc.truth_max, sc.found_max, sc.count_agree, sc.stations);
    for (double r : sc.lane_rms) std::printf(" %.3f", r);
    std::printf("  (%.2f s filter)\n", res.stats.filter_s);
    for (const Lane& l : res.lanes) {
      std::printf("    lane %d: s %.1f-%.1f, d %.2f..%.2f, split_from %d, merges_into %d, bounds %s/%s\n", l.id, l.s_begin,
                  l.s_end, l.centre.d(l.s_begin), l.centre.d(l.s_end), l.split_from, l.merges_into,
                  map::toString(l.left.type), map::toString(l.right.type));
      if (std::getenv("LANEMAP_ORACLE_VERBOSE")) {
        for (double s = l.s_begin; s <= l.s_end; s += 5.0) std::printf(" %.0f:%.2f", s, l.centre.d(s));
        std::printf("\n");
      }
    }
    return sc;
  }

  static osm::OsmData* data_;
  static skeleton::Skeleton* sk_;
  static sim::SimWorld* world_;
};
osm::OsmData* OracleSim::data_ = nullptr;
skeleton::Skeleton* OracleSim::sk_ = nullptr;
sim::SimWorld* OracleSim::world_ = nullptr;

TEST_F(OracleSim, WestOaklandRoads) {
  // Roads with at least 60 m to explore, every k-th by id so the sample is spread over the map.
  std::vector<const skeleton::AtomicRoad*> roads;
  for (const auto& r : sk_->roads()) {
    if (r.s_end - r.s_begin >= 60.0) roads.push_back(&r);
  }
  ASSERT_GE(roads.size(), 8u);
  const int want = std::getenv("LANEMAP_ORACLE_ALL") ? static_cast<int>(roads.size()) : 10;
  const size_t stride = std::max<size_t>(1, roads.size() / want);
  std::vector<RoadScore> scores;
  for (size_t i = 0; i < roads.size() && static_cast<int>(scores.size()) < want; i += stride) {
    scores.push_back(score(*roads[i], ExplorerOptions{}));
  }
  int stations = 0, agree = 0;
  std::vector<double> rms;
  for (const auto& sc : scores) {
    stations += sc.stations;
    agree += sc.count_agree;
    rms.insert(rms.end(), sc.lane_rms.begin(), sc.lane_rms.end());
  }
  std::sort(rms.begin(), rms.end());
  const double median = rms.empty() ? INFINITY : rms[rms.size() / 2];
  std::printf("%zu roads: lane count right at %d/%d stations (%.0f %%); %zu lanes, RMS median %.3f m, max %.3f m\n",
              scores.size(), agree, stations, 100.0 * agree / std::max(1, stations), rms.size(), median,
              rms.empty() ? INFINITY : rms.back());
  // Thresholds. With oracle labels the error left is the algorithm's: the Frenet frame's smoothing,
  // the 0.1 m grid, the particle spread in a lane and the taper of a turn pocket, where the truth
  // switches its lane count at a section boundary and the particles a few metres later (measured:
  // 98 % of stations, median 0.06 m, worst lane 0.15 m in a pocket taper). The bounds leave room for
  // seeds and world changes but stay below the paper's camera-only RMS (0.25 m) for every lane.
  EXPECT_GE(agree, 0.90 * stations);
  EXPECT_LT(median, 0.10);
  EXPECT_LT(rms.back(), 0.25);
}

}  // namespace
