#include "core/sim/simulator.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <optional>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <variant>

namespace lanemap::sim {
namespace {

int64_t toUtime(int64_t start, double t) { return start + static_cast<int64_t>(std::llround(t * 1e6)); }

// A fixed set of threads running queued tasks in submission order. The destructor drops tasks not
// started (their futures then report a broken promise) and joins.
class WorkerPool {
 public:
  explicit WorkerPool(int threads) {
    for (int i = 0; i < threads; ++i) workers_.emplace_back([this] { work(); });
  }
  ~WorkerPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      tasks_.clear();
    }
    wake_.notify_all();
    for (auto& w : workers_) w.join();
  }
  template <typename F>
  auto submit(F f) -> std::future<decltype(f())> {
    auto task = std::make_shared<std::packaged_task<decltype(f())()>>(std::move(f));
    auto future = task->get_future();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      tasks_.emplace_back([task] { (*task)(); });
    }
    wake_.notify_one();
    return future;
  }

 private:
  void work() {
    for (;;) {
      std::function<void()> task;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stop_ || !tasks_.empty(); });
        if (stop_) return;
        task = std::move(tasks_.front());
        tasks_.pop_front();
      }
      task();
    }
  }
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  bool stop_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace

Simulator::Simulator(const World& world, const Trajectory& trajectory, const geo::LocalFrame& frame,
                     const camera::CameraModel& camera, const RenderOptions& render,
                     const std::optional<LidarScannerOptions>& lidar, const SimulatorOptions& options)
    : world_(world), sim_world_(dynamic_cast<const SimWorld*>(&world)), trajectory_(trajectory), frame_(frame),
      renderer_(camera, render), options_(options) {
  if (lidar) scanner_.emplace(*lidar);
}

PoseMeasurement Simulator::poseAt(double t, PoseNoise& noise, double dt) const {
  PoseMeasurement m;
  m.truth = trajectory_.at(t);
  m.utime = toUtime(options_.start_utime, t);
  const PoseError e = noise.next(dt);
  const Eigen::Vector3d p = m.truth.vehicle_to_enu.translation() + e.position;
  m.wgs84 = frame_.toWgs84(p);
  const Eigen::Matrix3d err = (Eigen::AngleAxisd(e.rpy.z(), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(e.rpy.y(), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(e.rpy.x(), Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
  m.orientation = Eigen::Quaterniond(err * m.truth.vehicle_to_enu.linear()).normalized();
  m.velocity_enu = m.truth.vehicle_to_enu.linear().col(0) * m.truth.speed;
  m.angular_rate = Eigen::Vector3d(0.0, 0.0, m.truth.yaw_rate);
  const auto& o = noise.options();
  m.position_sigma_m = std::hypot(o.position_sigma_m, o.bias_sigma_m);
  m.yaw_sigma_rad = o.yaw_sigma_deg * M_PI / 180.0;
  return m;
}

CameraMeasurement Simulator::cameraAt(double t, int64_t seq) const {
  const VehicleState st = trajectory_.at(t);
  const RenderedFrame f = seenFrom(st.label_lanelet, [&](const World& w) {
    return renderer_.render(w, st.vehicle_to_enu, st.label_lanelet, options_.seed * 1000003ULL + static_cast<uint64_t>(seq));
  });
  CameraMeasurement m;
  m.utime = toUtime(options_.start_utime, t);
  m.seq = seq;
  m.width = f.rgb.cols;
  m.height = f.rgb.rows;
  m.ego_lanelet = st.label_lanelet;
  cv::imencode(".jpg", f.rgb, m.jpeg, {cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality});
  cv::imencode(".png", f.labels, m.labels_png, {cv::IMWRITE_PNG_COMPRESSION, 3});
  return m;
}

SimulatorCounts Simulator::run(SensorSink& sink, const std::function<void(double)>& progress) {
  SimulatorCounts counts;
  PoseNoise noise(options_.pose_noise, options_.seed);
  const double T = trajectory_.duration();
  const double pose_dt = 1.0 / options_.pose_rate_hz;
  const double cam_dt = 1.0 / options_.camera_rate_hz;
  const double sweep_dt = scanner_ ? scanner_->sweepPeriodS() : 0.0;
  const double t0_abs = static_cast<double>(options_.start_utime) * 1e-6;  // for LIDAR clock
  const int64_t hour_us = 3600LL * 1000000LL;
  const int64_t hour_base = options_.start_utime / hour_us * hour_us;
  const int threads = options_.threads > 0 ? options_.threads
                                           : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));

  // Each sensor keeps its own schedule; the earliest next measurement is emitted first, so the
  // sink sees time order. A LIDAR sweep is emitted when it is complete, as a driver publishes it.
  enum class Kind { kPose, kCamera, kLidar };
  struct Event {
    Kind kind = Kind::kPose;
    double t = 0.0;
    int64_t index = 0;
    std::future<CameraMeasurement> camera;        // with workers: the frame being rendered
    std::future<LidarScanner::Cast> lidar;        // with workers: the sweep being cast
  };
  int64_t pose_i = 0, cam_i = 0, sweep_i = 0;
  auto next = [&]() -> std::optional<Event> {
    const double tp = pose_i * pose_dt;
    const double tc = cam_i * cam_dt;
    const double ts = scanner_ ? (sweep_i + 1) * sweep_dt : 1e300;  // end of the sweep
    const double t = std::min({tp, tc, ts});
    if (t > T) return std::nullopt;
    Event e;
    e.t = t;
    if (t == tp) {
      e.kind = Kind::kPose;
      e.index = pose_i++;
    } else if (t == tc) {
      e.kind = Kind::kCamera;
      e.index = cam_i++;
    } else {
      e.kind = Kind::kLidar;
      e.index = sweep_i++;
    }
    return e;
  };
  auto castSweep = [this, t0_abs, sweep_dt](int64_t i) {
    // Seen from the car's OSM level at the sweep's start (as camera frames are).
    return seenFrom(trajectory_.at(i * sweep_dt).label_lanelet, [&](const World& w) {
      return scanner_->cast(
          w, t0_abs + i * sweep_dt, [this, t0_abs](double t_abs) { return trajectory_.at(t_abs - t0_abs).vehicle_to_enu; },
          options_.seed * 7777ULL + static_cast<uint64_t>(i));
    });
  };

  // With workers, frames and sweeps are started up to 2 per worker ahead of the one emitted.
  std::optional<WorkerPool> pool;
  if (threads > 1) pool.emplace(threads);
  const int ahead = threads > 1 ? 2 * threads : 0;
  std::deque<Event> window;
  int started = 0;  // frames and sweeps in the window
  bool schedule_done = false;

  int64_t last_packet_utime = 0;
  double last_progress = -1.0;
  for (;;) {
    while (!schedule_done && (window.empty() || started < ahead)) {
      std::optional<Event> e = next();
      if (!e) {
        schedule_done = true;
        break;
      }
      if (pool && e->kind == Kind::kCamera) {
        e->camera = pool->submit([this, t = e->t, i = e->index] { return cameraAt(t, i); });
      } else if (pool && e->kind == Kind::kLidar) {
        e->lidar = pool->submit([&castSweep, i = e->index] { return castSweep(i); });
      }
      if (e->kind != Kind::kPose) ++started;
      window.push_back(std::move(*e));
    }
    if (window.empty()) break;
    Event e = std::move(window.front());
    window.pop_front();
    const double t = e.t;
    if (e.kind == Kind::kPose) {
      sink.onPose(poseAt(t, noise, pose_dt));
      ++counts.poses;
    } else if (e.kind == Kind::kCamera) {
      --started;
      sink.onCamera(pool ? e.camera.get() : cameraAt(t, e.index));
      ++counts.camera_frames;
    } else {
      --started;
      const LidarSweep sweep = scanner_->encode(pool ? e.lidar.get() : castSweep(e.index));
      if (!sweep.packets.empty()) {
        LidarMeasurement m;
        m.packets = sweep.packets;
        for (const auto& pk : sweep.packets) {
          const uint32_t usec = static_cast<uint32_t>(pk[lidar::kTimestampOffset]) |
                                static_cast<uint32_t>(pk[lidar::kTimestampOffset + 1]) << 8 |
                                static_cast<uint32_t>(pk[lidar::kTimestampOffset + 2]) << 16 |
                                static_cast<uint32_t>(pk[lidar::kTimestampOffset + 3]) << 24;
          int64_t u = hour_base + usec;
          while (u < last_packet_utime - hour_us / 2) u += hour_us;  // the hour rolled over
          m.packet_utime.push_back(u);
          last_packet_utime = u;
        }
        m.utime = m.packet_utime.front();
        m.publish_utime = toUtime(options_.start_utime, t);
        counts.lidar_packets += static_cast<int64_t>(m.packets.size());
        ++counts.lidar_sweeps;
        sink.onLidar(m);
      }
    }
    if (progress && t - last_progress >= 1.0) {
      progress(T > 0 ? t / T : 1.0);
      last_progress = t;
    }
  }
  if (progress) progress(1.0);
  return counts;
}

}  // namespace lanemap::sim
