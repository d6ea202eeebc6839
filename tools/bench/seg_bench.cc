// Segmenter throughput (issue 7): frames/s of the shipped model (config/segmenter.yaml) on 640x360
// simulated camera frames, JPEG decode + resize + OpenCV DNN forward + bilinear score upsampling +
// argmax, with OpenCV limited to one thread and to two (cv::setNumThreads). The baseline beside it,
// same run: the network run whole by OpenCV (`depth_to_space: model`), whose labels must be the same
// pixel for pixel (counted). Issue 17's target: 25 ms a frame on one core. Then where the
// network's time goes on one thread: OpenCV's own per-layer times (Net::getPerfProfile), summed by
// the model's top-level module (tools/seg/model.py: enc1..enc4, dec3..dec1, head; up and Concat are
// the decoder's upsampling and skip joins), which is what a smaller network must cut. Prints
// figures only.
//   lanemap-bench-seg [--frames N] [--model FILE.onnx]
#include "core/seg/segmenter.h"
#include "core/seg/sim_frames.h"

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

using namespace lanemap;

namespace {

// "onnx_node!/dec1/dec1.0/Conv" -> "dec1", "onnx_node!/up_2/Resize" -> "up", "onnx_node!/Concat_2" -> "Concat".
std::string moduleOf(const std::string& layer) {
  const size_t bang = layer.find("!/");
  std::string m = bang == std::string::npos ? layer : layer.substr(bang + 2);
  m = m.substr(0, m.find('/'));
  const size_t us = m.rfind('_');
  if (us != std::string::npos && us + 1 < m.size() && m.find_first_not_of("0123456789", us + 1) == std::string::npos) m.resize(us);
  return m;
}

// The network run whole by OpenCV on one thread, `runs` times on a random input of its size:
// milliseconds per forward pass by module, in the order the modules first run.
void printLayerProfile(const std::string& onnx, int width, int height, int runs) {
  cv::setNumThreads(1);
  cv::dnn::Net net = cv::dnn::readNetFromONNX(onnx);
  cv::Mat blob(std::vector<int>{1, 3, height, width}, CV_32F);
  cv::randu(blob, -2.0, 2.0);
  const std::vector<std::string> names = net.getLayerNames();
  std::vector<double> sum;
  for (int k = 0; k < runs + 1; ++k) {
    net.setInput(blob);
    net.forward();
    std::vector<double> t;
    net.getPerfProfile(t);
    if (k == 0) continue;  // warm-up
    sum.resize(t.size(), 0.0);
    for (size_t i = 0; i < t.size(); ++i) sum[i] += t[i];
  }
  const double to_ms = 1e3 / cv::getTickFrequency() / runs;
  std::vector<std::pair<std::string, double>> modules;
  double total = 0.0;
  for (size_t i = 0; i < sum.size() && i < names.size(); ++i) {
    const std::string m = moduleOf(names[i]);
    auto it = std::find_if(modules.begin(), modules.end(), [&](const auto& e) { return e.first == m; });
    if (it == modules.end()) it = modules.insert(modules.end(), {m, 0.0});
    it->second += sum[i] * to_ms;
    total += sum[i] * to_ms;
  }
  std::printf("   where the network's time goes, one thread, OpenCV's per-layer times (mean of %d runs, %.1f ms in all):\n", runs, total);
  for (const auto& [m, ms] : modules) {
    if (ms < 0.05) continue;
    std::printf("     %-14s %6.2f ms  %4.1f %%%s\n", m.c_str(), ms, 100.0 * ms / total,
                m == "DepthToSpace" ? "  (the shipped settings do it in the segmenter, not in OpenCV)" : "");
  }
}

}  // namespace

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
    seg::ModelConfig whole_mc = mc;
    whole_mc.shuffle_in_segmenter = false;
    seg::Segmenter model(mc), whole(whole_mc);
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
    std::printf("   pixel shuffle: %s\n", model.shuffleBlock() > 0
                                               ? ("the segmenter's (block " + std::to_string(model.shuffleBlock()) + ")").c_str()
                                               : "the model's (no trailing DepthToSpace found)");
    for (int threads : {1, 2}) {
      cv::setNumThreads(threads);
      struct Run {
        seg::Segmenter* seg;
        const char* what;
        double decode_s = 0.0, total_s = 0.0;
      };
      Run runs[2] = {{&whole, "OpenCV runs the whole network (baseline)"}, {&model, "shipped settings"}};
      for (Run& r : runs) r.seg->segment(frames[0].bgr);  // warm-up
      long differ = 0;
      for (int i = 0; i < n; ++i) {
        const auto& f = frames[static_cast<size_t>(i) % frames.size()];
        cv::Mat out[2];
        for (int k = 0; k < 2; ++k) {  // interleaved: both see the same machine load
          Run& r = runs[k];
          const auto t0 = std::chrono::steady_clock::now();
          const cv::Mat bgr = seg::decodeFrame(seg::kPixelJpeg, f.bgr.cols, f.bgr.rows, 0, f.jpeg.data(), f.jpeg.size());
          const auto t1 = std::chrono::steady_clock::now();
          out[k] = r.seg->segment(bgr);
          const auto t2 = std::chrono::steady_clock::now();
          r.decode_s += std::chrono::duration<double>(t1 - t0).count();
          r.total_s += std::chrono::duration<double>(t2 - t0).count();
        }
        if (out[0].empty() || out[1].empty()) return 1;
        differ += cv::countNonZero(out[0] != out[1]);
      }
      for (const Run& r : runs)
        std::printf("   %d thread%s: %.1f frames/s (%.1f ms/frame: JPEG decode %.1f ms, segmentation %.1f ms)  %s%s\n",
                    threads, threads == 1 ? " " : "s", n / r.total_s, 1e3 * r.total_s / n, 1e3 * r.decode_s / n,
                    1e3 * (r.total_s - r.decode_s) / n, r.what,
                    threads == 1 && r.seg == &model ? " (issue 17's target: <= 25 ms a frame on one core)" : "");
      std::printf("   %d thread%s: %ld of %ld label pixels differ between the two\n", threads, threads == 1 ? " " : "s",
                  differ, static_cast<long>(n) * frames[0].bgr.cols * frames[0].bgr.rows);
    }
    printLayerProfile(mc.path, mc.input_width, mc.input_height, 10);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-bench-seg: %s\n", e.what());
    return 2;
  }
}
