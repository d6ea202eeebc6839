// lanemap-segmenter: semantic segmentation of the front camera (METHOD.md section 2). Subscribes
// CAMERA_FRONT (JPEG or raw image_t), runs an ONNX model through OpenCV DNN (core/seg/segmenter.h:
// input size, normalisation and class mapping from the config, so any segmentation model fits)
// and publishes SEMANTIC_FRONT (label_image_t, PNG or RAW) with the source frame's utime and seq.
//
// Frames go through a bounded queue (1-2 frames) to one worker thread; when the model is slower
// than the camera the OLDEST waiting frame is dropped (frames_dropped in STATUS), so the labels
// stay current and memory stays flat. Corrupt or wrong-size frames are counted and skipped. A
// missing or non-ONNX model is an error at start (exit code 2).
//
// --oracle republishes the simulator's SEMANTIC_FRONT_TRUTH as SEMANTIC_FRONT (ablations: the
// pipeline on perfect labels); no model is loaded.
//
// STATUS latency (p50/p99 of the last 500 frames) is this process's share of frame-to-BEV: from the
// input message's receive time (lcm::ReceiveBuffer::recv_utime of CAMERA_FRONT, or of
// SEMANTIC_FRONT_TRUTH with --oracle; wall clock, taken by LCM's receive thread) to the moment its
// SEMANTIC_FRONT is published. With the model that includes the wait in LCM's queue and in the
// frame queue, JPEG decode, inference and PNG encode; dropped frames have none. The bev_builder's
// latency (labels received -> projected) is the rest of camera-to-BEV. (Not now - msg.utime: a
// replayed log keeps its recording's utimes.)
//
//   lanemap-segmenter --config config/segmenter.yaml [--model FILE.onnx] [--oracle]
//
// Offline (no LCM traffic): --log-in drive.lcmlog --log-out out.lcmlog copies every event of the
// log and adds, after each CAMERA_FRONT frame, its SEMANTIC_FRONT (every frame, none dropped), so
// lanemap-offline can map a recorded drive on the model's labels.
#pragma once

#include "core/io/atomic_file.h"
#include "core/seg/segmenter.h"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/lcm_log_writer.h"
#include "processes/framework/log_reader.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include "processes/segmenter/frame_queue.h"
#include <opencv2/core.hpp>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

namespace lanemap::segmenter_app {


using namespace lanemap;

using Settings = SegmenterSettings;  // config/segmenter.yaml (processes/framework/process_configs.h)

// A camera frame and when LCM received it (wall clock, microseconds).
struct ReceivedFrame {
  image_t msg;
  int64_t recv_utime = 0;
};

// Model mode: camera frames -> queue -> worker (decode, segment, publish).
class SegmenterApp {
 public:
  SegmenterApp(Process& process, const Settings& s, std::unique_ptr<seg::Segmenter> model)
      : process_(process), s_(s), model_(std::move(model)), queue_(static_cast<size_t>(s.queue_frames)) {
    auto* sub = process_.lcm().subscribe(s_.camera_channel, &SegmenterApp::onImage, this);
    sub->setQueueCapacity(s_.lcm_queue);
    for (const char* c : {"frames_received", "frames_dropped", "frames_corrupt", "frames_wrong_size",
                          "frames_segmented", "labels_published"})
      process_.counters().set(c, 0);
    worker_ = std::thread([this] { run(); });
    // Process replay: the next frame goes in once this one is labelled (or skipped), so none is
    // dropped and the output does not depend on the machine's speed.
    process_.setIdleCheck([this] { return finished_.load() == received_.load(); });
  }
  ~SegmenterApp() {
    stop_ = true;
    queue_.close();
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onImage(const lcm::ReceiveBuffer* rbuf, const std::string&, const image_t* msg) {
    auto& c = process_.counters();
    c.add("frames_received");
    ++received_;
    const size_t dropped = queue_.push(ReceivedFrame{*msg, rbuf->recv_utime});
    finished_ += static_cast<int64_t>(dropped);
    if (dropped) c.add("frames_dropped", static_cast<int64_t>(dropped));
    c.set("queue_max_depth", static_cast<int64_t>(queue_.maxDepth()));
  }

  void run() {
    auto& c = process_.counters();
    double ms_sum = 0.0;
    int64_t n = 0;
    while (!stop_) {
      std::optional<ReceivedFrame> frame = queue_.pop(std::chrono::milliseconds(100));
      if (!frame) continue;
      struct Finished {  // however the frame's turn ends (published, skipped, failed)
        std::atomic<int64_t>& n;
        ~Finished() { ++n; }
      } finished{finished_};
      const image_t* msg = &frame->msg;
      const auto t0 = std::chrono::steady_clock::now();
      cv::Mat bgr;
      try {
        if ((s_.expect_width > 0 && msg->width != s_.expect_width) ||
            (s_.expect_height > 0 && msg->height != s_.expect_height)) {
          throw seg::FrameError("frame is " + std::to_string(msg->width) + "x" + std::to_string(msg->height) +
                                ", expected " + std::to_string(s_.expect_width) + "x" + std::to_string(s_.expect_height));
        }
        bgr = seg::decodeFrame(msg->pixelformat, msg->width, msg->height, msg->row_stride, msg->data.data(),
                               msg->data.size());
      } catch (const seg::FrameError& e) {
        const std::string what = e.what();
        const bool size = what.find("expected") != std::string::npos || what.find("message says") != std::string::npos;
        c.add(size ? "frames_wrong_size" : "frames_corrupt");
        if (warnings_++ < 10) std::cerr << "segmenter: frame seq " << msg->seq << " skipped: " << what << "\n";
        continue;
      }
      cv::Mat labels;
      try {
        labels = model_->segment(bgr);
      } catch (const std::exception& e) {
        c.add("frames_failed");
        if (warnings_++ < 10) std::cerr << "segmenter: frame seq " << msg->seq << " failed: " << e.what() << "\n";
        continue;
      }
      if (s_.debug_delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(s_.debug_delay_ms));
      c.add("frames_segmented");
      label_image_t out;
      out.utime = msg->utime;
      out.seq = msg->seq;
      out.width = labels.cols;
      out.height = labels.rows;
      if (s_.raw) {
        out.encoding = label_image_t::ENCODING_RAW;
        out.data.assign(labels.data, labels.data + labels.total());
      } else {
        out.encoding = label_image_t::ENCODING_PNG;
        out.data = seg::encodeLabelsPng(labels);
      }
      out.size = static_cast<int32_t>(out.data.size());
      out.source = model_->name();
      process_.lcm().publish(s_.output_channel, &out);
      const int64_t published_utime = geo::wallUtime();
      c.add("labels_published");
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      ms_sum += ms;
      ++n;
      c.set("segment_ms_last", static_cast<int64_t>(ms + 0.5));
      c.set("segment_ms_mean", static_cast<int64_t>(ms_sum / n + 0.5));
      process_.latency().add(static_cast<double>(published_utime - frame->recv_utime) * 1e-3);
    }
  }

  Process& process_;
  Settings s_;
  std::unique_ptr<seg::Segmenter> model_;
  segmenter::DropOldestQueue<ReceivedFrame> queue_;
  std::atomic<bool> stop_{false};
  std::atomic<int64_t> received_{0}, finished_{0};  // frames in; frames labelled, skipped or dropped
  int warnings_ = 0;
  std::thread worker_;
};

// Oracle mode: SEMANTIC_FRONT_TRUTH -> SEMANTIC_FRONT, unchanged but for the channel.
class OracleApp {
 public:
  OracleApp(Process& process, const Settings& s) : process_(process), s_(s) {
    process_.lcm().subscribe(s_.truth_channel, &OracleApp::onTruth, this)->setQueueCapacity(s_.lcm_queue);
    process_.counters().set("truth_received", 0);
    process_.counters().set("labels_published", 0);
  }

 private:
  void onTruth(const lcm::ReceiveBuffer* rbuf, const std::string&, const label_image_t* msg) {
    process_.counters().add("truth_received");
    process_.lcm().publish(s_.output_channel, msg);
    process_.latency().add(static_cast<double>(geo::wallUtime() - rbuf->recv_utime) * 1e-3);
    process_.counters().add("labels_published");
  }
  Process& process_;
  Settings s_;
};

// Offline: every camera frame of the log `in` segmented into `out`; returns the number of frames
// that failed.
inline int64_t segmentLogInto(LogReader& in, LcmLogWriter& out, const std::string& in_path, const std::string& out_path,
                              const Settings& s, seg::Segmenter& model) {
  int64_t frames = 0, bad = 0;
  while (const lcm::LogEvent* ev = in.next()) {
    out.write(ev->channel, ev->timestamp, ev->data, static_cast<size_t>(ev->datalen));
    if (ev->channel != s.camera_channel) continue;
    image_t img;
    if (img.decode(ev->data, 0, ev->datalen) < 0) {
      ++bad;
      continue;
    }
    cv::Mat labels;
    try {
      labels = model.segment(seg::decodeFrame(img.pixelformat, img.width, img.height, img.row_stride, img.data.data(),
                                              img.data.size()));
    } catch (const std::exception& e) {
      if (bad++ < 10) std::cerr << "segmenter: frame seq " << img.seq << " skipped: " << e.what() << "\n";
      continue;
    }
    label_image_t lab;
    lab.utime = img.utime;
    lab.seq = img.seq;
    lab.width = labels.cols;
    lab.height = labels.rows;
    lab.encoding = s.raw ? label_image_t::ENCODING_RAW : label_image_t::ENCODING_PNG;
    if (s.raw) lab.data.assign(labels.data, labels.data + labels.total());
    else lab.data = seg::encodeLabelsPng(labels);
    lab.size = static_cast<int32_t>(lab.data.size());
    lab.source = model.name();
    out.message(s.output_channel, ev->timestamp, lab);
    if (++frames % 100 == 0) std::cerr << "segmenter: " << frames << " frames\n";
  }
  if (in.events() == 0) throw std::runtime_error("not an LCM log, or no whole event in it: " + in_path + " (" + in.damageReport() + ")");
  if (in.damaged()) std::cerr << "segmenter: warning: the log is damaged, segmented what could be read: " << in.damageReport() << "\n";
  std::cerr << "segmenter: " << frames << " frames segmented into " << out_path << ", " << bad << " skipped\n";
  return bad;
}

// segmentLogInto from the file IN_PATH to OUT_PATH. The output is written to OUT_PATH.partial and
// renamed over OUT_PATH only when the whole input was read: a failure (not a log, a write error)
// leaves no output, partial or empty, behind, and an earlier file at OUT_PATH as it was.
inline int64_t segmentLog(const std::string& in_path, const std::string& out_path, const Settings& s, seg::Segmenter& model) {
  LogReader in(in_path);  // a damaged log: what is readable is segmented, and said
  const std::string partial = out_path + ".partial";
  int64_t bad = 0;
  try {
    {
      LcmLogWriter out(partial);
      bad = segmentLogInto(in, out, in_path, out_path, s, model);
    }  // closed (flushed) before the rename
    io::renameFileDurably(partial, out_path);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(partial, ec);
    throw;
  }
  return bad;
}

}  // namespace lanemap::segmenter_app
