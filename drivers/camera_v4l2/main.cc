// lanemap-camera-v4l2: the front camera driver. V4L2 mmap streaming from a USB/UVC (or any V4L2)
// camera; MJPEG frames passed through as JPEG, YUYV frames converted and JPEG-encoded; the kernel's
// buffer timestamp as utime; sequence gaps counted as drops; CAMERA_FRONT (lanemap::image_t,
// PIXEL_FORMAT_JPEG). A missing or unplugged camera is a clear error, or with `reconnect: true` a
// wait with back-off until it is back.
//
//   lanemap-camera-v4l2 --config config/camera_v4l2.yaml [--device /dev/video2] [--list]
#include "drivers/camera_v4l2/camera_app.h"
#include "processes/framework/stop_signals.h"
#include "processes/framework/process.h"

#include <iostream>
#include <optional>

int main(int argc, char** argv) {
  lanemap::Process process("camera_v4l2");
  std::optional<std::string> device, format;
  std::optional<uint32_t> width, height;
  std::optional<double> fps;
  std::optional<bool> reconnect;
  bool list = false;
  auto& app = process.cli();
  app.add_option("--device", device, "V4L2 device (default: config, /dev/video0)");
  app.add_option("--format", format, "mjpeg | yuyv | auto (default: config, auto)");
  app.add_option("--width", width, "image width asked for (the driver may choose another)");
  app.add_option("--height", height, "image height asked for");
  app.add_option("--fps", fps, "frame rate asked for (S_PARM)");
  app.add_option("--reconnect", reconnect, "true: wait for a missing or unplugged camera; false: exit 2");
  app.add_flag("--list", list, "list the V4L2 devices and their pixel formats, then exit");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;
  if (list) {
    lanemap::drivers::listDevices(std::cout);
    return 0;
  }
  try {
    lanemap::drivers::CameraSettings settings;
    settings.load(process.settings());
    process.settings().finish();
    if (device) settings.device = *device;
    if (format) settings.capture.format = *format;
    if (width) settings.capture.width = *width;
    if (height) settings.capture.height = *height;
    if (fps) settings.capture.fps = *fps;
    if (reconnect) settings.capture.reconnect = *reconnect;
    settings.capture.validate();
    lanemap::setStopSignalsBlocked(true);  // only the capture thread takes them
    lanemap::drivers::CameraApp camera(process, settings);
    const int rc = process.spin();
    return camera.exitCode() != 0 ? camera.exitCode() : rc;
  } catch (const std::exception& e) {
    std::cerr << "camera_v4l2: " << e.what() << "\n";
    return 2;
  }
}
