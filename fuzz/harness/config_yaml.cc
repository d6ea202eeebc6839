// The processes' YAML configuration readers: the vehicle/camera model (core/camera
// CameraModel::fromYaml, mountFromYaml), the segmentation model config (core/seg
// ModelConfig::fromYaml) and the lane explorer options (core/lanes ExplorerOptions::fromYaml).
// Input: a YAML document (seeds: config/*.yaml). Property: bad values are exceptions with a
// message, never a crash or a sanitizer report.
#include "core/camera/camera_model.h"
#include "core/lanes/options.h"
#include "core/seg/segmenter.h"
#include "fuzz/fuzz_util.h"

#include <yaml-cpp/yaml.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lanemap;
  YAML::Node root;
  try {
    root = YAML::Load(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const YAML::Exception&) {
    return 0;
  }
  auto attempt = [](auto&& f) {
    try {
      f();
    } catch (const std::exception& e) {
      FUZZ_CHECK(e.what() != nullptr);
    }
  };
  attempt([&] {
    if (root.IsMap() && root["explorer"]) (void)lanes::ExplorerOptions::fromYaml(root["explorer"]);
  });
  attempt([&] {
    if (root.IsMap() && root["camera"] && root["camera"].IsMap() && root["camera"]["mount"])
      (void)camera::mountFromYaml(root["camera"]["mount"], "camera.mount");
  });
  for (const char* key : {"camera", "front_camera"}) {
    attempt([&] {
      if (root.IsMap() && root[key]) {
        const auto cam = camera::CameraModel::fromYaml(root[key]);
        (void)cam;
      }
    });
  }
  attempt([&] { (void)camera::CameraModel::fromYaml(root); });
  attempt([&] { (void)camera::mountFromYaml(root, "fuzz"); });
  attempt([&] { (void)seg::ModelConfig::fromYaml(root, "/nonexistent"); });
  attempt([&] {
    if (root.IsMap() && root["model"]) (void)seg::ModelConfig::fromYaml(root["model"], "/nonexistent");
  });
  attempt([&] { (void)lanes::ExplorerOptions::fromYaml(root); });
  return 0;
}
