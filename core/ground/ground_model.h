// Ground models for the BEV projection (METHOD.md section 3): where a camera ray meets the road.
//
// - FlatGround: a plane. The baseline of the paper is the plane the car stands on (the vehicle
//   frame's z = 0 plane: its wheels define it, so roll and pitch of the car tilt it), which is the
//   classic inverse perspective mapping; FlatGround::underVehicle builds it from the pose.
//   It is wrong wherever the road is not that plane: a crowned cross-section, a change of grade
//   ahead (a few decimetres of height at 20 m move a projected pixel by metres along the ray,
//   because the ray meets the ground at a grazing angle of a few degrees).
// - MeshGround (ground_mesh.h): the topographic model, a 2.5D Delaunay mesh of the LIDAR's ground
//   points; rays are intersected with its triangles.
//
// Every model answers the same question, so the Projector takes any of them.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>

namespace lanemap::ground {

class GroundModel {
 public:
  virtual ~GroundModel() = default;
  // Ray parameter t (> 0, <= max_t) of the first intersection of origin + t * dir with the ground
  // (dir need not be unit; t is in units of |dir|), or nullopt when the ray meets no ground there.
  virtual std::optional<double> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                          double max_t) const = 0;
};

// An infinite plane through `point` with normal `normal` (any length, pointing up).
class FlatGround : public GroundModel {
 public:
  FlatGround(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
  // The plane the vehicle stands on (its frame's z = 0), in the frame vehicle_to_enu maps into.
  static FlatGround underVehicle(const Eigen::Isometry3d& vehicle_to_enu);

  std::optional<double> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                  double max_t) const override;
  // Height of the plane above (east, north); the plane must not be vertical.
  double heightAt(double east, double north) const;
  const Eigen::Vector3d& point() const { return point_; }
  const Eigen::Vector3d& normal() const { return normal_; }

 private:
  Eigen::Vector3d point_;
  Eigen::Vector3d normal_;  // unit
};

}  // namespace lanemap::ground
