#include "core/seg/sim_frames.h"

#include "core/camera/camera_model.h"
#include "core/osm/osm_data.h"
#include "core/sim/camera_renderer.h"
#include "core/sim/drive.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"

#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>

namespace lanemap::seg {

namespace {

constexpr double kDeg = M_PI / 180.0;

sim::RenderOptions drawConditions(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  sim::RenderOptions r;
  r.light = 0.35 + 0.9 * u(rng);                 // dusk .. very bright day
  r.sun_azimuth_deg = 360.0 * u(rng);
  r.sun_elevation_deg = -5.0 + 75.0 * u(rng);    // a sixth of the sets: overcast, no shadows
  r.ambient = 0.3 + 0.3 * u(rng);
  r.sensor_noise = 1.0 + 5.0 * u(rng);
  r.haze_distance_m = 150.0 + 450.0 * u(rng);
  r.shadow_softness_deg = 0.8 + 2.0 * u(rng);
  return r;
}

}  // namespace

int renderSimFrames(const SimFrameOptions& o, const std::function<bool(const SimFrame&)>& sink) {
  if (o.max_frames <= 0) return 0;
  if (!(o.frame_spacing_s > 0.0)) throw std::runtime_error("renderSimFrames: frame_spacing_s must be > 0");
  const YAML::Node vehicle = YAML::LoadFile(o.vehicle_yaml);
  const camera::CameraModel camera = camera::CameraModel::fromYaml(vehicle["camera"]);
  sim::WorldOptions world_options =
      o.world_yaml.empty() ? sim::WorldOptions() : sim::WorldOptions::fromYamlFile(o.world_yaml);
  world_options.seed = o.seed;
  if (o.faded_marking >= 0.0) world_options.p_faded_marking = o.faded_marking;
  sim::DriveOptions drive;
  if (!o.drive_yaml.empty()) drive = sim::DriveOptions::fromYaml(YAML::LoadFile(o.drive_yaml)["drive"]);
  drive.seed = o.seed;
  drive.duration_s = o.duration_s;
  // The routes the shipped model was trained and scored on (models/README.md): none turns round at
  // a dead end, where every lane would be labelled background while the camera looks along the road.
  drive.turn_round_at_dead_ends = false;

  const osm::OsmData osm_data = osm::readOsm(o.osm_path);
  const skeleton::Skeleton sk = skeleton::Skeleton::build(osm_data);
  const auto world = sim::buildWorld(sk, world_options);
  const sim::LanePlan plan = sim::planDrive(sk, world->truth(), drive);
  const sim::Trajectory trajectory(world->truth(), *world, plan, drive);

  // The region split along east over the extent of the network's roads.
  double min_e = std::numeric_limits<double>::infinity(), max_e = -min_e;
  for (const auto& road : sk.roads())
    for (const auto& p : road.polyline) {
      min_e = std::min(min_e, p.x());
      max_e = std::max(max_e, p.x());
    }
  const double split_e = min_e + o.validation_fraction * (max_e - min_e);
  auto inRegion = [&](const Eigen::Vector2d& p) {
    switch (o.region) {
      case SimRegion::kAll: return true;
      case SimRegion::kValidation: return p.x() < split_e;
      case SimRegion::kTrain: return p.x() > split_e + o.guard_m;
    }
    return true;
  };

  std::mt19937_64 rng(o.seed * 0x9E3779B97F4A7C15ULL + 17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::unique_ptr<sim::CameraRenderer>> renderers;
  const int sets = o.vary_conditions ? std::max(1, o.condition_sets) : 1;
  for (int i = 0; i < sets; ++i) {
    sim::RenderOptions r = o.vary_conditions ? drawConditions(rng) : sim::RenderOptions();
    r.opposite_directions = [w = world.get()](int64_t a, int64_t b) {
      const map::Lanelet* la = w->lanelet(a);
      const map::Lanelet* lb = w->lanelet(b);
      return la && lb && la->from_node == lb->to_node && la->to_node == lb->from_node;
    };
    renderers.push_back(std::make_unique<sim::CameraRenderer>(camera, r));
  }

  const Eigen::Vector3d centre = camera.opticalCentreVehicle();
  int produced = 0;
  for (double t = o.frame_spacing_s * u(rng); t <= trajectory.duration() && produced < o.max_frames;
       t += o.frame_spacing_s * (0.6 + 0.8 * u(rng))) {
    const sim::VehicleState st = trajectory.at(t);
    const Eigen::Vector2d pos = st.vehicle_to_enu.translation().head<2>();
    // Draw the jitter whether or not the frame is kept, so a frame does not depend on the region.
    const int set = static_cast<int>(u(rng) * sets) % sets;
    const double dp = o.vary_conditions ? (2.0 * u(rng) - 1.0) * o.pitch_jitter_deg : 0.0;
    const double dr = o.vary_conditions ? (2.0 * u(rng) - 1.0) * o.roll_jitter_deg : 0.0;
    const double dy = o.vary_conditions ? (2.0 * u(rng) - 1.0) * o.yaw_jitter_deg : 0.0;
    const double dz = o.vary_conditions ? (2.0 * u(rng) - 1.0) * o.height_jitter_m : 0.0;
    if (!inRegion(pos)) continue;
    // The camera turned about its optical centre (and raised): the vehicle pose moved instead, so
    // one renderer (its cached rays) serves every jitter. Positive pitch = nose down = +y rotation.
    const Eigen::Matrix3d rj = (Eigen::AngleAxisd(dy * kDeg, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(dp * kDeg, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(dr * kDeg, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
    Eigen::Isometry3d jitter = Eigen::Isometry3d::Identity();
    jitter.linear() = rj;
    jitter.translation() = centre - rj * centre + Eigen::Vector3d(0.0, 0.0, dz);
    const Eigen::Isometry3d pose = st.vehicle_to_enu * jitter;

    const sim::CameraRenderer& renderer = *renderers[static_cast<size_t>(set)];
    const sim::RenderedFrame rf =
        renderer.render(*world, pose, st.label_lanelet, o.seed * 1000003ULL + static_cast<uint64_t>(produced));
    SimFrame f;
    f.index = produced;
    f.t = t;
    f.position = pos;
    cv::imencode(".jpg", rf.rgb, f.jpeg, {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality});
    f.bgr = cv::imdecode(f.jpeg, cv::IMREAD_COLOR);
    f.labels = rf.labels;
    f.light = renderer.options().light;
    f.sun_elevation_deg = renderer.options().sun_elevation_deg;
    f.pitch_offset_deg = dp;
    ++produced;
    if (!sink(f)) break;
  }
  return produced;
}

ConfusionMatrix::ConfusionMatrix(int num_classes)
    : n_(num_classes), m_(static_cast<size_t>(num_classes) * num_classes, 0) {
  if (num_classes <= 0) throw std::invalid_argument("ConfusionMatrix: num_classes must be > 0");
}

void ConfusionMatrix::add(const cv::Mat& truth, const cv::Mat& predicted) {
  if (truth.type() != CV_8UC1 || predicted.type() != CV_8UC1 || truth.size() != predicted.size())
    throw std::invalid_argument("ConfusionMatrix::add: need two CV_8UC1 images of one size");
  for (int r = 0; r < truth.rows; ++r) {
    const uint8_t* t = truth.ptr<uint8_t>(r);
    const uint8_t* p = predicted.ptr<uint8_t>(r);
    for (int c = 0; c < truth.cols; ++c) {
      if (t[c] >= n_ || p[c] >= n_) continue;  // unknown ids: ignored
      ++m_[static_cast<size_t>(t[c]) * n_ + p[c]];
    }
  }
}

double ConfusionMatrix::iou(int c) const {
  int64_t tp = m_[static_cast<size_t>(c) * n_ + c], fn = 0, fp = 0;
  for (int k = 0; k < n_; ++k) {
    if (k == c) continue;
    fn += m_[static_cast<size_t>(c) * n_ + k];
    fp += m_[static_cast<size_t>(k) * n_ + c];
  }
  const int64_t uni = tp + fn + fp;
  return uni == 0 ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(tp) / uni;
}

double ConfusionMatrix::meanIou(const std::vector<int>& classes) const {
  double sum = 0.0;
  int n = 0;
  for (int c : classes) {
    const double v = iou(c);
    if (std::isnan(v)) continue;
    sum += v;
    ++n;
  }
  return n == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / n;
}

double ConfusionMatrix::pixelAccuracy() const {
  int64_t diag = 0, all = 0;
  for (int i = 0; i < n_; ++i)
    for (int j = 0; j < n_; ++j) {
      all += m_[static_cast<size_t>(i) * n_ + j];
      if (i == j) diag += m_[static_cast<size_t>(i) * n_ + j];
    }
  return all == 0 ? 0.0 : static_cast<double>(diag) / all;
}

int64_t ConfusionMatrix::truthPixels(int c) const {
  int64_t s = 0;
  for (int k = 0; k < n_; ++k) s += m_[static_cast<size_t>(c) * n_ + k];
  return s;
}

}  // namespace lanemap::seg
