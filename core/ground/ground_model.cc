#include "core/ground/ground_model.h"

#include <cmath>
#include <stdexcept>

namespace lanemap::ground {

FlatGround::FlatGround(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) : point_(point) {
  const double n = normal.norm();
  if (!(n > 0.0) || !std::isfinite(n)) throw std::invalid_argument("FlatGround: normal must be non-zero");
  normal_ = normal / n;
}

FlatGround FlatGround::underVehicle(const Eigen::Isometry3d& vehicle_to_enu) {
  return FlatGround(vehicle_to_enu.translation(), vehicle_to_enu.linear().col(2));
}

std::optional<double> FlatGround::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                            double max_t) const {
  const double denom = normal_.dot(dir);
  if (std::abs(denom) < 1e-12) return std::nullopt;  // parallel
  const double t = normal_.dot(point_ - origin) / denom;
  if (!(t > 0.0) || t > max_t) return std::nullopt;
  return t;
}

double FlatGround::heightAt(double east, double north) const {
  return point_.z() - (normal_.x() * (east - point_.x()) + normal_.y() * (north - point_.y())) / normal_.z();
}

}  // namespace lanemap::ground
