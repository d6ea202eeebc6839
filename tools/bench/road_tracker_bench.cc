// Road tracker and skeleton queries: how many poses a second they take, on the bundled street
// networks (West Oakland, and Monaco for a whole city). Prints figures, asserts nothing.
//   lanemap-bench-road-tracker [osm files...]
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/road_tracker.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace lanemap;
using Clock = std::chrono::steady_clock;

namespace {

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void bench(const std::string& path) {
  auto t0 = Clock::now();
  const osm::OsmData data = osm::readOsm(path);
  const double t_read = secondsSince(t0);
  t0 = Clock::now();
  const auto sk = skeleton::Skeleton::build(data);
  const double t_build = secondsSince(t0);
  double total_length = 0.0;
  for (const auto& r : sk.roads()) total_length += r.length;
  std::printf("%s\n  read %.2f s, skeleton %.2f s: %zu atomic roads (%.1f km), %zu intersections\n", path.c_str(),
              t_read, t_build, sk.roads().size(), total_length / 1000.0, sk.intersections().size());

  // nearestRoads at random points on the roads, 3 m off, with a heading.
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 3.0);
  std::vector<std::pair<Eigen::Vector2d, double>> queries;
  for (int i = 0; i < 200000; ++i) {
    const auto& r = sk.roads()[rng() % sk.roads().size()];
    const double s = std::uniform_real_distribution<double>(0.0, r.length)(rng);
    const Eigen::Vector2d t = sk.tangentAt(r, s);
    queries.push_back({sk.pointAt(r, s) + Eigen::Vector2d(noise(rng), noise(rng)), std::atan2(t.y(), t.x())});
  }
  t0 = Clock::now();
  size_t found = 0;
  for (const auto& [p, h] : queries) found += sk.nearestRoads(p, 8.0, h).size();
  const double t_q = secondsSince(t0);
  std::printf("  nearestRoads(8 m, heading): %.2f us per query (%zu queries, %.1f matches each)\n",
              1e6 * t_q / queries.size(), queries.size(), double(found) / queries.size());
  t0 = Clock::now();
  size_t in_roi = 0;
  for (const auto& q : queries) in_roi += sk.intersectionContaining(q.first) != nullptr;
  std::printf("  intersectionContaining: %.2f us per query (%zu of %zu in an ROI)\n",
              1e6 * secondsSince(t0) / queries.size(), in_roi, queries.size());

  // The tracker on 100 Hz poses driven along every road in turn (10 m/s, 1.5 m noise).
  tracking::RoadTracker tracker(sk);
  int64_t utime = 1767225600000000;
  size_t poses = 0, events = 0;
  t0 = Clock::now();
  for (const auto& r : sk.roads()) {
    for (double s = 0.0; s < r.length; s += 0.1) {
      const Eigen::Vector2d t = sk.tangentAt(r, s);
      tracking::PoseInput in;
      in.utime = (utime += 10000);
      in.position = sk.pointAt(r, s) + Eigen::Vector2d(0.5 * noise(rng), 0.5 * noise(rng));
      in.heading = std::atan2(t.y(), t.x());
      in.velocity = 10.0 * t;
      events += tracker.update(in).size();
      ++poses;
    }
  }
  const double t_t = secondsSince(t0);
  std::printf("  RoadTracker::update: %.2f us per pose (%zu poses, %zu events): %.0fx the 100 Hz pose rate\n",
              1e6 * t_t / poses, poses, events, poses / t_t / 100.0);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) files.push_back(argv[i]);
  if (files.empty()) files = {LANEMAP_DATA_DIR "/osm/west-oakland.osm", LANEMAP_DATA_DIR "/osm/monaco.osm.pbf"};
  try {
    for (const auto& f : files) bench(f);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-bench-road-tracker: %s\n", e.what());
    return 2;
  }
  return 0;
}
