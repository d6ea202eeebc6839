// The pieces of lane exploration: DBSCAN (2D and 1D agree), the natural cubic spline, the
// piecewise-linear regression with optimised break points (Eq. 6), the Frenet frame, options.
#include "core/lanes/centre_line.h"
#include "core/lanes/dbscan.h"
#include "core/lanes/frenet.h"
#include "core/lanes/options.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using namespace lanemap::lanes;

TEST(Dbscan, FindsLanesAndNoise) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  std::vector<Eigen::Vector2d> pts;
  std::vector<double> d;
  for (double c : {-5.25, -1.75, 1.75}) {
    for (int i = 0; i < 100; ++i) {
      pts.emplace_back(0.0, c + u(rng));
      d.push_back(pts.back().y());
    }
  }
  pts.emplace_back(0.0, 8.0);  // a lone particle
  d.push_back(8.0);
  int k2 = 0, k1 = 0;
  const auto a = dbscan(pts, 1.0, 4, &k2);
  const auto b = dbscan1d(d, 1.0, 4, &k1);
  EXPECT_EQ(k2, 3);
  EXPECT_EQ(k1, 3);
  EXPECT_EQ(a.back(), -1);
  EXPECT_EQ(b.back(), -1);
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    EXPECT_EQ(a[i], static_cast<int>(i / 100));  // clusters numbered in input order
    EXPECT_EQ(b[i], static_cast<int>(i / 100));  // and in increasing d
  }
}

TEST(NaturalSpline, InterpolatesWithZeroEndCurvature) {
  std::vector<double> x{0, 2, 3, 7, 10}, y{1, -1, 0.5, 2, 0};
  const NaturalSpline sp(x, y);
  for (size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(sp(x[i]), y[i], 1e-12);
  EXPECT_NEAR(sp.secondDerivative(1e-9), 0.0, 1e-6);
  EXPECT_NEAR(sp.secondDerivative(10 - 1e-9), 0.0, 1e-6);
  for (double s = 0.1; s < 10; s += 0.37) {
    EXPECT_NEAR(sp.derivative(s), (sp(s + 1e-6) - sp(s - 1e-6)) / 2e-6, 1e-5);
  }
  EXPECT_NEAR(sp(12.0), y.back() + 2.0 * sp.derivative(10.0), 1e-9);  // linear beyond the end
  EXPECT_THROW(NaturalSpline({0, 0}, {1, 2}), LanesError);
}

TEST(PiecewiseLinear, RecoversBreakPoints) {
  // d(s): flat at -1.75 to s = 60, moves 3.3 m left until s = 75, flat after (a pocket taper).
  BinnedSamples b;
  std::mt19937_64 rng(2);
  std::normal_distribution<double> noise(0.0, 0.03);
  auto f = [](double s) { return s < 60 ? -1.75 : s < 75 ? -1.75 + 3.3 * (s - 60) / 15 : 1.55; };
  for (double s = 0.5; s < 150; s += 1.0) {
    b.s.push_back(s);
    b.mean.push_back(f(s) + noise(rng));
    b.weight.push_back(100);
  }
  const auto fit = fitPiecewiseLinear(b, 5.0, 0.3);
  ASSERT_EQ(fit.knots.size(), 4u);
  EXPECT_NEAR(fit.knots[1], 60.0, 3.0);
  EXPECT_NEAR(fit.knots[2], 75.0, 3.0);
  const CentreLine cl(fit, 0.0, 150.0);
  double sq = 0;
  for (double s : b.s) sq += std::pow(cl.d(s) - f(s), 2);
  EXPECT_LT(std::sqrt(sq / b.s.size()), 0.1);
  // A straight lane needs no break at all (the penalty keeps noise from adding some).
  for (auto& m : b.mean) m = -1.75 + noise(rng);
  EXPECT_EQ(fitPiecewiseLinear(b, 5.0, 0.3).knots.size(), 2u);
}

TEST(FrenetFrame, RoundTripOnACurve) {
  std::vector<Eigen::Vector2d> poly;
  for (int i = 0; i <= 20; ++i) {
    const double a = i * 0.05;
    poly.emplace_back(100 * std::sin(a), 100 * (1 - std::cos(a)));  // left turn, R = 100 m
  }
  const FrenetFrame f(poly, 0.5, 6.0);
  for (double s = 5; s < f.length() - 5; s += 7.3) {
    for (double d : {-6.0, -1.0, 0.0, 2.5, 8.0}) {
      const Eigen::Vector2d p = f.toEnu(s, d);
      const Eigen::Vector2d sd = f.toFrenet(p);
      EXPECT_NEAR(sd.x(), s, 1e-6);
      EXPECT_NEAR(sd.y(), d, 1e-6);
    }
    // Chords (sagitta 3 cm) and the 6 m moving average keep the reference within 0.1 m of the arc.
    EXPECT_NEAR((f.point(s) - Eigen::Vector2d(0, 100)).norm(), 100.0, 0.1);
  }
  EXPECT_GT(f.normal(10).y(), 0.9);  // left of the driving direction (east) is north
}

TEST(ExplorerOptions, YamlDefaultsAndErrors) {
  const auto o = ExplorerOptions::fromYaml(YAML::Load("num_particles: 800\ndbscan_eps_m: 0.8"));
  EXPECT_EQ(o.num_particles, 800);
  EXPECT_DOUBLE_EQ(o.dbscan_eps_m, 0.8);
  EXPECT_DOUBLE_EQ(o.footprint_length_m, 3.0);
  EXPECT_THROW(ExplorerOptions::fromYaml(YAML::Load("num_particle: 800")), LanesError);
  EXPECT_THROW(ExplorerOptions::fromYaml(YAML::Load("v_min: 2.0\nv_max: 1.0")), LanesError);
  EXPECT_THROW(ExplorerOptions::fromYaml(YAML::Load("dt_s: fast")), LanesError);
  // The shipped config is the paper's parameters.
  const auto c = ExplorerOptions::fromYaml(YAML::LoadFile(std::string(LANEMAP_SOURCE_DIR) + "/config/lane_mapper.yaml")["explorer"]);
  EXPECT_EQ(c.num_particles, 500);
  EXPECT_DOUBLE_EQ(c.w_max, 0.2);
  EXPECT_DOUBLE_EQ(c.dbscan_eps_m, 1.0);
}

}  // namespace
