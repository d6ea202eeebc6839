// Centre-line regression (METHOD.md section 4, the paper's Eq. 6): a continuous piecewise-linear
// function d = f(s) whose break points minimise the summed squared residual of the particle
// positions, smoothed by a natural cubic spline through its knots, so the centre line is C2 and
// can be evaluated and differentiated at any arc length s of the road's Frenet frame.
#pragma once

#include <cstddef>
#include <vector>

namespace lanemap::lanes {

// Natural cubic spline through (x_i, y_i), x strictly increasing; linear beyond the ends (the
// natural end condition y'' = 0 continued). One knot gives a constant.
class NaturalSpline {
 public:
  NaturalSpline() = default;
  NaturalSpline(std::vector<double> x, std::vector<double> y);  // throws LanesError
  double operator()(double x) const;
  double derivative(double x) const;
  double secondDerivative(double x) const;
  const std::vector<double>& knots() const { return x_; }
  const std::vector<double>& values() const { return y_; }
  bool empty() const { return x_.empty(); }

 private:
  size_t segment(double x) const;
  std::vector<double> x_, y_, m_;  // m_ = second derivatives at the knots
};

// Data for the regression: particle positions binned along s. Minimising Eq. 6 over the
// particles equals minimising the count-weighted squared residual of the bin means (the
// within-bin scatter does not depend on f), so binning loses nothing.
struct BinnedSamples {
  std::vector<double> s;       // bin centres, increasing
  std::vector<double> mean;    // mean d in the bin
  std::vector<double> weight;  // particle count in the bin
};

struct PiecewiseLinearFit {
  std::vector<double> knots;   // break points b_i, including both ends
  std::vector<double> values;  // f at the knots (continuous)
  double sse = 0.0;            // weighted squared residual of the bin means (weights / mean weight)
  double operator()(double s) const;  // f(s), linear beyond the end knots
};

// Optimises the break points over candidates every `break_spacing` (dynamic programming over
// segmentations, each segment a least-squares line, with `penalty` per additional segment so a
// break is only taken when it pays), then solves the continuous piecewise-linear least squares
// on the chosen breaks. Throws LanesError without data.
PiecewiseLinearFit fitPiecewiseLinear(const BinnedSamples& data, double break_spacing, double penalty);

// A lane's centre line in the road's Frenet frame: d(s) for s in [s_begin, s_end].
class CentreLine {
 public:
  CentreLine() = default;
  // The natural spline's knots: the break points plus samples of f every ~knot_spacing between.
  CentreLine(const PiecewiseLinearFit& fit, double s_begin, double s_end, double knot_spacing = 5.0);
  double sBegin() const { return s0_; }
  double sEnd() const { return s1_; }
  double d(double s) const { return spline_(s); }
  double dPrime(double s) const { return spline_.derivative(s); }
  const NaturalSpline& spline() const { return spline_; }
  const PiecewiseLinearFit& piecewiseLinear() const { return fit_; }

 private:
  PiecewiseLinearFit fit_;
  NaturalSpline spline_;
  double s0_ = 0.0, s1_ = 0.0;
};

}  // namespace lanemap::lanes
