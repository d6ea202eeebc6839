// The V4L2 camera driver's application object: its settings (config/camera_v4l2.yaml, overridable
// on the command line) and CameraApp, which runs core/camera's capture loop on a worker thread and
// publishes every frame as lanemap::image_t (JPEG) on CAMERA_FRONT, with the loop's counters in
// STATUS.
#pragma once

#include "core/camera/v4l2_capture.h"
#include "core/camera/v4l2_device.h"
#include "processes/framework/channels.h"
#include "processes/framework/process.h"

#include <atomic>
#include <string>
#include <thread>

namespace lanemap::drivers {

struct CameraSettings {
  std::string device = "/dev/video0";
  std::string channel = channels::kCameraFront;
  camera::CaptureSettings capture;

  // Reads the keys present in `config` (unknown keys are an error naming them). Throws
  // std::runtime_error naming the key on a wrong type.
  // The driver's config (strict: the caller's finish() refuses unknown keys).
  void load(const config::YamlReader& config);
};

class CameraApp {
 public:
  // Starts the capture thread. A device that fails for good (missing with reconnect off, not a
  // camera, no usable format) stops the process: exitCode() is then 2.
  CameraApp(Process& process, CameraSettings settings);
  ~CameraApp();
  int exitCode() const { return exit_code_.load(); }

 private:
  void publish(const camera::CapturedFrame& frame);
  void updateCounters();

  Process& process_;
  CameraSettings settings_;
  camera::V4l2Device device_;
  camera::CameraCapture capture_;
  std::atomic<bool> stop_{false};
  std::atomic<int> exit_code_{0};
  std::thread worker_;
};

// Prints the V4L2 devices present, their card names and pixel formats (for --list).
void listDevices(std::ostream& out);

}  // namespace lanemap::drivers
