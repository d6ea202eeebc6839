// The shipped segmentation model (models/lanesegnet.onnx, run through core/seg/segmenter.h exactly
// as lanemap-segmenter runs it) scored on simulated frames of street networks it was never trained
// on (it saw only Monaco): West Oakland, and four networks of data/osm/dev, rendered here with the
// simulator's core, with seeds used neither for the model card's validation nor by the broad
// benchmark. Per-class IoU and mIoU are printed and asserted. Plus: model/config errors, frame
// decoding errors, the drop-oldest queue, the confusion-matrix arithmetic.
#include "core/seg/segmenter.h"
#include "core/seg/sim_frames.h"
#include "processes/segmenter/frame_queue.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

using namespace lanemap;

namespace {

const std::string kRoot = LANEMAP_SOURCE_DIR;
const char* kClassNames[] = {"background", "lane_ego", "lane_left", "lane_right", "lane_left_left",
                             "lane_right_right", "dashed_line", "solid_line", "crosswalk", "curb", "stop_line"};

seg::ModelConfig shippedModel() {
  return seg::ModelConfig::fromYaml(YAML::LoadFile(kRoot + "/config/segmenter.yaml")["model"], kRoot);
}

// One rendered West Oakland camera frame (not a training network).
cv::Mat oneFrame(uint64_t seed) {
  seg::SimFrameOptions o;
  o.osm_path = kRoot + "/data/osm/west-oakland.osm";
  o.vehicle_yaml = kRoot + "/config/vehicle.yaml";
  o.seed = seed;
  o.max_frames = 1;
  o.frame_spacing_s = 5.0;
  cv::Mat img;
  seg::renderSimFrames(o, [&](const seg::SimFrame& f) {
    img = f.bgr;
    return false;
  });
  return img;
}

// The shipped model scored on frames rendered here with the simulator's core (varied light and
// camera, as the model card's frames): `frames_per_seed` frames of one drive per seed over `osm`;
// also counted into `pooled` when given.
seg::ConfusionMatrix scoreShippedModel(seg::Segmenter& model, const std::string& osm, const std::vector<uint64_t>& seeds,
                                       int frames_per_seed, double spacing_s, double duration_s, int* frames,
                                       seg::ConfusionMatrix* pooled = nullptr) {
  seg::SimFrameOptions o;
  o.osm_path = kRoot + "/data/osm/" + osm;
  o.vehicle_yaml = kRoot + "/config/vehicle.yaml";
  o.world_yaml = kRoot + "/config/sim_world.yaml";
  o.drive_yaml = kRoot + "/config/sim_drive.yaml";
  o.max_frames = frames_per_seed;
  o.frame_spacing_s = spacing_s;
  o.duration_s = duration_s;
  seg::ConfusionMatrix cm(11);
  for (const uint64_t seed : seeds) {
    o.seed = seed;
    seg::renderSimFrames(o, [&](const seg::SimFrame& f) {
      const cv::Mat labels = model.segment(f.bgr);
      EXPECT_EQ(labels.size(), f.labels.size());
      cm.add(f.labels, labels);
      if (pooled) pooled->add(f.labels, labels);
      ++*frames;
      return true;
    });
  }
  return cm;
}

double printIou(const std::string& what, int frames, const seg::ConfusionMatrix& cm) {
  std::printf("lanesegnet on %d frames of %s, 640x360:\n", frames, what.c_str());
  for (int c = 0; c < 11; ++c)
    std::printf("  %-17s IoU %.3f  (%lld truth pixels)\n", kClassNames[c], cm.iou(c),
                static_cast<long long>(cm.truthPixels(c)));
  std::vector<int> all(11);
  for (int c = 0; c < 11; ++c) all[c] = c;
  const double miou = cm.meanIou(all);
  std::printf("  mIoU %.3f, pixel accuracy %.3f\n", miou, cm.pixelAccuracy());
  return miou;
}

}  // namespace

TEST(SegModel, IouOnHeldOutWestOakland) {
  seg::Segmenter model(shippedModel());
  // Three drives of a network never trained on, with seeds used neither for the model card's
  // validation (West Oakland seeds 101-112) nor by the broad benchmark (1-2). One drive had too few
  // pixels of the rare classes for an IoU to mean much (9,400 dashed-line, 26,000 right-lane pixels
  // in seed 4242's 60 frames).
  int frames = 0;
  const seg::ConfusionMatrix cm = scoreShippedModel(model, "west-oakland.osm", {4242, 4243, 4244}, 60, 2.0, 300.0, &frames);
  ASSERT_GE(frames, 60);
  const double miou = printIou("held-out West Oakland (seeds 4242-4244)", frames, cm);

  // The bar: 0.75 IoU for the ego / left / right lanes and the lane markings. Measured here
  // with the shipped model (lanesegnet-v3, models/README.md): ego 0.958, left 0.950, right 0.905,
  // dashed 0.848, solid 0.910, crosswalk 0.914, curb 0.849, mIoU 0.784. All five bar classes are
  // asserted at the bar, and every class at what was measured less a margin, so a worse model fails:
  // lanesegnet-v2 here has right 0.761, dashed 0.762, solid 0.874, mIoU 0.740 (right 0.562 on
  // seed 4242 alone) and fails six of the margins; lanesegnet-v4 (trained on nine networks, not
  // shipped) has right 0.804, dashed 0.806 and fails two.
  EXPECT_GE(cm.iou(1), 0.75);   // ego lane
  EXPECT_GE(cm.iou(2), 0.75);   // left lane
  EXPECT_GE(cm.iou(3), 0.75);   // right lane
  EXPECT_GE(cm.iou(6), 0.75);   // dashed line
  EXPECT_GE(cm.iou(7), 0.75);   // solid line
  EXPECT_GT(cm.iou(0), 0.97);   // background
  EXPECT_GT(cm.iou(1), 0.94);
  EXPECT_GT(cm.iou(2), 0.93);
  EXPECT_GT(cm.iou(3), 0.87);
  EXPECT_GT(cm.iou(6), 0.81);
  EXPECT_GT(cm.iou(7), 0.89);
  EXPECT_GT(cm.iou(8), 0.89);   // crosswalk
  EXPECT_GT(cm.iou(9), 0.82);   // curb
  EXPECT_GT(miou, 0.76);
}

TEST(SegModel, IouOnHeldOutDevNetworks) {
  seg::Segmenter model(shippedModel());
  // Four data/osm/dev networks the model never saw (the shipped model was trained on Monaco alone;
  // tools/seg/train.sh's HELD_OUT, which RECIPE=many keeps out of training too): a highway exit
  // ramp, a multi-lane junction, a city grid, a roundabout. One drive each, seed 4242 (neither the
  // card's validation seeds 101-104 nor the benchmark's 1-2). Measured with lanesegnet-v3: the ego
  // lane 0.886 (i5), 0.626 (kingsway), 0.888 (neukolln), 0.976 (perth); pooled ego 0.880, left
  // 0.885, right 0.902, dashed 0.889, solid 0.872, mIoU 0.792. Asserted less a margin: a model that
  // generalises worse fails. lanesegnet-v4 (models/README.md) passes all but kingsway's ego lane
  // (0.536), with pooled ego 0.914, left 0.910, right 0.942, mIoU 0.804.
  struct Network {
    const char* osm;
    double min_ego_iou;
  };
  const Network kNetworks[] = {{"dev/i5_exit_ramp.osm", 0.86},
                               {"dev/kingsway_junction.osm", 0.59},
                               {"dev/neukolln.osm", 0.86},
                               {"dev/perth_peanut_roundabout.osm", 0.95}};
  seg::ConfusionMatrix pooled(11);
  int frames = 0;
  for (const Network& net : kNetworks) {
    int n = 0;
    const seg::ConfusionMatrix cm = scoreShippedModel(model, net.osm, {4242}, 30, 2.5, 100.0, &n, &pooled);
    EXPECT_GE(n, 15) << net.osm;
    printIou(std::string(net.osm) + " (held out, seed 4242)", n, cm);
    EXPECT_GT(cm.iou(1), net.min_ego_iou) << net.osm;
    frames += n;
  }
  const double miou = printIou("the four held-out dev networks", frames, pooled);
  EXPECT_GE(pooled.iou(1), 0.75);  // the bar, as on West Oakland
  EXPECT_GE(pooled.iou(2), 0.75);
  EXPECT_GE(pooled.iou(3), 0.75);
  EXPECT_GE(pooled.iou(6), 0.75);
  EXPECT_GE(pooled.iou(7), 0.75);
  EXPECT_GT(pooled.iou(1), 0.86);  // ego lane
  EXPECT_GT(pooled.iou(2), 0.865); // left lane
  EXPECT_GT(pooled.iou(3), 0.88);  // right lane
  EXPECT_GT(pooled.iou(6), 0.87);  // dashed line
  EXPECT_GT(pooled.iou(7), 0.85);  // solid line
  EXPECT_GT(miou, 0.77);
}

TEST(SegModel, MissingModelIsAClearError) {
  seg::ModelConfig c = shippedModel();
  c.path = "/nonexistent/model.onnx";
  try {
    seg::Segmenter s(c);
    FAIL() << "no error";
  } catch (const seg::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
}

TEST(SegModel, NonOnnxFileIsAClearError) {
  lanemap::testing::TempDir tmp("seg-model");
  {
    std::ofstream f(tmp.str("model.onnx"));
    f << "this is not a protobuf, just text pretending to be a model\n";
  }
  seg::ModelConfig c = shippedModel();
  c.path = tmp.str("model.onnx");
  try {
    seg::Segmenter s(c);
    FAIL() << "no error";
  } catch (const seg::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("not an ONNX model"), std::string::npos) << e.what();
  }
}

TEST(SegModel, ClassMapMustMatchTheModelsOutput) {
  seg::ModelConfig c = shippedModel();
  c.class_map = {0, 1, 2, 3, 4};  // the model has 11 output channels
  try {
    seg::Segmenter s(c);
    FAIL() << "no error";
  } catch (const seg::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("outputs 11 classes but the config maps 5"), std::string::npos) << e.what();
  }
}

TEST(SegModel, ClassMapRemapsClasses) {
  // Identity vs a map that sends every class to 9 except the ego lane (1 -> 3): the labels follow.
  seg::ModelConfig c = shippedModel();
  seg::Segmenter ident(c);
  c.class_map = {9, 3, 9, 9, 9, 9, 9, 9, 9, 9, 9};
  seg::Segmenter mapped(c);
  const cv::Mat img = oneFrame(4243);
  ASSERT_FALSE(img.empty());
  const cv::Mat a = ident.segment(img), b = mapped.segment(img);
  int n = 0;
  for (int r = 0; r < a.rows; ++r)
    for (int x = 0; x < a.cols; ++x) {
      // Rows above crop_top are lanemap background whatever the map says: the model never saw them.
      const uint8_t want = r < c.crop_top ? 0 : a.at<uint8_t>(r, x) == 1 ? 3 : 9;
      ASSERT_EQ(b.at<uint8_t>(r, x), want);
      n += a.at<uint8_t>(r, x) == 1;
    }
  std::printf("ego-lane pixels remapped: %d\n", n);
  EXPECT_GT(n, 5000);  // a road frame: the ego lane is a good part of the image
}

TEST(SegModel, CropTopRowsAreBackgroundAndTheRestIsTheModelsView) {
  // With crop_top K the model sees only the frame below row K: the labels there are exactly those of
  // the same model run (without a crop) on that part of the frame, and every row above is background.
  seg::ModelConfig c = shippedModel();
  const int k = 100;
  c.crop_top = 0;
  seg::Segmenter whole(c);
  c.crop_top = k;
  seg::Segmenter cropped(c);
  const cv::Mat img = oneFrame(4244);
  ASSERT_FALSE(img.empty());
  const cv::Mat labels = cropped.segment(img);
  ASSERT_EQ(labels.size(), img.size());
  EXPECT_EQ(cv::countNonZero(labels.rowRange(0, k)), 0);
  const cv::Mat below = whole.segment(img.rowRange(k, img.rows).clone());
  EXPECT_EQ(cv::countNonZero(labels.rowRange(k, img.rows) != below), 0);
  EXPECT_GT(cv::countNonZero(below), below.total() / 4);  // the road: not a blank answer
  try {
    cropped.segment(img.rowRange(0, k + 7).clone());
    FAIL() << "no error";
  } catch (const seg::FrameError& e) {
    EXPECT_NE(std::string(e.what()).find("crop_top 100"), std::string::npos) << e.what();
  }
}

TEST(SegModel, TheSegmentersPixelShuffleGivesTheModelsOwnLabels) {
  // The shipped model's scores end in a DepthToSpace (block 2, CRD): by default the segmenter stops
  // the network before it and lays the scores out itself (issue 17: OpenCV's 6-D Permute was a
  // quarter of the forward pass). Its labels must be the model's own, pixel for pixel, on real
  // frames and on a frame of another size (resized to the input like any other).
  seg::ModelConfig c = shippedModel();
  seg::Segmenter fast(c);
  EXPECT_EQ(fast.shuffleBlock(), 2);
  c.shuffle_in_segmenter = false;
  seg::Segmenter whole(c);
  EXPECT_EQ(whole.shuffleBlock(), 0);
  long labelled = 0;
  for (const uint64_t seed : {4242u, 4243u}) {
    const cv::Mat img = oneFrame(seed);
    ASSERT_FALSE(img.empty());
    const cv::Mat a = fast.segment(img), b = whole.segment(img);
    EXPECT_EQ(cv::countNonZero(a != b), 0) << "seed " << seed;
    labelled += cv::countNonZero(a);
    cv::Mat small;
    cv::resize(img, small, cv::Size(500, 300));
    EXPECT_EQ(cv::countNonZero(fast.segment(small) != whole.segment(small)), 0) << "seed " << seed;
  }
  EXPECT_GT(labelled, 2 * 640 * 240 / 4);  // road scenes, not blank answers
}

TEST(SegConfig, ErrorsNameTheKey) {
  auto err = [](const std::string& yaml) {
    try {
      seg::ModelConfig::fromYaml(YAML::Load(yaml));
    } catch (const seg::ModelError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(err("{input_width: 256}").find("'path'"), std::string::npos);
  EXPECT_NE(err("{path: m.onnx, colour: 3}").find("unknown key 'colour'"), std::string::npos);
  EXPECT_NE(err("{path: m.onnx, output: probabilities}").find("'output' must be scores or labels"), std::string::npos);
  EXPECT_NE(err("{path: m.onnx, std: [1, 0, 1]}").find("'std'"), std::string::npos);
  EXPECT_NE(err("{path: m.onnx, mean: [1, 2]}").find("'mean' must be 3 numbers"), std::string::npos);
  EXPECT_NE(err("{path: m.onnx, input_width: 2}").find("input_width"), std::string::npos);
  EXPECT_NE(err("{path: m.onnx, crop_top: -1}").find("crop_top"), std::string::npos);
  EXPECT_NE(err("{path: m.onnx, depth_to_space: gpu}").find("'depth_to_space' must be segmenter or model"), std::string::npos);
  EXPECT_FALSE(seg::ModelConfig::fromYaml(YAML::Load("{path: m.onnx, depth_to_space: model}")).shuffle_in_segmenter);
  EXPECT_TRUE(seg::ModelConfig::fromYaml(YAML::Load("{path: m.onnx}")).shuffle_in_segmenter);
  EXPECT_EQ(seg::ModelConfig::fromYaml(YAML::Load("{path: m.onnx, crop_top: 120}")).crop_top, 120);
  const auto c = seg::ModelConfig::fromYaml(YAML::Load("{path: models/lanesegnet.onnx, mean: 0.5, upsample: labels}"), kRoot);
  EXPECT_EQ(c.path, kRoot + "/models/lanesegnet.onnx");  // resolved against the base folder
  EXPECT_EQ(c.name, "lanesegnet");
  EXPECT_DOUBLE_EQ(c.mean[2], 0.5);
  EXPECT_FALSE(c.upsample_scores);
}

// The model block of a segmenter config, as lanemap-segmenter and lanemap-offline read it.
TEST(SegConfig, FromSegmenterConfigWithAndWithoutAModelOverride) {
  const YAML::Node config = YAML::Load("{threads: 2, model: {path: models/lanesegnet.onnx, name: v3, crop_top: 120}}");
  const auto a = seg::ModelConfig::fromSegmenterConfig(config, "", kRoot);
  EXPECT_EQ(a.path, kRoot + "/models/lanesegnet.onnx");
  EXPECT_EQ(a.name, "v3");
  EXPECT_EQ(a.crop_top, 120);
  const YAML::Node unnamed = YAML::Load("{model: {path: models/lanesegnet.onnx, crop_top: 120}}");
  const auto b = seg::ModelConfig::fromSegmenterConfig(unnamed, "/tmp/other.onnx");
  EXPECT_EQ(b.path, "/tmp/other.onnx");
  EXPECT_EQ(b.name, "other");  // the override's stem, not the config's file
  EXPECT_EQ(b.crop_top, 120);  // the rest of the block stays
  // The config's name is its own file's: another model given in its place is named by its stem (a
  // map's summary said "lanesegnet-v3" of another model's labels), the same file keeps it.
  EXPECT_EQ(seg::ModelConfig::fromSegmenterConfig(config, "/tmp/other.onnx").name, "other");
  EXPECT_EQ(seg::ModelConfig::fromSegmenterConfig(config, "models/lanesegnet.onnx", kRoot).name, "v3");
  EXPECT_EQ(seg::ModelConfig::fromSegmenterConfig(config, kRoot + "/models/../models/lanesegnet.onnx", kRoot).name, "v3");
  EXPECT_THROW(seg::ModelConfig::fromSegmenterConfig(YAML::Load("{threads: 2}")), seg::ModelError);
}

TEST(SegFrames, DecodeErrorsAreClear) {
  cv::Mat img(360, 640, CV_8UC3, cv::Scalar(10, 20, 30));
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", img, jpeg);
  const cv::Mat ok = seg::decodeFrame(seg::kPixelJpeg, 640, 360, 0, jpeg.data(), jpeg.size());
  EXPECT_EQ(ok.size(), cv::Size(640, 360));
  EXPECT_NEAR(ok.at<cv::Vec3b>(100, 100)[2], 30, 3);

  std::vector<uint8_t> corrupt(jpeg.begin(), jpeg.begin() + 200);  // a truncated header
  for (size_t i = 2; i < corrupt.size(); ++i) corrupt[i] ^= 0x5a;
  EXPECT_THROW(seg::decodeFrame(seg::kPixelJpeg, 640, 360, 0, corrupt.data(), corrupt.size()), seg::FrameError);
  try {
    seg::decodeFrame(seg::kPixelJpeg, 320, 180, 0, jpeg.data(), jpeg.size());
    FAIL();
  } catch (const seg::FrameError& e) {
    EXPECT_NE(std::string(e.what()).find("JPEG is 640x360 but the message says 320x180"), std::string::npos);
  }
  std::vector<uint8_t> raw(640 * 360 * 3, 7);
  EXPECT_EQ(seg::decodeFrame(seg::kPixelBgr, 640, 360, 0, raw.data(), raw.size()).at<cv::Vec3b>(5, 5)[0], 7);
  EXPECT_THROW(seg::decodeFrame(seg::kPixelBgr, 640, 360, 0, raw.data(), raw.size() - 1), seg::FrameError);
  EXPECT_THROW(seg::decodeFrame(0x31323334, 640, 360, 0, raw.data(), raw.size()), seg::FrameError);
  EXPECT_THROW(seg::decodeFrame(seg::kPixelJpeg, 0, 360, 0, jpeg.data(), jpeg.size()), seg::FrameError);

  cv::Mat labels(4, 5, CV_8UC1);
  for (int i = 0; i < 20; ++i) labels.data[i] = static_cast<uint8_t>(i % 11);
  const cv::Mat back = seg::decodeLabels(1, 5, 4, seg::encodeLabelsPng(labels));
  EXPECT_EQ(cv::countNonZero(back != labels), 0);
  EXPECT_THROW(seg::decodeLabels(1, 6, 4, seg::encodeLabelsPng(labels)), seg::FrameError);
}

TEST(SegQueue, DropsTheOldestAndStaysBounded) {
  segmenter::DropOldestQueue<int> q(2);
  size_t dropped = 0;
  for (int i = 1; i <= 7; ++i) dropped += q.push(i);
  EXPECT_EQ(dropped, 5u);
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(q.maxDepth(), 2u);
  EXPECT_EQ(*q.pop(std::chrono::milliseconds(1)), 6);
  EXPECT_EQ(*q.pop(std::chrono::milliseconds(1)), 7);
  EXPECT_FALSE(q.pop(std::chrono::milliseconds(1)).has_value());
  EXPECT_THROW(segmenter::DropOldestQueue<int>(0), std::invalid_argument);
}

TEST(SegMetrics, ConfusionMatrixIou) {
  seg::ConfusionMatrix cm(3);
  cv::Mat t = (cv::Mat_<uint8_t>(1, 6) << 0, 0, 1, 1, 1, 2);
  cv::Mat p = (cv::Mat_<uint8_t>(1, 6) << 0, 1, 1, 1, 2, 2);
  cm.add(t, p);
  EXPECT_DOUBLE_EQ(cm.iou(0), 1.0 / 2.0);  // tp 1, fn 1, fp 0
  EXPECT_DOUBLE_EQ(cm.iou(1), 2.0 / 4.0);  // tp 2, fn 1, fp 1
  EXPECT_DOUBLE_EQ(cm.iou(2), 1.0 / 2.0);  // tp 1, fn 0, fp 1
  EXPECT_DOUBLE_EQ(cm.meanIou({0, 1, 2}), 0.5);
  EXPECT_DOUBLE_EQ(cm.pixelAccuracy(), 4.0 / 6.0);
  EXPECT_EQ(cm.truthPixels(1), 3);
  seg::ConfusionMatrix empty(2);
  EXPECT_TRUE(std::isnan(empty.iou(1)));
}
