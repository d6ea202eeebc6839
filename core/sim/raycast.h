// Ray casting against a simulated World: the nearest hit of a ray on the ground heightfield or on a
// box obstacle. The simulator's camera (one ray per pixel) and LIDAR (one per laser firing) use it.
//
// Ground: the ray is marched with steps bounded by the ground's maximum slope (a Lipschitz bound:
// the ray cannot reach the ground before it has dropped by its current height above it), never
// shorter than min_step + step_growth * distance, and the first sign change of
// (ray height - ground height) is refined by the Illinois (secant/regula falsi) method until the
// point is within 0.1 * tolerance_m of the surface vertically. With the default steps a crest of
// curvature k is crossed unseen only where it pokes above the ray by < k * step^2 / 8 (< 1 mm for
// 4 cm bumps every 4 m out to 100 m). ~10 World::height calls per camera ray on average.
// Obstacles: yaw-rotated boxes, slab test in the box frame, queried from World::obstaclesNear in
// chunks along the ray, or, for many rays from one point (a camera frame, a LIDAR sweep), taken
// from an ObstacleFan built once.
#pragma once

#include "core/sim/world.h"

#include <Eigen/Core>

#include <limits>
#include <vector>

namespace lanemap::sim {

struct RaycastOptions {
  // Steepest ground slope the marcher assumes (rise over run): 10 % grade, 2 % crown and bumps of a
  // few cm over metres stay well under 0.2. Steeper ground (e.g. a curb step) is still found by
  // the sign-change test, only with the min-step resolution.
  double max_ground_slope = 0.2;
  double min_step_m = 0.02;      // shortest march step
  double step_growth = 0.002;    // + this fraction of the distance travelled (far rays step longer)
  double tolerance_m = 1e-3;     // refine the ground hit until the bracket is this short (metres)
  double obstacle_chunk_m = 20.0;  // length of the ray pieces used to query obstaclesNear
  bool ground = true;            // test the ground
  bool obstacles = true;         // test obstacles
};

struct RayHit {
  bool hit = false;
  double range = std::numeric_limits<double>::infinity();  // metres along the unit ray
  Eigen::Vector3d point = Eigen::Vector3d::Zero();         // ENU
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();       // outward unit normal at the hit (obstacle
                                                           // faces; +Up for ground: see groundNormal)
  bool is_obstacle = false;
  const Obstacle* obstacle = nullptr;  // the box hit (when is_obstacle)
  GroundSample ground;                 // the ground sample at the hit (when !is_obstacle)
  // How far along the ray it was found above the ground (raycast over an ObstacleFan): just short
  // of the ground crossing, where the march gave up behind a box, or max_range / infinity.
  double ground_clear = 0.0;
};

// The nearest hit within (0, max_range]; hit=false when none. `unit_dir_enu` must be unit length.
RayHit raycast(const World& world, const Eigen::Vector3d& origin_enu,
               const Eigen::Vector3d& unit_dir_enu, double max_range,
               const RaycastOptions& options = RaycastOptions());

// An obstacle with its yaw's sine and cosine precomputed (the slab test then needs no trig).
struct PreparedBox {
  const Obstacle* obstacle = nullptr;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d half_extent = Eigen::Vector3d::Ones();
  double cos_yaw = 1.0, sin_yaw = 0.0;
  // Radius of a sphere about the centre holding the box (a little over |half_extent|): a ray that
  // passes farther from the centre cannot enter the box (missesBound).
  double bound_radius = 0.0;
  explicit PreparedBox(const Obstacle& o);
  // True when the ray from `origin` along `unit_dir` cannot enter the box within (0, t_max]: it
  // passes outside the bounding sphere, or the sphere lies wholly behind the origin or beyond
  // t_max. Conservative (never true for a ray intersectBox would find), and a few multiplies
  // against intersectBox's rotation and three divisions.
  bool missesBound(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_dir, double t_max) const {
    const Eigen::Vector3d rel = centre - origin;
    const double along = rel.dot(unit_dir);
    if (along < -bound_radius || along - bound_radius > t_max) return true;
    return rel.squaredNorm() - along * along > bound_radius * bound_radius;
  }
};

// The obstacles around one viewpoint, binned by the azimuth range they cover as seen from it, for
// many rays from (about) that point: a camera frame (all rays from one optical centre) or a LIDAR
// sweep (the sensor moves by `origin_slack` metres at most during it). A ray then tests only the
// boxes of its azimuth bin instead of querying World::obstaclesNear along its length. Exact: the
// bins are conservative (boxes grown by the slack, one spare bin each side).
class ObstacleFan {
 public:
  ObstacleFan(const World& world, const Eigen::Vector3d& origin_enu, double max_range,
              double origin_slack = 0.0, double bin_deg = 0.25);
  // Boxes a ray from within origin_slack of the origin along `unit_dir` may hit within max_range.
  const std::vector<int>& candidates(const Eigen::Vector3d& unit_dir) const;
  const std::vector<PreparedBox>& boxes() const { return boxes_; }

 private:
  std::vector<PreparedBox> boxes_;
  std::vector<std::vector<int>> bins_;  // box indices per azimuth bin
  std::vector<int> all_;                // every box (for vertical rays)
  double bin_rad_;
};

// As raycast() above, the obstacles taken from a prepared fan (no World::obstaclesNear calls).
// `clear_until` > 0: the ray is known to be above the ground before that distance (see
// clearanceCarriesOver), so the ground march starts there instead of at the origin (and at the
// origin after all if the ray is not above the ground there). The hit is then the same crossing
// found from another bracket (the same surface point to within options.tolerance_m), except on a
// ray that grazes the ground, where the other march's samples may catch (or step over) a crest the
// ray passes under by less than the march resolves (see above: < 1 mm).
RayHit raycast(const World& world, const Eigen::Vector3d& origin_enu,
               const Eigen::Vector3d& unit_dir_enu, double max_range, const ObstacleFan& fan,
               const RaycastOptions& options = RaycastOptions(), double clear_until = 0.0);

// Rays from one origin: where the ray `below` is above the ground up to distance T, the ray `above`
// is too, when it climbs away from `below` faster than ground of slope max_ground_slope can rise
// over the horizontal distance between them (rise >= slope * apart, per metre of ray): the same
// slope bound the march itself relies on. A camera column (rays from the bottom of the image up)
// then starts each ray's march where the ray below it was still above the ground.
bool clearanceCarriesOver(const Eigen::Vector3d& below_unit_dir, const Eigen::Vector3d& above_unit_dir,
                          double max_ground_slope);

// Ground only: distance to the first ground crossing (infinity when none within max_range).
double raycastGround(const World& world, const Eigen::Vector3d& origin_enu,
                     const Eigen::Vector3d& unit_dir_enu, double max_range,
                     const RaycastOptions& options = RaycastOptions());

// Entry distance of a ray into a (yaw-rotated) box, in [t_min, t_max]; infinity when it misses.
// `normal` (optional) receives the outward normal of the face entered (ENU).
double intersectBox(const Obstacle& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                    double t_min, double t_max, Eigen::Vector3d* normal = nullptr);

double intersectBox(const PreparedBox& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                    double t_min, double t_max, Eigen::Vector3d* normal = nullptr);

// Unit ground normal at (east, north) by central differences of World::height over +-h metres.
Eigen::Vector3d groundNormal(const World& world, double east, double north, double h = 0.05);

}  // namespace lanemap::sim
