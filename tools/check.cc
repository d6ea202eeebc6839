// lanemap-check: the requirements of Autoware's Lanelet2 format that Lanelet2's own validator does
// not check (core/io/map_check.h lists them), each with pass or fail and the offending ids.
//
//   lanemap-check MAP.osm [--autoware]      # exit 0: every rule passes; 1: a rule fails; 2: bad input
#include "core/io/map_check.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  CLI::App app{"Checks a Lanelet2 map against Autoware's map requirements that lanelet2_validate does not check:\n"
               "ele on every node, lanelet tags (subtype, location, one_way, speed_limit), lane_change on lines\n"
               "between same-direction lanes, shared borders, bounds that share no node, centre lines inside\n"
               "their lanelet, one lanelet per intersection path, regulatory elements (stop signs, give way, traffic\n"
               "lights) referenced by a lanelet with a stop line as ref_line; with --autoware also turn_direction,\n"
               "stop lines referenced by a regulatory element, crosswalk lanelets referred to by Autoware's crosswalk\n"
               "element and map_projector_info.yaml. Exit status 1 on any failure."};
  std::string path;
  lanemap::io::MapCheckOptions options;
  size_t max_ids = 20;
  app.add_option("map", path, "Lanelet2 map (.osm)")->required();
  app.add_flag("--autoware", options.autoware, "also Autoware's layout: turn_direction, stop line and crosswalk regulatory elements, map_projector_info.yaml");
  app.add_option("--max-ids", max_ids, "offending ids printed per rule")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const auto results = lanemap::io::checkLanelet2Map(path, options);
    int failed = 0;
    for (const auto& r : results) {
      const char* verdict = !r.applicable ? "n/a " : r.passed ? "pass" : "FAIL";
      std::printf("%s  %-34s %s", verdict, r.name.c_str(), r.what.c_str());
      if (!r.offenders.empty()) {
        std::printf(": %zu:", r.offenders.size());
        for (size_t i = 0; i < r.offenders.size() && i < max_ids; ++i) std::printf(" %lld", static_cast<long long>(r.offenders[i]));
        if (r.offenders.size() > max_ids) std::printf(" ...");
      }
      std::printf("\n");
      failed += r.passed ? 0 : 1;
    }
    std::printf("%d of %zu requirements failed\n", failed, results.size());
    return failed ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-check: %s\n", e.what());
    return 2;
  }
}
