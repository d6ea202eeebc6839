// The cost of closing one road against the size of the map (issue 14: "adding or updating one road
// costs the same in a store of 100 roads as in one of 3,000"). What the lane mapper does when a
// road closes (processes/lane_mapper/lane_mapper_app.h): the road's own file, its lanes into the
// kept map (core/mapping/map_assembler.h: the two intersections at its ends rebuilt); and what an
// export of the whole map costs (lane_map.osm: every road and intersection assembled and written),
// which the lane mapper does after every road (export_interval_s 0) or at most once per
// export_interval_s. Beside it, the whole rebuild the lane mapper did before (every intersection
// built again per road). Over Monaco's skeleton, the first N atomic roads in breadth-first order
// from one road (so they join at junctions) with two straight-line lanes each (no BEV, no
// exploration: that part costs the same at any store size). Prints, per N, the milliseconds of
// each (wall clock: the writes are fsynced, so a busy disk shows) and the ratio to the smallest
// store's, measured in the same run. Asserts nothing.
//   lanemap-bench-store [--sizes 100,300,1000,3000]
#include "core/io/lanelet2.h"
#include "core/intersections/intersections.h"
#include "core/io/speed_limits.h"
#include "core/mapping/map_assembler.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/synthetic_lanes.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace lanemap;

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double cpuMs() { return 1e3 * static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

}  // namespace

int main(int argc, char** argv) {
  std::vector<size_t> sizes{100, 300, 1000, 3000};
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--sizes") {
      sizes.clear();
      std::stringstream ss(argv[i + 1]);
      for (std::string n; std::getline(ss, n, ',');) sizes.push_back(std::stoul(n));
    }
  }
  const std::string osm_path = std::string(LANEMAP_DATA_DIR) + "/osm/monaco.osm.pbf";
  const osm::OsmData data = osm::readOsm(osm_path);
  const skeleton::Skeleton sk = skeleton::Skeleton::build(data);
  // Roads in breadth-first order over the junctions from the first road.
  std::vector<const skeleton::AtomicRoad*> order;
  std::set<int64_t> seen_roads, seen_nodes;
  std::deque<int64_t> nodes{sk.roads().front().from};
  seen_nodes.insert(nodes.front());
  while (!nodes.empty()) {
    const auto* in = sk.intersection(nodes.front());
    nodes.pop_front();
    if (!in) continue;
    for (const auto& list : {in->outgoing, in->incoming}) {
      for (const int64_t id : list) {
        const auto* r = sk.road(id);
        if (!r || !seen_roads.insert(id).second) continue;
        order.push_back(r);
        for (const int64_t n : {r->from, r->to}) {
          if (seen_nodes.insert(n).second) nodes.push_back(n);
        }
      }
    }
  }
  std::printf("== cost of closing one road against the map's size (Monaco: %zu atomic roads, %zu reached from road %lld)\n",
              sk.roads().size(), order.size(), static_cast<long long>(sk.roads().front().id));
  std::printf("  %7s %9s %10s %9s %9s %8s | %10s %9s %8s | %12s %8s\n", "ROADS", "LANELETS", "ROAD_FILE", "JUNCTIONS", "CLOSE_MS",
              "x_FIRST", "EXPORT_MS", "(CPU_MS)", "x_FIRST", "REBUILD_MS", "x_FIRST");
  const auto tmp = std::filesystem::temp_directory_path() / ("lanemap-bench-store-" + std::to_string(::getpid()));
  std::filesystem::create_directories(tmp);
  double first_close = 0.0, first_export = 0.0, first_rebuild = 0.0;
  io::Lanelet2WriteOptions write_options;  // as the lane mapper writes: OSM maxspeed per road
  write_options.speed_limit_kmh_by_road = io::speedLimitsKmh(sk);
  for (const size_t n_wanted : sizes) {
    const size_t n = std::min(n_wanted, order.size());
    if (n < 2) continue;
    mapping::MapAssembler assembler(sk, {}, data.restrictions);
    for (size_t i = 0; i + 1 < n; ++i) assembler.setRoad(order[i]->id, lanemap::testing::twoStraightLanes(sk, *order[i]));
    assembler.update();
    // The road that closes now: its file and its intersections; then the export; then (as before)
    // every intersection built again. 3 times, the best kept.
    double road_ms = 1e300, junctions_ms = 1e300, export_ms = 1e300, export_cpu_ms = 1e300, rebuild_ms = 1e300;
    size_t lanelets = 0;
    for (int rep = 0; rep < 3; ++rep) {
      auto t0 = std::chrono::steady_clock::now();
      map::LaneMap lanes = lanemap::testing::twoStraightLanes(sk, *order[n - 1]);
      io::writeLanelet2(lanes, (tmp / "road.osm").string(), write_options);
      road_ms = std::min(road_ms, msSince(t0));
      t0 = std::chrono::steady_clock::now();
      assembler.setRoad(order[n - 1]->id, lanes);
      assembler.update();
      junctions_ms = std::min(junctions_ms, msSince(t0));
      t0 = std::chrono::steady_clock::now();
      const double c0 = cpuMs();
      const map::LaneMap all = assembler.map();
      io::writeLanelet2(all, (tmp / "lane_map.osm").string(), write_options);
      export_ms = std::min(export_ms, msSince(t0));
      export_cpu_ms = std::min(export_cpu_ms, cpuMs() - c0);
      lanelets = all.lanelets.size();
      t0 = std::chrono::steady_clock::now();
      const auto rebuilt = intersections::buildIntersections(sk, assembler.roads(), {}, data.restrictions);
      rebuild_ms = std::min(rebuild_ms, msSince(t0));
      if (rebuilt.size() != assembler.intersections().size()) {
        std::fprintf(stderr, "lanemap-bench-store: %zu intersections kept, %zu rebuilt: the kept map is not the rebuilt one\n",
                     assembler.intersections().size(), rebuilt.size());
        return 1;
      }
    }
    const double close = road_ms + junctions_ms;
    if (first_close == 0.0) {
      first_close = close;
      first_export = export_ms;
      first_rebuild = rebuild_ms;
    }
    std::printf("  %7zu %9zu %10.1f %9.1f %9.1f %8.1f | %10.1f %9.1f %8.1f | %12.1f %8.1f\n", n, lanelets, road_ms, junctions_ms, close,
                close / first_close, export_ms, export_cpu_ms, export_ms / first_export, rebuild_ms, rebuild_ms / first_rebuild);
  }
  std::filesystem::remove_all(tmp);
  std::printf("  (wall-clock ms, best of 3. CLOSE_MS: the road's file plus its intersections, what the lane mapper spends per\n"
              "   road besides exploring it; EXPORT_MS: lane_map.osm assembled and written (atomic, fsynced), CPU_MS its CPU time;\n"
              "   REBUILD_MS: every intersection built again, what each road cost before the map was kept between roads)\n");
  return 0;
}
