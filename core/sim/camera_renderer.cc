// Camera rendering for the simulator: one ray per pixel, surface colours, lighting, labels, noise.
#include "core/sim/camera_renderer.h"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

namespace lanemap::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
// Direct sun scale: flat ground under a 40 deg sun gets ambient + (1 - ambient) * 1.6 * sin 40 ~ 1,
// so albedos read as the colours a camera records on a bright day.
constexpr double kSunGain = 1.6;

// ---- deterministic hashing (thread-count independent noise) ----
uint64_t mix64(uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}
uint64_t hash2(int64_t a, int64_t b, uint64_t salt) {
  return mix64(static_cast<uint64_t>(a) * 0x9e3779b97f4a7c15ULL ^ mix64(static_cast<uint64_t>(b) + salt));
}
double unitFromHash(uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }

// Noise fixed to the world (so texture stays put from frame to frame): a value in [-1, 1] per
// `cell`-sized square, or smoothly interpolated between cell corners.
double cellNoise(double e, double n, double cell, uint64_t salt) {
  return 2.0 * unitFromHash(hash2(static_cast<int64_t>(std::floor(e / cell)),
                                  static_cast<int64_t>(std::floor(n / cell)), salt)) - 1.0;
}
double smoothNoise(double e, double n, double cell, uint64_t salt) {
  const double x = e / cell, y = n / cell;
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0 - 2.0 * tx);
  ty = ty * ty * (3.0 - 2.0 * ty);
  auto corner = [&](int64_t i, int64_t j) { return 2.0 * unitFromHash(hash2(i, j, salt)) - 1.0; };
  const double a = corner(ix, iy) + tx * (corner(ix + 1, iy) - corner(ix, iy));
  const double b = corner(ix, iy + 1) + tx * (corner(ix + 1, iy + 1) - corner(ix, iy + 1));
  return a + ty * (b - a);
}

// Approximately standard normal from one hash (Irwin-Hall of four 16-bit uniforms).
double gaussFromHash(uint64_t h) {
  double s = 0.0;
  for (int i = 0; i < 4; ++i) s += static_cast<double>((h >> (16 * i)) & 0xffff) / 65535.0;
  return (s - 2.0) * std::sqrt(3.0);  // variance of the sum is 4/12
}

// ---- colours (RGB in [0, 1]) ----
using Rgb = Eigen::Vector3d;

Rgb skyColour(const Eigen::Vector3d& dir) {
  const Rgb horizon(0.80, 0.85, 0.90), zenith(0.33, 0.53, 0.85);
  const double t = std::sqrt(std::clamp(dir.z(), 0.0, 1.0));
  return horizon + t * (zenith - horizon);
}

// True when the solid paint at (e, n) separates lanes of opposite directions: two road lanelets
// next to it that are not in one cross-section.
bool separatesDirections(const World& world, double e, double n, const GroundSample& paint,
                         const std::function<bool(int64_t, int64_t)>& opposite) {
  auto isOpposite = [&](int64_t a, int64_t b) { return opposite ? opposite(a, b) : !world.laneOffset(a, b); };
  std::array<int64_t, 9> lanelets{};
  int count = 0;
  if (paint.lanelet >= 0) lanelets[count++] = paint.lanelet;
  static constexpr double kProbe[2] = {0.4, 0.8};
  static constexpr double kDirs[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const double r : kProbe) {
    for (const auto& d : kDirs) {
      const GroundSample g = world.sample(e + r * d[0], n + r * d[1]);
      if (g.surface != Surface::kAsphalt || g.lanelet < 0) continue;
      for (int i = 0; i < count; ++i) {
        if (lanelets[i] != g.lanelet && isOpposite(lanelets[i], g.lanelet)) return true;
      }
      lanelets[count++] = g.lanelet;
    }
  }
  return false;
}

Rgb groundColour(const World& world, const GroundSample& g, double e, double n, const RenderOptions& o) {
  const double fine = cellNoise(e, n, 0.07, 11);
  const double patch = smoothNoise(e, n, 1.7, 12);
  switch (g.surface) {
    case Surface::kAsphalt:
    case Surface::kIntersection:
      return Rgb(0.27, 0.27, 0.28) * (1.0 + 0.10 * fine + 0.09 * patch);
    case Surface::kParking:
      return Rgb(0.30, 0.30, 0.31) * (1.0 + 0.10 * fine + 0.09 * patch);
    case Surface::kBikeLane:
      return Rgb(0.34, 0.27, 0.25) * (1.0 + 0.08 * fine + 0.06 * patch);
    case Surface::kSolidPaint:
      if (o.yellow_centre_lines && separatesDirections(world, e, n, g, o.opposite_directions))
        return Rgb(0.86, 0.70, 0.22) * (1.0 + 0.05 * fine);
      [[fallthrough]];
    case Surface::kDashedPaint:
    case Surface::kCrosswalkPaint:
    case Surface::kStopLinePaint:
      return Rgb(0.86, 0.86, 0.83) * (1.0 + 0.05 * fine + 0.04 * patch);
    case Surface::kCurb:
      return Rgb(0.72, 0.72, 0.70) * (1.0 + 0.04 * fine);
    case Surface::kSidewalk:
      return Rgb(0.60, 0.58, 0.55) * (1.0 + 0.05 * fine + 0.05 * patch +
                                      0.04 * cellNoise(e, n, 1.0, 13));  // paving slabs
    case Surface::kOffRoad:
    default:
      return Rgb(0.28, 0.40, 0.18) * (1.0 + 0.20 * fine + 0.15 * patch);
  }
}

// Ground normal at a point on the surface by forward differences (2 height() calls; the point's own
// height is known to 0.1 mm, so over 0.2 m the slope is good to 1e-3).
Eigen::Vector3d groundNormalAt(const World& world, const Eigen::Vector3d& p) {
  constexpr double kStep = 0.2;
  const double dzde = (world.height(p.x() + kStep, p.y()) - p.z()) / kStep;
  const double dzdn = (world.height(p.x(), p.y() + kStep) - p.z()) / kStep;
  return Eigen::Vector3d(-dzde, -dzdn, 1.0).normalized();
}

Eigen::Vector3d sunDirection(const RenderOptions& o) {
  const double az = o.sun_azimuth_deg * kDegToRad, el = o.sun_elevation_deg * kDegToRad;
  return {std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), std::sin(el)};
}

// Which obstacles may shade which ground, for one frame: every box near the camera is entered in
// the cells of a 2 m grid (around the camera, as large as the render range) that its shadow can
// reach: its footprint swept away from the sun by the longest shadow it casts, grown by the
// penumbra. A ground pixel then tests only the boxes of its cell.
class ShadowGrid {
 public:
  ShadowGrid(const World& world, const Eigen::Vector3d& centre, const Eigen::Vector3d& sun, const RenderOptions& o)
      : sun_(sun), range_(o.shadow_range_m), radius_(std::tan(o.shadow_softness_deg * kDegToRad)) {
    u_ = sun.unitOrthogonal();
    v_ = sun.cross(u_);
    const double half = o.max_range_m + kCell;
    n_ = static_cast<int>(std::ceil(2.0 * half / kCell));
    x0_ = centre.x() - half;
    y0_ = centre.y() - half;
    cells_.assign(static_cast<size_t>(n_) * n_, {});
    std::vector<const Obstacle*> near;
    world.obstaclesNear(centre.head<2>(), half + range_, &near);
    const Eigen::Vector2d sun_xy = sun.head<2>().normalized();
    // The lowest sun ray of the disc: shadows are longest for it.
    const double low_el = std::max(std::asin(std::clamp(sun.z(), -1.0, 1.0)) - o.shadow_softness_deg * kDegToRad,
                                   1.0 * kDegToRad);
    const double margin = range_ * radius_ + 0.1;
    for (const Obstacle* ob : near) {
      const PreparedBox b(*ob);
      const double ex = std::abs(b.cos_yaw) * b.half_extent.x() + std::abs(b.sin_yaw) * b.half_extent.y();
      const double ey = std::abs(b.sin_yaw) * b.half_extent.x() + std::abs(b.cos_yaw) * b.half_extent.y();
      // Ground up to 3 m below the box's base (hills) still gets its shadow.
      const double drop = 2.0 * b.half_extent.z() + 3.0;
      const double length = std::min(range_ * std::cos(low_el), drop / std::tan(low_el));
      const Eigen::Vector2d far = b.centre.head<2>() - length * sun_xy;
      const double xa = std::min(b.centre.x(), far.x()) - ex - margin, xb = std::max(b.centre.x(), far.x()) + ex + margin;
      const double ya = std::min(b.centre.y(), far.y()) - ey - margin, yb = std::max(b.centre.y(), far.y()) + ey + margin;
      const int ia = std::max(0, static_cast<int>(std::floor((xa - x0_) / kCell)));
      const int ib = std::min(n_ - 1, static_cast<int>(std::floor((xb - x0_) / kCell)));
      const int ja = std::max(0, static_cast<int>(std::floor((ya - y0_) / kCell)));
      const int jb = std::min(n_ - 1, static_cast<int>(std::floor((yb - y0_) / kCell)));
      if (ia > ib || ja > jb) continue;
      const int index = static_cast<int>(boxes_.size());
      boxes_.push_back(b);
      for (int j = ja; j <= jb; ++j)
        for (int i = ia; i <= ib; ++i) cells_[static_cast<size_t>(j) * n_ + i].push_back(index);
    }
  }

  // Fraction [0, 1] of the (softened) sun visible from a ground point: four rays spread over the
  // sun disc, the pattern rotated per pixel (a dithered penumbra).
  double visibility(const Eigen::Vector3d& point, uint64_t pixel_hash) const {
    const int i = static_cast<int>(std::floor((point.x() - x0_) / kCell));
    const int j = static_cast<int>(std::floor((point.y() - y0_) / kCell));
    if (i < 0 || j < 0 || i >= n_ || j >= n_) return 1.0;
    const std::vector<int>& cell = cells_[static_cast<size_t>(j) * n_ + i];
    if (cell.empty()) return 1.0;
    const double rot = 2.0 * M_PI * unitFromHash(pixel_hash);
    const Eigen::Vector3d start = point + Eigen::Vector3d(0, 0, 0.02);
    int blocked = 0;
    for (int k = 0; k < 4; ++k) {
      const double a = rot + k * 0.5 * M_PI;
      const double r = radius_ * (k % 2 ? 0.4 : 0.9);
      const Eigen::Vector3d dir = (sun_ + r * (std::cos(a) * u_ + std::sin(a) * v_)).normalized();
      for (const int b : cell) {
        if (std::isfinite(intersectBox(boxes_[b], start, dir, 0.0, range_))) {
          ++blocked;
          break;
        }
      }
    }
    return 1.0 - blocked / 4.0;
  }

 private:
  static constexpr double kCell = 2.0;
  Eigen::Vector3d sun_, u_, v_;
  double range_, radius_;
  int n_ = 0;
  double x0_ = 0.0, y0_ = 0.0;
  std::vector<PreparedBox> boxes_;
  std::vector<std::vector<int>> cells_;
};

void validate(const RenderOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("RenderOptions: " + what); };
  if (!(o.max_range_m > 0.0)) fail("max_range_m must be > 0");
  if (!(o.light >= 0.0)) fail("light must be >= 0");
  if (!(o.ambient >= 0.0 && o.ambient <= 1.0)) fail("ambient must be in [0, 1]");
  if (!(o.sensor_noise >= 0.0)) fail("sensor_noise must be >= 0");
  if (!(o.haze_distance_m > 0.0)) fail("haze_distance_m must be > 0");
  if (!(o.shadow_range_m > 0.0)) fail("shadow_range_m must be > 0");
}

}  // namespace

CameraRenderer::CameraRenderer(const camera::CameraModel& camera, const RenderOptions& options)
    : camera_(camera), options_(options) {
  validate(options_);
  rays_vehicle_.reserve(static_cast<size_t>(camera.width()) * camera.height());
  for (int v = 0; v < camera.height(); ++v)
    for (int u = 0; u < camera.width(); ++u) rays_vehicle_.push_back(camera.rayVehicle({u, v}));
}

RenderedFrame CameraRenderer::render(const World& world, const Eigen::Isometry3d& vehicle_to_enu,
                                     int64_t ego_lanelet, uint64_t seed) const {
  const int width = camera_.width(), height = camera_.height();
  RenderedFrame frame;
  frame.rgb.create(height, width, CV_8UC3);
  frame.labels.create(height, width, CV_8UC1);
  frame.range.create(height, width, CV_32FC1);

  const Eigen::Matrix3d rotation = vehicle_to_enu.linear();
  const Eigen::Vector3d origin = vehicle_to_enu * camera_.opticalCentreVehicle();
  const Eigen::Vector3d sun = sunDirection(options_);
  const bool sun_up = options_.sun_elevation_deg > 0.0;
  const RenderOptions& o = options_;
  const uint64_t noise_seed = mix64(seed);
  // Per frame: the obstacles binned by azimuth from the optical centre, and the shadow grid.
  const ObstacleFan fan(world, origin, o.max_range_m);
  std::optional<ShadowGrid> shadows;
  if (o.shadows && sun_up) shadows.emplace(world, origin, sun, o);

  // Column by column, from the bottom of the image (the nearest ground) up: where the ray of the
  // pixel below was still above the ground up to some distance, this one is too (when it climbs
  // away from it faster than the ground can rise: clearanceCarriesOver), so its ground march starts
  // there. The columns are independent, so the frame does not depend on the thread count.
  cv::parallel_for_(cv::Range(0, width), [&](const cv::Range& columns) {
    for (int u = columns.start; u < columns.end; ++u) {
      double clear_below = 0.0;
      Eigen::Vector3d dir_below = Eigen::Vector3d::Zero();
      for (int v = height - 1; v >= 0; --v) {
        auto* bgr = frame.rgb.ptr<cv::Vec3b>(v);
        auto* label = frame.labels.ptr<uint8_t>(v);
        auto* range = frame.range.ptr<float>(v);
        const size_t index = static_cast<size_t>(v) * width + u;
        const Eigen::Vector3d dir = rotation * rays_vehicle_[index];
        const double clear_until =
            o.march_from_pixel_below && clear_below > 0.0 && clearanceCarriesOver(dir_below, dir, o.raycast.max_ground_slope)
                ? clear_below
                : 0.0;
        const RayHit hit = raycast(world, origin, dir, o.max_range_m, fan, o.raycast, clear_until);
        clear_below = hit.ground_clear;
        dir_below = dir;
        const uint64_t pixel_hash = mix64(noise_seed ^ (index * 0x2545f4914f6cdd1dULL));

        Rgb colour;
        LabelClass cls = LabelClass::kBackground;
        if (!hit.hit) {
          colour = skyColour(dir);
          range[u] = std::numeric_limits<float>::infinity();
        } else {
          range[u] = static_cast<float>(hit.range);
          Rgb albedo;
          Eigen::Vector3d normal;
          double lit = 1.0;
          if (hit.is_obstacle) {
            albedo = hit.obstacle->colour.cast<double>() *
                     (1.0 + 0.03 * cellNoise(hit.point.x() + hit.point.z(), hit.point.y(), 0.15, 21));
            normal = hit.normal;
          } else {
            albedo = groundColour(world, hit.ground, hit.point.x(), hit.point.y(), o);
            normal = groundNormalAt(world, hit.point);
            cls = labelFor(world, hit.ground, ego_lanelet);
            if (shadows) lit = shadows->visibility(hit.point, pixel_hash);
          }
          const double diffuse = sun_up ? std::max(0.0, normal.dot(sun)) * lit : 0.0;
          colour = albedo * (o.ambient + (1.0 - o.ambient) * kSunGain * diffuse);
          const double haze = 1.0 - std::exp(-hit.range / o.haze_distance_m);
          colour += haze * (skyColour(Eigen::Vector3d::UnitZ() * 0.05) - colour);
        }
        label[u] = static_cast<uint8_t>(cls);
        for (int c = 0; c < 3; ++c) {
          const double noise = o.sensor_noise * gaussFromHash(mix64(pixel_hash + c + 1));
          const double value = 255.0 * o.light * colour[2 - c] + noise;  // BGR
          bgr[u][c] = static_cast<uint8_t>(std::clamp(std::lround(value), 0L, 255L));
        }
      }
    }
  });
  return frame;
}

}  // namespace lanemap::sim
