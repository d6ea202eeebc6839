// Lane exploration (core/lanes/explorer.h): particle-filter time per 100 m of road at N = 500 (the
// paper's value) and N = 2000, on a painted 700 m road with three lanes and a turn pocket, and on
// a 220 m curve. Prints figures, asserts nothing.
//   lanemap-bench-lanes
#include "core/lanes/explorer.h"
#include "tests/lanes/synthetic_bev.h"

#include <chrono>
#include <cstdio>

using namespace lanemap;
using namespace lanemap::lanes;
using namespace lanemap::lanes::testing;

namespace {

Layout threeLanes(double length, double radius) {
  Layout L;
  L.ref.length = length;
  L.ref.radius = radius;
  const double e[] = {5.1, 1.7, -1.7, -5.1};
  L.lines.push_back({ramp(length - 60, length - 45, e[0], e[0] + 3.3), -1e9, 1e9, Line::kSolid, false});
  L.lines.push_back({constant(e[0]), length - 60, 1e9, Line::kDashed, true});
  L.lines.push_back({constant(e[1]), -1e9, 1e9, Line::kDashed, true});
  L.lines.push_back({constant(e[2]), -1e9, 1e9, Line::kDashed, true});
  L.lines.push_back({constant(e[3]), -1e9, 1e9, Line::kSolid, false});
  L.lines.push_back({ramp(length - 60, length - 45, e[0] + 0.5, e[0] + 3.8), -1e9, 1e9, Line::kCurb, false});
  L.lines.push_back({constant(e[3] - 0.5), -1e9, 1e9, Line::kCurb, false});
  L.areas.push_back({constant(e[3] - 0.5), ramp(length - 60, length - 45, e[0] + 0.5, e[0] + 3.8)});
  return L;
}

void bench(const char* name, const Layout& L) {
  auto t0 = std::chrono::steady_clock::now();
  const bev::BevGrid grid = paint(L);
  const double paint_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RoadGeometry road;
  road.road_id = 1;
  road.polyline = L.ref.polyline();
  road.s_begin = 3.0;
  road.s_end = L.ref.length - 3.0;
  const double hm = (road.s_end - road.s_begin) / 100.0;
  std::printf("%s: %.0f m explored, grid %zu tiles (%.1f MiB, painted in %.2f s)\n", name, road.s_end - road.s_begin,
              grid.tileCount(), grid.memoryBytes() / 1048576.0, paint_s);
  for (int n : {500, 2000}) {
    ExplorerOptions o;
    o.num_particles = n;
    double filter = 1e9, total = 1e9;
    ExplorationResult res;
    for (int rep = 0; rep < 3; ++rep) {  // best of 3
      t0 = std::chrono::steady_clock::now();
      res = exploreRoad(grid, road, o);
      total = std::min(total, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      filter = std::min(filter, res.stats.filter_s);
    }
    std::printf("  N = %4d: particle filter %.1f ms per 100 m (%d steps, %.2f us per particle-step); whole "
                "exploration %.1f ms per 100 m (raster %.0f ms, fit %.1f ms); %zu lanes\n",
                n, 1e3 * filter / hm, res.stats.steps, 1e6 * filter / std::max<int64_t>(1, res.stats.particle_steps),
                1e3 * total / hm, 1e3 * res.stats.raster_s, 1e3 * res.stats.fit_s, res.lanes.size());
  }
}

}  // namespace

int main() {
  bench("straight road, 3 lanes + turn pocket", threeLanes(700.0, 0.0));
  bench("curve R = 150 m, 3 lanes + turn pocket", threeLanes(220.0, 150.0));
  return 0;
}
