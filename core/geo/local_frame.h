// Local ENU frame: WGS84 <-> east/north/up metres around one origin (GeographicLib LocalCartesian).
#pragma once

#include <Eigen/Core>

#include <memory>

namespace GeographicLib { class LocalCartesian; }

namespace lanemap::geo {

struct LatLonAlt {
  double lat = 0.0;  // degrees
  double lon = 0.0;  // degrees
  double alt = 0.0;  // metres above the WGS84 ellipsoid
};

// One origin per map; every coordinate in core is ENU metres of such a frame.
class LocalFrame {
 public:
  explicit LocalFrame(const LatLonAlt& origin);
  LocalFrame(const LocalFrame& other);
  LocalFrame& operator=(const LocalFrame& other);
  ~LocalFrame();

  const LatLonAlt& origin() const { return origin_; }
  Eigen::Vector3d toEnu(const LatLonAlt& p) const;
  Eigen::Vector3d toEnu(double lat, double lon, double alt = 0.0) const;
  LatLonAlt toWgs84(const Eigen::Vector3d& enu) const;

 private:
  LatLonAlt origin_;
  std::unique_ptr<GeographicLib::LocalCartesian> cartesian_;
};

}  // namespace lanemap::geo
