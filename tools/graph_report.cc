// lanemap-graph-report: how a live run of the graph went, from the recording beside it
// (config/launch/demo.yaml writes ${store}/graph.lcmlog: STATUS, ROAD_EVENT, BEV_ROAD, LANE_MAP,
// POSE): per process CPU share and latency p50/p99, frame-to-BEV latency, every drop counter and
// hand-over loss, and how long after the drive's end the map was complete
// (processes/framework/graph_report.h says how each figure is taken).
//
//   lanemap-graph-report --log STORE/graph.lcmlog [--drive-log DRIVE/drive.lcmlog] [--fail-on-drop]
// Exit status: 0; 1 with --fail-on-drop when a frame was dropped or lost; 2 on an error.
#include "processes/framework/channels.h"
#include "processes/framework/graph_report.h"

#include <CLI/CLI.hpp>

#include <iostream>

int main(int argc, char** argv) {
  CLI::App app{"Drops, latency, CPU and map completion of a live graph run, from its recording"};
  std::string log, drive_log, labels = lanemap::channels::kSemanticFront;
  bool fail_on_drop = false;
  app.add_option("--log", log, "the recording: STATUS, LANE_MAP, BEV_ROAD, ROAD_EVENT, POSE (demo.yaml's graph.lcmlog)")->required();
  app.add_option("--drive-log", drive_log, "the drive log that was played (to check every message arrived)");
  app.add_option("--labels", labels, "the bev_builder's semantic channel")->capture_default_str();
  app.add_flag("--fail-on-drop", fail_on_drop, "exit 1 when a frame was dropped or lost");
  CLI11_PARSE(app, argc, argv);
  try {
    const lanemap::GraphReport r = lanemap::readGraphReport(log, drive_log, labels);
    lanemap::printGraphReport(r, std::cout);
    return fail_on_drop && r.framesLost() > 0 ? 1 : 0;
  } catch (const std::exception& e) {
    std::cerr << "lanemap-graph-report: " << e.what() << "\n";
    return 2;
  }
}
