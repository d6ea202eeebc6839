// lanemap-lidar-vlp16: the Velodyne VLP-16 (and VLP-32C / HDL-32E) driver. Receives data packets
// on UDP 2368 (position packets on 8308 are counted), bundles each rotation into LIDAR_PACKETS,
// optionally decodes it into LIDAR_POINTS, and counts rejected packets by reason in STATUS.
// `--pcap FILE [--rate-scale X]` replays a capture (pcap or raw 1206-byte payloads) through the
// same path and exits at its end.
#include "drivers/lidar_vlp16/lidar_app.h"
#include "processes/framework/stop_signals.h"
#include "processes/framework/process.h"

#include <iostream>
#include <optional>

int main(int argc, char** argv) {
  lanemap::Process process("lidar_vlp16");
  lanemap::drivers::LidarSettings cli;  // command-line overrides of the config
  std::optional<std::string> model, address;
  std::optional<int> port, position_port;
  bool publish_points = false;
  auto& app = process.cli();
  app.add_option("--pcap", cli.pcap,
                 "replay a capture (pcap or raw 1206-byte payloads), then exit");
  app.add_option("--rate-scale", cli.rate_scale,
                 "replay speed: 1 real time, 0 as fast as possible");
  app.add_flag("--keep-capture-time", cli.keep_capture_time,
               "stamp replayed packets with capture time");
  app.add_option("--model", model, "vlp16 | vlp32c | hdl32e | auto (default: config, vlp16)");
  app.add_option("--address", address, "address to bind (default: config, 0.0.0.0)");
  app.add_option("--port", port, "UDP data port (default: config, 2368)");
  app.add_option("--position-port", position_port, "UDP position port, 0 = none (default 8308)");
  app.add_flag("--publish-points", publish_points, "also publish decoded LIDAR_POINTS");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;

  try {
    lanemap::drivers::LidarSettings settings;
    settings.load(process.settings());
    process.settings().finish();
    settings.pcap = cli.pcap;
    if (app.count("--rate-scale")) settings.rate_scale = cli.rate_scale;
    settings.keep_capture_time = settings.keep_capture_time || cli.keep_capture_time;
    if (model) settings.model = *model;
    if (address) settings.address = *address;
    if (port) settings.data_port = *port;
    if (position_port) settings.position_port = *position_port;
    settings.publish_points = settings.publish_points || publish_points;
    settings.validate();
    lanemap::setStopSignalsBlocked(true);  // only the driver's worker thread takes them
    lanemap::drivers::LidarApp lidar(process, settings);
    const int rc = process.spin();
    return process.counters().get("replay_errors") > 0 ? 1 : rc;  // e.g. a pcap cut mid-record
  } catch (const std::exception& e) {
    std::cerr << "lidar_vlp16: " << e.what() << "\n";
    return 2;
  }
}
