// lanemap-pose-nmea: the GNSS (or GNSS/INS) pose driver. Reads NMEA 0183 (GGA, RMC, HDT, VTG) from
// a serial device, a UDP port or a file (`--file F [--realtime]`), verifies checksums, and
// publishes one POSE (pose_t) per fix epoch; rejected lines are counted by reason in STATUS.
#include "drivers/pose_nmea/pose_app.h"
#include "processes/framework/process.h"
#include "processes/framework/stop_signals.h"

#include <iostream>
#include <optional>

int main(int argc, char** argv) {
  lanemap::Process process("pose_nmea");
  std::optional<std::string> file, serial, source;
  std::optional<int> baud, udp_port;
  bool realtime = false;
  auto& app = process.cli();
  app.add_option("--file", file, "read NMEA from a file, publish, then exit");
  app.add_flag("--realtime", realtime, "with --file: pace the epochs by their NMEA time");
  app.add_option("--serial", serial, "read a serial device (default: config, /dev/ttyUSB0)");
  app.add_option("--baud", baud, "serial baud rate (default: config, 115200)");
  app.add_option("--udp-port", udp_port, "read NMEA datagrams on this UDP port");
  app.add_option("--source", source, "serial | udp | file (default: config, serial)");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;

  try {
    lanemap::drivers::PoseSettings settings;
    settings.load(process.settings());
    process.settings().finish();
    if (source) settings.source = *source;
    if (serial) {
      settings.source = "serial";
      settings.serial_device = *serial;
    }
    if (udp_port) {
      settings.source = "udp";
      settings.udp_port = *udp_port;
    }
    if (file) {
      settings.source = "file";
      settings.file = *file;
    }
    if (baud) settings.baud = *baud;
    settings.realtime = settings.realtime || realtime;
    settings.validate();
    // SIGINT/SIGTERM are taken by the reader thread (it unblocks them), not by spin()'s LCM wait.
    lanemap::setStopSignalsBlocked(true);
    lanemap::drivers::PoseApp pose(process, settings);
    const int rc = process.spin();
    return process.counters().get("source_errors") > 0 ? 1 : rc;  // e.g. the device was unplugged
  } catch (const std::exception& e) {
    std::cerr << "pose_nmea: " << e.what() << "\n";
    return 2;
  }
}
