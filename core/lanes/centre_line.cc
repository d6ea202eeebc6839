#include "core/lanes/centre_line.h"

#include "core/lanes/options.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace lanemap::lanes {

NaturalSpline::NaturalSpline(std::vector<double> x, std::vector<double> y) : x_(std::move(x)), y_(std::move(y)) {
  if (x_.empty() || x_.size() != y_.size()) throw LanesError("spline: need as many values as knots (>= 1)");
  for (size_t i = 1; i < x_.size(); ++i) {
    if (!(x_[i] > x_[i - 1])) throw LanesError("spline: knots must increase strictly");
  }
  const size_t n = x_.size();
  m_.assign(n, 0.0);
  if (n < 3) return;
  // Tridiagonal system for the interior second derivatives (Thomas algorithm), m_0 = m_n-1 = 0.
  std::vector<double> a(n, 0.0), b(n, 0.0), c(n, 0.0), r(n, 0.0);
  for (size_t i = 1; i + 1 < n; ++i) {
    const double h0 = x_[i] - x_[i - 1], h1 = x_[i + 1] - x_[i];
    a[i] = h0 / 6.0;
    b[i] = (h0 + h1) / 3.0;
    c[i] = h1 / 6.0;
    r[i] = (y_[i + 1] - y_[i]) / h1 - (y_[i] - y_[i - 1]) / h0;
  }
  for (size_t i = 2; i + 1 < n; ++i) {
    const double f = a[i] / b[i - 1];
    b[i] -= f * c[i - 1];
    r[i] -= f * r[i - 1];
  }
  for (size_t i = n - 2; i >= 1; --i) {
    m_[i] = (r[i] - (i + 2 < n ? c[i] * m_[i + 1] : 0.0)) / b[i];
    if (i == 1) break;
  }
}

size_t NaturalSpline::segment(double x) const {
  const auto it = std::upper_bound(x_.begin(), x_.end(), x);
  const size_t i = static_cast<size_t>(std::max<std::ptrdiff_t>(1, it - x_.begin()));
  return std::min(i, x_.size() - 1) - 1;
}

double NaturalSpline::derivative(double x) const {
  if (x_.size() < 2) return 0.0;
  const size_t i = segment(std::clamp(x, x_.front(), x_.back()));
  const double h = x_[i + 1] - x_[i];
  const double xc = std::clamp(x, x_.front(), x_.back());
  const double A = (x_[i + 1] - xc) / h, B = (xc - x_[i]) / h;
  return (y_[i + 1] - y_[i]) / h - (3 * A * A - 1) / 6.0 * h * m_[i] + (3 * B * B - 1) / 6.0 * h * m_[i + 1];
}

double NaturalSpline::secondDerivative(double x) const {
  if (x_.size() < 2 || x <= x_.front() || x >= x_.back()) return 0.0;
  const size_t i = segment(x);
  const double h = x_[i + 1] - x_[i];
  const double A = (x_[i + 1] - x) / h, B = (x - x_[i]) / h;
  return A * m_[i] + B * m_[i + 1];
}

double NaturalSpline::operator()(double x) const {
  if (x_.empty()) return 0.0;
  if (x_.size() == 1) return y_[0];
  if (x < x_.front()) return y_.front() + (x - x_.front()) * derivative(x_.front());
  if (x > x_.back()) return y_.back() + (x - x_.back()) * derivative(x_.back());
  const size_t i = segment(x);
  const double h = x_[i + 1] - x_[i];
  const double A = (x_[i + 1] - x) / h, B = (x - x_[i]) / h;
  return A * y_[i] + B * y_[i + 1] + ((A * A * A - A) * m_[i] + (B * B * B - B) * m_[i + 1]) * h * h / 6.0;
}

PiecewiseLinearFit fitPiecewiseLinear(const BinnedSamples& data, double spacing, double penalty) {
  const size_t n = data.s.size();
  if (n == 0 || data.mean.size() != n || data.weight.size() != n) throw LanesError("regression: no data");
  double wsum = 0.0;
  for (double w : data.weight) wsum += w;
  if (!(wsum > 0)) throw LanesError("regression: zero weight");
  const double wnorm = n / wsum;
  const double x0 = data.s.front();
  // Prefix sums of w, w x, w y, w x^2, w x y, w y^2 (x relative to the first bin).
  std::vector<std::array<double, 6>> P(n + 1, {0, 0, 0, 0, 0, 0});
  for (size_t i = 0; i < n; ++i) {
    const double w = data.weight[i] * wnorm, x = data.s[i] - x0, y = data.mean[i];
    const std::array<double, 6> v{w, w * x, w * y, w * x * x, w * x * y, w * y * y};
    for (int k = 0; k < 6; ++k) P[i + 1][k] = P[i][k] + v[k];
  }
  // Line fit over bins [i, j): SSE and the line (a + b x).
  auto line = [&](size_t i, size_t j, double* a, double* b) {
    double S[6];
    for (int k = 0; k < 6; ++k) S[k] = P[j][k] - P[i][k];
    if (j <= i || S[0] <= 0) {
      *a = 0;
      *b = 0;
      return 0.0;
    }
    const double mx = S[1] / S[0], my = S[2] / S[0];
    const double sxx = S[3] - S[0] * mx * mx, sxy = S[4] - S[0] * mx * my, syy = S[5] - S[0] * my * my;
    *b = sxx > 1e-9 ? sxy / sxx : 0.0;
    *a = my - *b * mx;
    return std::max(0.0, syy - (*b) * sxy);
  };
  // Candidate breaks: the first bin of every `spacing` stretch, and the end.
  std::vector<size_t> cand{0};
  long last_k = 0;
  for (size_t i = 1; i < n; ++i) {
    const long k = static_cast<long>(std::floor((data.s[i] - x0) / spacing + 1e-9));
    if (k > last_k) {
      cand.push_back(i);
      last_k = k;
    }
  }
  cand.push_back(n);
  const size_t m = cand.size();
  std::vector<double> best(m, std::numeric_limits<double>::infinity());
  std::vector<size_t> from(m, 0);
  best[0] = 0.0;
  for (size_t j = 1; j < m; ++j) {
    for (size_t i = 0; i < j; ++i) {
      double a, b;
      const double c = best[i] + line(cand[i], cand[j], &a, &b) + penalty;
      if (c < best[j]) {
        best[j] = c;
        from[j] = i;
      }
    }
  }
  std::vector<size_t> chosen{m - 1};
  while (chosen.back() != 0) chosen.push_back(from[chosen.back()]);
  std::reverse(chosen.begin(), chosen.end());
  PiecewiseLinearFit fit;
  std::vector<double> init;
  for (size_t k = 0; k < chosen.size(); ++k) {
    const size_t c = cand[chosen[k]];
    const double x = c < n ? data.s[c] : data.s.back();
    if (!fit.knots.empty() && x <= fit.knots.back() + 1e-9) continue;
    fit.knots.push_back(x);
    // The DP's segment lines at this knot (averaged where two meet): prior for empty intervals.
    double v = 0.0;
    int cnt = 0;
    for (int side = 0; side < 2; ++side) {
      const size_t seg = side == 0 ? k : k + 1;  // segment ending / starting here
      if (seg == 0 || seg >= chosen.size()) continue;
      double a, b;
      line(cand[chosen[seg - 1]], cand[chosen[seg]], &a, &b);
      v += a + b * (x - x0);
      ++cnt;
    }
    init.push_back(cnt ? v / cnt : data.mean[std::min(c, n - 1)]);
  }
  const size_t K = fit.knots.size();
  if (K == 1) {
    fit.values = {P[n][2] / P[n][0]};
    fit.sse = std::max(0.0, P[n][5] - P[n][0] * fit.values[0] * fit.values[0]);
    return fit;
  }
  // Continuous piecewise-linear least squares with hat functions at the knots, a small ridge
  // towards the DP's lines keeps knots between empty bins determined.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(K, K);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(K);
  for (size_t i = 0; i < n; ++i) {
    const double w = data.weight[i] * wnorm, x = data.s[i];
    size_t k = std::upper_bound(fit.knots.begin(), fit.knots.end(), x) - fit.knots.begin();
    k = std::clamp<size_t>(k, 1, K - 1) - 1;
    const double t = std::clamp((x - fit.knots[k]) / (fit.knots[k + 1] - fit.knots[k]), 0.0, 1.0);
    const double b0 = 1 - t, b1 = t;
    A(k, k) += w * b0 * b0;
    A(k, k + 1) += w * b0 * b1;
    A(k + 1, k) += w * b0 * b1;
    A(k + 1, k + 1) += w * b1 * b1;
    r(k) += w * b0 * data.mean[i];
    r(k + 1) += w * b1 * data.mean[i];
  }
  for (size_t k = 0; k < K; ++k) {
    A(k, k) += 1e-4;
    r(k) += 1e-4 * init[k];
  }
  const Eigen::VectorXd c = A.ldlt().solve(r);
  fit.values.assign(c.data(), c.data() + K);
  double sse = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double x = data.s[i];
    size_t k = std::upper_bound(fit.knots.begin(), fit.knots.end(), x) - fit.knots.begin();
    k = std::clamp<size_t>(k, 1, K - 1) - 1;
    const double t = std::clamp((x - fit.knots[k]) / (fit.knots[k + 1] - fit.knots[k]), 0.0, 1.0);
    const double e = data.mean[i] - ((1 - t) * fit.values[k] + t * fit.values[k + 1]);
    sse += data.weight[i] * wnorm * e * e;
  }
  fit.sse = sse;
  return fit;
}

double PiecewiseLinearFit::operator()(double s) const {
  if (knots.empty()) return 0.0;
  if (knots.size() == 1) return values[0];
  size_t k = std::upper_bound(knots.begin(), knots.end(), s) - knots.begin();
  k = std::clamp<size_t>(k, 1, knots.size() - 1) - 1;
  const double t = (s - knots[k]) / (knots[k + 1] - knots[k]);  // linear beyond the ends
  return (1 - t) * values[k] + t * values[k + 1];
}

CentreLine::CentreLine(const PiecewiseLinearFit& fit, double s_begin, double s_end, double knot_spacing)
    : fit_(fit), s0_(s_begin), s1_(s_end) {
  // The spline goes through the piecewise-linear function sampled at its breaks and every
  // knot_spacing between them: it rounds the corners and cannot overshoot between far breaks.
  std::vector<double> x, y;
  for (size_t k = 0; k < fit.knots.size(); ++k) {
    x.push_back(fit.knots[k]);
    if (k + 1 == fit.knots.size()) break;
    const double len = fit.knots[k + 1] - fit.knots[k];
    const int n = static_cast<int>(std::floor(len / knot_spacing));
    for (int i = 1; i < n; ++i) x.push_back(fit.knots[k] + len * i / n);
  }
  for (double s : x) y.push_back(fit(s));
  spline_ = NaturalSpline(x, y);
}

}  // namespace lanemap::lanes
