// lanemap-segmenter: CAMERA_FRONT in, the 10 lane-relative classes out on SEMANTIC_FRONT (METHOD.md
// section 2); --oracle republishes the simulator's truth labels.
// The process: processes/segmenter/segmenter_app.h (what it does, its STATUS counters).
//
//   lanemap-segmenter --config config/segmenter.yaml [--model FILE.onnx] [--oracle]
#include "processes/segmenter/segmenter_app.h"

using namespace lanemap;
using namespace lanemap::segmenter_app;

int main(int argc, char** argv) {
  Process process("segmenter");
  bool oracle_flag = false;
  std::string model_flag;
  process.cli().add_flag("--oracle", oracle_flag, "republish SEMANTIC_FRONT_TRUTH as SEMANTIC_FRONT (no model)");
  process.cli().add_option("--model", model_flag, "ONNX model (overrides model.path of the config)");
  std::string log_in, log_out;
  process.cli().add_option("--log-in", log_in, "offline: segment every CAMERA_FRONT frame of this LCM log ...");
  process.cli().add_option("--log-out", log_out, "... into this copy of it (with SEMANTIC_FRONT added), then exit");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;
  try {
    const Settings s = SegmenterSettings::fromYaml(process.settings(), model_flag);
    process.settings().finish();
    const bool oracle = oracle_flag || s.oracle;
    if (oracle) {
      std::cerr << "segmenter: oracle mode: " << s.truth_channel << " -> " << s.output_channel << "\n";
      OracleApp app(process, s);
      process.setState("oracle");
      return process.spin();
    }
    if (s.threads > 0) cv::setNumThreads(s.threads);
    if (!s.model) throw std::runtime_error("no model: give --model FILE.onnx or a model: block (its path) in the config");
    const seg::ModelConfig& mc = *s.model;
    auto model = std::make_unique<seg::Segmenter>(mc);
    std::cerr << "segmenter: model " << mc.path << " (" << model->modelClasses() << " classes, input "
              << mc.input_width << "x" << mc.input_height << "), " << s.camera_channel << " -> "
              << s.output_channel << ", queue " << s.queue_frames << "\n";
    if (!log_in.empty() || !log_out.empty()) {
      if (log_in.empty() || log_out.empty()) throw std::runtime_error("--log-in and --log-out go together");
      segmentLog(log_in, log_out, s, *model);
      return 0;
    }
    SegmenterApp app(process, s, std::move(model));
    process.setState("running");
    return process.spin();
  } catch (const std::exception& e) {
    std::cerr << "segmenter: error: " << e.what() << "\n";
    return 2;
  }
}
