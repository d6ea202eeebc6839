// Ray casting against the simulated World: heightfield marching + secant refinement, box slabs.
#include "core/sim/raycast.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace lanemap::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Height of the ray above the ground at distance t (negative: below the ground).
struct GroundGap {
  const World& world;
  const Eigen::Vector3d& o;
  const Eigen::Vector3d& d;
  double operator()(double t) const {
    return o.z() + t * d.z() - world.height(o.x() + t * d.x(), o.y() + t * d.y());
  }
};

// Illinois regula falsi on a bracket [a, b] with gap(a) > 0 >= gap(b).
double refineCrossing(const GroundGap& gap, double a, double fa, double b, double fb, double tol) {
  int side = 0;
  double c = b;
  for (int iter = 0; iter < 64; ++iter) {
    c = (fa - fb) != 0.0 ? (a * fb - b * fa) / (fb - fa) : 0.5 * (a + b);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    const double fc = gap(c);
    // 0.1 tolerance vertically: the point lies on the surface to well under the asked tolerance.
    if (std::abs(fc) < 0.1 * tol) return c;
    if (fc > 0.0) {
      a = c;
      fa = fc;
      if (side == 1) fb *= 0.5;
      side = 1;
    } else {
      b = c;
      fb = fc;
      if (side == -1) fa *= 0.5;
      side = -1;
    }
    if (b - a < tol) return (a * fb - b * fa) / (fb - fa);
  }
  return c;
}

double marchGround(const World& world, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                   double max_range, const RaycastOptions& opt, double give_up_after, double start = 0.0,
                   double* clear = nullptr);

}  // namespace

double raycastGround(const World& world, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double max_range, const RaycastOptions& opt) {
  return marchGround(world, o, d, max_range, opt, kInf);
}

namespace {

// The ground march of raycastGround, which may give up early: once the ray is known to be above
// the ground beyond `give_up_after` it returns +infinity (the crossing, if any, is farther). The
// march visits the same points whatever `give_up_after` is, so a crossing it does return is the
// one raycastGround returns, to the bit. It starts at `start` (the caller knows the ray is above
// the ground before it; see raycast's clear_until), or at 0 when the ray is not above the ground
// there after all. `clear` (optional) receives how far the ray was found above the ground: the
// last marched point before the crossing, the point where it gave up, or max_range.
double marchGround(const World& world, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                   double max_range, const RaycastOptions& opt, double give_up_after, double start,
                   double* clear) {
  const GroundGap gap{world, o, d};
  double scratch = 0.0;
  double& clear_until = clear ? *clear : scratch;
  double t = 0.0;
  double f = 0.0;
  if (start > 0.0 && start < max_range) {
    t = start;
    f = gap(t);
    if (!(f > 0.0)) t = 0.0;  // the hint does not hold here: march from the origin
  }
  if (t == 0.0) f = gap(0.0);
  clear_until = t;
  if (!(f > 0.0)) return 0.0;  // starts on or under the ground
  const double horizontal = std::hypot(d.x(), d.y());
  // The fastest the gap can shrink per metre of ray: the ray's descent plus the ground's rise.
  const double closing_rate = opt.max_ground_slope * horizontal - d.z();
  if (closing_rate <= 0.0) {  // rises faster than any ground can
    clear_until = kInf;
    return kInf;
  }
  while (t < max_range) {
    const double step = std::max(f / closing_rate, opt.min_step_m + opt.step_growth * t);
    const double t_next = std::min(t + step, max_range);
    const double f_next = gap(t_next);
    if (f_next <= 0.0) return refineCrossing(gap, t, f, t_next, f_next, opt.tolerance_m);
    t = t_next;
    f = f_next;
    clear_until = t;
    if (t > give_up_after) return kInf;
  }
  return kInf;
}

}  // namespace

PreparedBox::PreparedBox(const Obstacle& o)
    : obstacle(&o),
      centre(o.centre),
      half_extent(o.half_extent),
      cos_yaw(std::cos(o.yaw)),
      sin_yaw(std::sin(o.yaw)),
      // The margin covers the rounding of missesBound's dot products (relative 1e-15 of distances
      // up to kilometres: under a micrometre).
      bound_radius(o.half_extent.norm() * (1.0 + 1e-9) + 1e-6) {}

double intersectBox(const PreparedBox& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                    double t_min, double t_max, Eigen::Vector3d* normal) {
  const double c = box.cos_yaw, s = box.sin_yaw;
  const Eigen::Vector3d rel = origin - box.centre;
  // Into the box frame: R(yaw)^T.
  const double p[3] = {c * rel.x() + s * rel.y(), -s * rel.x() + c * rel.y(), rel.z()};
  const double q[3] = {c * dir.x() + s * dir.y(), -s * dir.x() + c * dir.y(), dir.z()};
  double enter = t_min, leave = t_max;
  int axis = -1;
  double axis_sign = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double h = box.half_extent[i];
    if (std::abs(q[i]) < 1e-15) {
      if (std::abs(p[i]) > h) return kInf;
      continue;
    }
    const double inv = 1.0 / q[i];
    double t1 = (-h - p[i]) * inv, t2 = (h - p[i]) * inv;
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > enter) {
      enter = t1;
      axis = i;
      axis_sign = q[i] > 0.0 ? -1.0 : 1.0;  // the face entered looks against the ray
    }
    leave = std::min(leave, t2);
    if (enter > leave) return kInf;
  }
  if (normal) {
    if (axis < 0) {
      *normal = -dir;  // the ray starts inside the box
    } else {
      Eigen::Vector3d nb = Eigen::Vector3d::Zero();
      nb[axis] = axis_sign;
      *normal = Eigen::Vector3d(c * nb.x() - s * nb.y(), s * nb.x() + c * nb.y(), nb.z());
    }
  }
  return enter;
}

double intersectBox(const Obstacle& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                    double t_min, double t_max, Eigen::Vector3d* normal) {
  return intersectBox(PreparedBox(box), origin, dir, t_min, t_max, normal);
}

ObstacleFan::ObstacleFan(const World& world, const Eigen::Vector3d& origin, double max_range,
                         double origin_slack, double bin_deg)
    : bin_rad_(bin_deg * M_PI / 180.0) {
  if (!(bin_deg > 0.0 && bin_deg <= 90.0)) throw std::invalid_argument("ObstacleFan: bin_deg must be in (0, 90]");
  const int nbins = static_cast<int>(std::ceil(2.0 * M_PI / bin_rad_));
  bins_.assign(nbins, {});
  std::vector<const Obstacle*> near;
  world.obstaclesNear(origin.head<2>(), max_range + origin_slack, &near);
  for (const Obstacle* o : near) {
    const int index = static_cast<int>(boxes_.size());
    boxes_.emplace_back(*o);
    all_.push_back(index);
    const PreparedBox& b = boxes_.back();
    // The footprint grown by the slack: a superset of what any origin within the slack sees.
    const double hx = b.half_extent.x() + origin_slack, hy = b.half_extent.y() + origin_slack;
    const Eigen::Vector2d rel = origin.head<2>() - b.centre.head<2>();
    const double lx = b.cos_yaw * rel.x() + b.sin_yaw * rel.y(), ly = -b.sin_yaw * rel.x() + b.cos_yaw * rel.y();
    if (std::abs(lx) <= hx + 1e-6 && std::abs(ly) <= hy + 1e-6) {  // the origin stands in it
      for (auto& bin : bins_) bin.push_back(index);
      continue;
    }
    // Azimuths of the four corners relative to the centre's azimuth (the span is < 180 deg).
    const Eigen::Vector2d to_centre = -rel;
    const double a0 = std::atan2(to_centre.y(), to_centre.x());
    double lo = 0.0, hi = 0.0;
    for (int k = 0; k < 4; ++k) {
      const double cx = (k & 1 ? hx : -hx), cy = (k & 2 ? hy : -hy);
      const Eigen::Vector2d corner(b.centre.x() + b.cos_yaw * cx - b.sin_yaw * cy - origin.x(),
                                   b.centre.y() + b.sin_yaw * cx + b.cos_yaw * cy - origin.y());
      double a = std::atan2(corner.y(), corner.x()) - a0;
      a = std::remainder(a, 2.0 * M_PI);
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
    const int first = static_cast<int>(std::floor((a0 + lo) / bin_rad_)) - 1;
    const int last = static_cast<int>(std::floor((a0 + hi) / bin_rad_)) + 1;
    for (int k = first; k <= last && k - first < nbins; ++k) bins_[((k % nbins) + nbins) % nbins].push_back(index);
  }
}

const std::vector<int>& ObstacleFan::candidates(const Eigen::Vector3d& d) const {
  if (d.x() * d.x() + d.y() * d.y() < 1e-18) return all_;
  const int nbins = static_cast<int>(bins_.size());
  const int k = static_cast<int>(std::floor(std::atan2(d.y(), d.x()) / bin_rad_));
  return bins_[((k % nbins) + nbins) % nbins];
}

namespace {

// The ray's hit at range `best` (none beyond max_range): the obstacle found, unless the ground
// (at ground_range) is as near; a ground hit carries the surface sampled there.
RayHit finishHit(RayHit hit, double best, double ground_range, const World& world, const Eigen::Vector3d& o,
                 const Eigen::Vector3d& d, double max_range) {
  if (!(best <= max_range)) return hit;
  hit.hit = true;
  hit.range = best;
  hit.point = o + best * d;
  if (!hit.is_obstacle || best >= ground_range) {
    hit.is_obstacle = false;
    hit.obstacle = nullptr;
    hit.normal = Eigen::Vector3d::UnitZ();
    hit.ground = world.sample(hit.point.x(), hit.point.y());
  }
  return hit;
}

}  // namespace

RayHit raycast(const World& world, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range,
               const ObstacleFan& fan, const RaycastOptions& opt, double clear_until) {
  // The nearest box first (the same box, entry and normal the ground-first order finds when it is
  // nearer than the ground: its entry does not depend on the range limit), then the ground march,
  // which gives up once it is past that box (1 um margin, far above the rounding of a crossing
  // inside its bracket): a ray into a building no longer marches the ground behind it to
  // max_range. Where the ground is hit first, the march and so the hit are the same as before.
  RayHit hit;
  double obstacle_range = kInf;
  if (opt.obstacles) {
    for (const int i : fan.candidates(d)) {
      Eigen::Vector3d n;
      const PreparedBox& box = fan.boxes()[i];
      const double t_max = std::min(obstacle_range, max_range);
      if (box.missesBound(o, d, t_max)) continue;
      const double t = intersectBox(box, o, d, 0.0, t_max, &n);
      if (t < obstacle_range) {
        obstacle_range = t;
        hit.is_obstacle = true;
        hit.obstacle = box.obstacle;
        hit.normal = n;
      }
    }
  }
  const double give_up = hit.is_obstacle ? obstacle_range + 1e-6 : kInf;
  double clear = 0.0;
  const double ground_range = opt.ground ? marchGround(world, o, d, max_range, opt, give_up, clear_until, &clear) : kInf;
  double best = ground_range;
  if (hit.is_obstacle && obstacle_range < ground_range) {
    best = obstacle_range;
  } else {
    hit = RayHit();  // the ground is as near: no box
  }
  hit = finishHit(hit, best, ground_range, world, o, d, max_range);
  hit.ground_clear = opt.ground ? clear : kInf;
  return hit;
}

bool clearanceCarriesOver(const Eigen::Vector3d& below, const Eigen::Vector3d& above, double max_ground_slope) {
  // rise >= slope * apart, squared (no hypot per camera pixel; both sides are >= 0).
  const double rise = above.z() - below.z();
  const double dx = above.x() - below.x(), dy = above.y() - below.y();
  return rise > 0.0 && rise * rise >= max_ground_slope * max_ground_slope * (dx * dx + dy * dy);
}

RayHit raycast(const World& world, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
               double max_range, const RaycastOptions& opt) {
  RayHit hit;
  double best = kInf;
  if (opt.ground) best = raycastGround(world, o, d, max_range, opt);
  const double ground_range = best;

  if (opt.obstacles) {
    thread_local std::vector<const Obstacle*> nearby;
    const double horizontal = std::hypot(d.x(), d.y());
    const double end = std::min(best, max_range);
    const double chunk = std::max(opt.obstacle_chunk_m, 1e-3);
    for (double c0 = 0.0; c0 < end; c0 += chunk) {
      const double c1 = std::min(c0 + chunk, end);
      const double mid = 0.5 * (c0 + c1);
      const Eigen::Vector2d centre(o.x() + mid * d.x(), o.y() + mid * d.y());
      nearby.clear();
      world.obstaclesNear(centre, 0.5 * (c1 - c0) * horizontal + 1e-3, &nearby);
      for (const Obstacle* box : nearby) {
        Eigen::Vector3d n;
        const double t = intersectBox(*box, o, d, 0.0, std::min(best, max_range), &n);
        if (t < best) {
          best = t;
          hit.is_obstacle = true;
          hit.obstacle = box;
          hit.normal = n;
        }
      }
      if (best <= c1) break;  // any nearer box would have been returned by this or an earlier chunk
    }
  }

  return finishHit(hit, best, ground_range, world, o, d, max_range);
}

Eigen::Vector3d groundNormal(const World& world, double east, double north, double h) {
  const double dzde = (world.height(east + h, north) - world.height(east - h, north)) / (2.0 * h);
  const double dzdn = (world.height(east, north + h) - world.height(east, north - h)) / (2.0 * h);
  return Eigen::Vector3d(-dzde, -dzdn, 1.0).normalized();
}

}  // namespace lanemap::sim
