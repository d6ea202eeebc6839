#include "core/geo/local_frame.h"

#include <GeographicLib/LocalCartesian.hpp>

namespace lanemap::geo {

LocalFrame::LocalFrame(const LatLonAlt& origin)
    : origin_(origin),
      cartesian_(std::make_unique<GeographicLib::LocalCartesian>(origin.lat, origin.lon, origin.alt)) {}

LocalFrame::LocalFrame(const LocalFrame& other) : LocalFrame(other.origin_) {}

LocalFrame& LocalFrame::operator=(const LocalFrame& other) {
  if (this != &other) {
    origin_ = other.origin_;
    cartesian_ = std::make_unique<GeographicLib::LocalCartesian>(origin_.lat, origin_.lon, origin_.alt);
  }
  return *this;
}

LocalFrame::~LocalFrame() = default;

Eigen::Vector3d LocalFrame::toEnu(const LatLonAlt& p) const { return toEnu(p.lat, p.lon, p.alt); }

Eigen::Vector3d LocalFrame::toEnu(double lat, double lon, double alt) const {
  Eigen::Vector3d enu;
  cartesian_->Forward(lat, lon, alt, enu.x(), enu.y(), enu.z());
  return enu;
}

LatLonAlt LocalFrame::toWgs84(const Eigen::Vector3d& enu) const {
  LatLonAlt p;
  cartesian_->Reverse(enu.x(), enu.y(), enu.z(), p.lat, p.lon, p.alt);
  return p;
}

}  // namespace lanemap::geo
