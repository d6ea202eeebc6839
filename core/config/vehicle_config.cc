#include "core/config/vehicle_config.h"

namespace lanemap::config {

VehicleConfig VehicleConfig::fromYaml(const YamlReader& r) {
  const YamlReader cam = r.section("camera");
  VehicleConfig v(camera::CameraModel::fromYaml(cam));
  if (cam.read("frame_rate_hz", v.camera_frame_rate_hz) && !(v.camera_frame_rate_hz > 0.0)) {
    cam.fail("frame_rate_hz", "must be > 0");
  }
  if (cam.read("jpeg_quality", v.camera_jpeg_quality) && (v.camera_jpeg_quality < 0 || v.camera_jpeg_quality > 100)) {
    cam.fail("jpeg_quality", "must be within [0, 100]");
  }
  v.lidar = sim::LidarScannerOptions::fromYaml(r.section("lidar"));
  return v;
}

VehicleConfig VehicleConfig::fromYamlFile(const std::string& path) {
  const YamlReader r = YamlReader::loadFile(path);
  VehicleConfig v = fromYaml(r);
  r.finish();
  return v;
}

}  // namespace lanemap::config
