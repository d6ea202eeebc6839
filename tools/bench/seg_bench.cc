// Segmenter throughput (issue 7): frames/s of the shipped model (config/segmenter.yaml) on 640x360
// simulated camera frames, JPEG decode + resize + OpenCV DNN forward + bilinear score upsampling +
// argmax, with OpenCV limited to one thread and to two (cv::setNumThreads). Prints figures only.
//   lanemap-bench-seg [--frames N] [--model FILE.onnx]
#include "core/seg/segmenter.h"
#include "core/seg/sim_frames.h"

#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

using namespace lanemap;

int main(int argc, char** argv) {
  const std::string root = std::string(LANEMAP_DATA_DIR) + "/..";
  int n = 40;
  std::string model_path;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--frames")) n = std::max(1, std::atoi(argv[i + 1]));
    if (!std::strcmp(argv[i], "--model")) model_path = argv[i + 1];
  }
  try {
    seg::ModelConfig mc = seg::ModelConfig::fromYaml(YAML::LoadFile(root + "/config/segmenter.yaml")["model"], root);
    if (!model_path.empty()) mc.path = model_path;
    seg::Segmenter model(mc);
    seg::SimFrameOptions o;
    o.osm_path = std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm";
    o.vehicle_yaml = root + "/config/vehicle.yaml";
    o.seed = 3;
    o.max_frames = 10;
    o.frame_spacing_s = 2.0;
    std::vector<seg::SimFrame> frames;
    seg::renderSimFrames(o, [&](const seg::SimFrame& f) {
      frames.push_back(f);
      return true;
    });
    if (frames.empty()) throw std::runtime_error("no frames rendered");
    std::printf("   model %s: input %dx%d, frames %dx%d (JPEG), %d frames per run\n", mc.path.c_str(), mc.input_width,
                mc.input_height, frames[0].bgr.cols, frames[0].bgr.rows, n);
    for (int threads : {1, 2}) {
      cv::setNumThreads(threads);
      model.segment(frames[0].bgr);  // warm-up
      double decode_s = 0.0, total_s = 0.0;
      for (int i = 0; i < n; ++i) {
        const auto& f = frames[static_cast<size_t>(i) % frames.size()];
        const auto t0 = std::chrono::steady_clock::now();
        const cv::Mat bgr = seg::decodeFrame(seg::kPixelJpeg, f.bgr.cols, f.bgr.rows, 0, f.jpeg.data(), f.jpeg.size());
        const auto t1 = std::chrono::steady_clock::now();
        const cv::Mat labels = model.segment(bgr);
        const auto t2 = std::chrono::steady_clock::now();
        decode_s += std::chrono::duration<double>(t1 - t0).count();
        total_s += std::chrono::duration<double>(t2 - t0).count();
        if (labels.empty()) return 1;
      }
      std::printf("   %d thread%s: %.1f frames/s (%.1f ms/frame: JPEG decode %.1f ms, segmentation %.1f ms)\n", threads,
                  threads == 1 ? " " : "s", n / total_s, 1e3 * total_s / n, 1e3 * decode_s / n,
                  1e3 * (total_s - decode_s) / n);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-bench-seg: %s\n", e.what());
    return 2;
  }
}
