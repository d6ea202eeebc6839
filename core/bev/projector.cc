#include "core/bev/projector.h"

#include <algorithm>
#include <cmath>

namespace lanemap::bev {

uint8_t layerBits(uint8_t c) {
  uint8_t b = bit(Layer::kObserved);
  if (isLaneClass(c)) return b | bit(Layer::kDrivable);
  switch (c) {
    case 6: return b | bit(Layer::kDashedLine);
    case 7: return b | bit(Layer::kSolidLine);
    case 8: return b | bit(Layer::kCrosswalk);
    case 9: return b | bit(Layer::kCurb);
    case 10: return b | bit(Layer::kStopLine);
    default: return b;
  }
}

void addSplat(const FrameSplat& splat, BevGrid& grid) {
  for (const auto& c : splat.cells) {
    for (int l = 0; l < kNumLayers; ++l) {
      if (c.layers & (1u << l)) grid.add(BevGrid::Cell(c.x, c.y), static_cast<Layer>(l));
    }
  }
  grid.addFrame();
}

const char* toString(LabelCheck c) {
  switch (c) {
    case LabelCheck::kOk: return "ok";
    case LabelCheck::kWrongSize: return "wrong_size";
    case LabelCheck::kWrongType: return "wrong_type";
    case LabelCheck::kUnknownClass: return "unknown_class";
  }
  return "?";
}

Projector::Projector(const camera::CameraModel& camera, const ProjectorOptions& options)
    : camera_(camera), options_(options) {
  if (!(options_.resolution_m > 0.0) || !(options_.max_range_m > 0.0) || options_.sample_spacing_m < 0.0) {
    throw BevError("Projector: resolution_m and max_range_m must be > 0, sample_spacing_m >= 0");
  }
  centre_ = camera_.opticalCentreVehicle().cast<float>();
  buildRays();
  buildLattice();
}

void Projector::buildRays() {
  const int w = camera_.width(), h = camera_.height();
  rays_.resize(static_cast<size_t>(w) * h);
  candidate_.assign(rays_.size(), 0);
  const Eigen::Vector3d c = camera_.opticalCentreVehicle();
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      const Eigen::Vector3d d = camera_.rayVehicle(Eigen::Vector2d(u, v));
      rays_[i].dir = d.cast<float>();
      rays_[i].flat_hit.setZero();
      if (d.z() >= -1e-9) continue;  // at or above the horizon
      const Eigen::Vector3d hit = c + (-c.z() / d.z()) * d;
      rays_[i].flat_hit = hit.cast<float>();
      if ((hit - c).head<2>().norm() <= options_.max_range_m) {
        candidate_[i] = 1;
        ++candidates_;
      }
    }
  }
}

void Projector::buildLattice() {
  const int w = camera_.width(), h = camera_.height();
  const double spacing = options_.sample_spacing_m;
  const int uc = std::clamp(static_cast<int>(std::lround(camera_.intrinsics().cx)), 0, w - 2);
  bool have_last = false;
  Eigen::Vector3f last_hit = Eigen::Vector3f::Zero();
  for (int v = h - 1; v >= 0; --v) {  // from the car outwards
    Row r;
    r.v = v;
    for (int u = 0; u < w; ++u) {
      if (!candidate_[static_cast<size_t>(v) * w + u]) continue;
      if (r.u1 < 0) r.u0 = u;
      r.u1 = u;
    }
    if (r.u1 < 0) continue;
    const size_t ic = static_cast<size_t>(v) * w + uc;
    const Eigen::Vector3f hit = rays_[ic].flat_hit;
    if (spacing > 0.0 && have_last && (hit - last_hit).norm() < spacing) continue;
    have_last = true;
    last_hit = hit;
    rows_.push_back(r);
    int step = 1;
    if (spacing > 0.0) {
      const double across = (rays_[ic + 1].flat_hit - hit).norm();
      step = std::max(1, static_cast<int>(std::floor(spacing / std::max(across, 1e-6))));
    }
    for (int u = r.u0; u <= r.u1; u += step) {
      const int i = v * w + u;
      if (candidate_[i]) lattice_.push_back(i);
    }
  }
}

LabelCheck Projector::check(const cv::Mat& labels) const {
  if (labels.type() != CV_8UC1) return LabelCheck::kWrongType;
  if (labels.cols != camera_.width() || labels.rows != camera_.height()) return LabelCheck::kWrongSize;
  double lo = 0.0, hi = 0.0;
  cv::minMaxLoc(labels, &lo, &hi);
  return hi >= kNumClasses ? LabelCheck::kUnknownClass : LabelCheck::kOk;
}

void Projector::separationPixels(const cv::Mat& labels, const Row& r, std::vector<std::pair<int, uint8_t>>& out) const {
  const int w = camera_.width();
  const uint8_t* row = labels.ptr<uint8_t>(r.v);
  const uint8_t sep = bit(Layer::kLaneSeparation);
  const float max_gap = static_cast<float>(options_.max_separation_gap_m);
  int last_u = -1;
  uint8_t last_c = 0;
  bool paint_only = true;
  for (int u = r.u0; u <= r.u1; ++u) {
    const uint8_t c = row[u];
    if (!isLaneClass(c)) {
      if (c != kClassDashed && c != kClassSolid) paint_only = false;
      continue;
    }
    if (last_u >= 0 && c != last_c && paint_only) {
      const int base = r.v * w;
      const float gap = (rays_[base + u].flat_hit - rays_[base + last_u].flat_hit).norm();
      if (gap <= max_gap) {
        const int a = u == last_u + 1 ? last_u : last_u + 1;
        const int b = u == last_u + 1 ? u : u - 1;
        for (int k = a; k <= b; ++k) out.emplace_back(base + k, layerBits(row[k]) | sep);
      }
    }
    last_u = u;
    last_c = c;
    paint_only = true;
  }
}

FrameSplat Projector::project(const cv::Mat& labels, const Eigen::Isometry3d& vehicle_to_enu,
                              const ground::MeshGround* mesh) const {
  FrameSplat splat;
  splat.resolution = options_.resolution_m;
  const cv::Mat lab = labels.isContinuous() ? labels : labels.clone();
  const uint8_t* L = lab.ptr<uint8_t>(0);
  std::vector<std::pair<int, uint8_t>> px;
  px.reserve(lattice_.size() + 4096);
  for (int i : lattice_) px.emplace_back(i, layerBits(L[i]));
  if (options_.lane_separation) {
    for (const Row& r : rows_) separationPixels(lab, r, px);
  }
  // A local raster of layer bits around the camera deduplicates the cells (at most once per frame).
  const double res = options_.resolution_m;
  const Eigen::Vector3d c = vehicle_to_enu * centre_.cast<double>();
  const int R = static_cast<int>(std::ceil(options_.max_range_m / res)) + 2, n = 2 * R + 1;
  const int x0 = static_cast<int>(std::floor(c.x() / res)) - R, y0 = static_cast<int>(std::floor(c.y() / res)) - R;
  std::vector<uint8_t> raster(static_cast<size_t>(n) * n, 0);
  const Eigen::Matrix3d rot = vehicle_to_enu.linear();
  for (const auto& [i, bits] : px) {
    const Ray& ray = rays_[i];
    Eigen::Vector3d p = vehicle_to_enu * ray.flat_hit.cast<double>();
    if (mesh) {
      const Eigen::Vector3d d = rot * ray.dir.cast<double>();
      const double max_t = options_.max_range_m / std::max(d.head<2>().norm(), 1e-9);
      if (const auto t = mesh->intersect(c, d, max_t)) {
        p = c + *t * d;
        ++splat.mesh_hits;
      } else if (mesh->covers(p.x(), p.y())) {
        ++splat.dropped;
        continue;
      } else {
        ++splat.flat;
      }
    } else {
      ++splat.flat;
    }
    const int cx = static_cast<int>(std::floor(p.x() / res)) - x0, cy = static_cast<int>(std::floor(p.y() / res)) - y0;
    if (cx < 0 || cy < 0 || cx >= n || cy >= n) {
      ++splat.dropped;
      continue;
    }
    raster[static_cast<size_t>(cy) * n + cx] |= bits;
  }
  splat.pixels = px.size();
  for (int y = 0; y < n; ++y) {
    const uint8_t* row = &raster[static_cast<size_t>(y) * n];
    for (int x = 0; x < n; ++x) {
      if (row[x]) splat.cells.push_back(SplatCell{x + x0, y + y0, row[x]});
    }
  }
  return splat;
}

}  // namespace lanemap::bev
