// The world's surface: the terrain (grades, bumps) and a cross-section's road profile (crown,
// curbs). Part of buildWorld (core/sim/world_build.h).
#include "core/sim/world_build.h"

namespace lanemap::sim::world_build {

void Builder::makeTerrain() {
  if (o_.flat) return;
  auto r = rngFor(o_.seed, -1, 1);
  // Long waves: slope bound sum(A k) = max_grade; the bumps add little over a few metres.
  const int n = 4;
  std::vector<double> share(n);
  double tot = 0.0;
  for (auto& s : share) tot += (s = uni(r, 0.5, 1.0));
  for (int i = 0; i < n; ++i) {
    const double lambda = uni(r, 180.0, 700.0);
    const double k = 2.0 * kPi / lambda;
    const double th = uni(r, 0.0, 2.0 * kPi);
    detail::Terrain::Wave w;
    w.k = Vector2d(std::cos(th), std::sin(th)) * k;
    w.amplitude = o_.max_grade * share[i] / tot / k;
    w.phase = uni(r, 0.0, 2.0 * kPi);
    impl_->terrain.waves.push_back(w);
  }
  for (int i = 0; i < 2; ++i) {
    const double lambda = uni(r, 5.0, 11.0);
    const double th = uni(r, 0.0, 2.0 * kPi);
    detail::Terrain::Wave w;
    w.k = Vector2d(std::cos(th), std::sin(th)) * (2.0 * kPi / lambda);
    w.amplitude = o_.bump_amplitude_m / 2.0;
    w.phase = uni(r, 0.0, 2.0 * kPi);
    impl_->terrain.waves.push_back(w);
  }
}

double Builder::profileAt(const CrossSection& xs, double s, double d, double left_curb, double right_curb) const {
  if (o_.flat) return 0.0;
  const double fade = geom::smoothstep(std::min(s - xs.sb, xs.se - s) / kCrownFadeM);
  if (d <= left_curb + 1e-9 && d >= right_curb - 1e-9) return -o_.crown_slope * std::abs(d) * fade;
  const double edge = d > left_curb ? left_curb : right_curb;
  return -o_.crown_slope * std::abs(edge) * fade + o_.curb_height_m;
}

}  // namespace lanemap::sim::world_build
