// The car's own path through an intersection (see driven_passage.h).
#include "core/intersections/driven_passage.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lanemap::intersections {

namespace {

using Eigen::Vector2d;

// The foot of p on the path's segments from segment `first` on: segment index, its parameter and
// the distance.
struct Foot {
  size_t seg = 0;
  double t = 0.0, distance = std::numeric_limits<double>::infinity();
  Vector2d point = Vector2d::Zero();
};
Foot nearestFoot(const std::vector<Vector2d>& path, const Vector2d& p, size_t first) {
  Foot best;
  for (size_t i = first; i + 1 < path.size(); ++i) {
    const Vector2d ab = path[i + 1] - path[i];
    const double l2 = ab.squaredNorm();
    const double t = l2 > 1e-18 ? std::clamp((p - path[i]).dot(ab) / l2, 0.0, 1.0) : 0.0;
    const Vector2d q = path[i] + t * ab;
    const double d = (p - q).norm();
    if (d < best.distance) best = Foot{i, t, d, q};
  }
  return best;
}

std::vector<double> arcLengths(const std::vector<Vector2d>& line) {
  std::vector<double> s(line.size(), 0.0);
  for (size_t k = 1; k < line.size(); ++k) s[k] = s[k - 1] + (line[k] - line[k - 1]).norm();
  return s;
}

}  // namespace

Vector2d Displacement::operator()(double u) const {
  if (at.empty()) return Vector2d::Zero();
  if (at.size() == 1) return at[0];
  const double x = std::clamp(u, 0.0, 1.0) * static_cast<double>(at.size() - 1);
  const size_t k = std::min(at.size() - 2, static_cast<size_t>(x));
  const double f = x - static_cast<double>(k);
  return (1.0 - f) * at[k] + f * at[k + 1];
}

std::vector<Vector2d> Displacement::apply(const std::vector<Vector2d>& in, double step_m) const {
  if (in.size() < 2 || at.empty()) return in;
  std::vector<Vector2d> line{in.front()};
  for (size_t k = 1; k < in.size(); ++k) {
    const double len = (in[k] - in[k - 1]).norm();
    const int n = step_m > 0 ? static_cast<int>(std::ceil(len / step_m)) : 1;
    for (int i = 1; i < n; ++i) line.push_back(in[k - 1] + (in[k] - in[k - 1]) * (static_cast<double>(i) / n));
    line.push_back(in[k]);
  }
  const std::vector<double> s = arcLengths(line);
  const double total = s.back();
  std::vector<Vector2d> out = line;
  if (!(total > 1e-9)) return out;
  for (size_t k = 1; k + 1 < line.size(); ++k) out[k] += (*this)(s[k] / total);
  return out;
}

Displacement Displacement::smoothed(int passes) const {
  Displacement d = *this;
  std::vector<Vector2d> next = d.at;
  for (int pass = 0; pass < passes; ++pass) {
    for (size_t k = 1; k + 1 < d.at.size(); ++k) next[k] = 0.25 * (d.at[k - 1] + 2.0 * d.at[k] + d.at[k + 1]);
    d.at.swap(next);
  }
  return d;
}

std::vector<Vector2d> resampleEvenly(const std::vector<Vector2d>& line, int n) {
  if (line.empty() || n < 2) return line;
  const std::vector<double> s = arcLengths(line);
  std::vector<Vector2d> out;
  out.reserve(static_cast<size_t>(n));
  size_t seg = 0;
  for (int i = 0; i < n; ++i) {
    const double want = s.back() * i / (n - 1);
    while (seg + 2 < line.size() && s[seg + 1] < want) ++seg;
    if (line.size() == 1) {
      out.push_back(line[0]);
      continue;
    }
    const double len = s[seg + 1] - s[seg];
    const double f = len > 1e-12 ? std::clamp((want - s[seg]) / len, 0.0, 1.0) : 0.0;
    out.push_back(line[seg] + f * (line[seg + 1] - line[seg]));
  }
  out.front() = line.front();
  out.back() = line.back();
  return out;
}

std::optional<std::vector<Vector2d>> drivenCentre(const std::vector<Vector2d>& path, const Vector2d& p0, const Vector2d& p2,
                                                  const PassageOptions& o) {
  if (path.size() < 2 || !(o.max_offset_m > 0)) return std::nullopt;
  const Foot a = nearestFoot(path, p0, 0);
  if (!(a.distance <= o.max_offset_m)) return std::nullopt;
  const Foot b = nearestFoot(path, p2, a.seg);
  if (!(b.distance <= o.max_offset_m)) return std::nullopt;
  if (b.seg == a.seg && b.t <= a.t) return std::nullopt;  // p2 passed before p0
  std::vector<Vector2d> q{a.point};
  for (size_t i = a.seg + 1; i <= b.seg; ++i) q.push_back(path[i]);
  q.push_back(b.point);
  // Points closer than a centimetre to the one before say nothing and make zero-length segments.
  std::vector<Vector2d> clean{q.front()};
  for (size_t k = 1; k < q.size(); ++k) {
    if ((q[k] - clean.back()).norm() >= 0.01 || k + 1 == q.size()) clean.push_back(q[k]);
  }
  if (clean.size() < 2) return std::nullopt;
  const std::vector<double> s = arcLengths(clean);
  if (!(s.back() > 0.5 * (p2 - p0).norm())) return std::nullopt;  // a path shorter than the gap: not this one
  const Vector2d e0 = clean.front() - p0, e2 = clean.back() - p2;
  for (size_t k = 0; k < clean.size(); ++k) {
    const double u = s[k] / s.back();
    clean[k] -= (1.0 - u) * e0 + u * e2;
  }
  clean.front() = p0;
  clean.back() = p2;
  return clean;
}

Displacement displacementBetween(const std::vector<Vector2d>& driven, const std::vector<Vector2d>& bezier, const PassageOptions& o) {
  const int n = std::max(2, o.samples);
  const auto a = resampleEvenly(driven, n), b = resampleEvenly(bezier, n);
  Displacement d;
  d.passages = 1;
  d.at.resize(static_cast<size_t>(n), Vector2d::Zero());
  if (static_cast<int>(a.size()) != n || static_cast<int>(b.size()) != n) return d;
  for (int k = 1; k + 1 < n; ++k) d.at[static_cast<size_t>(k)] = a[static_cast<size_t>(k)] - b[static_cast<size_t>(k)];
  return d;
}

std::optional<Displacement> meanDisplacement(const std::vector<Displacement>& ds) {
  if (ds.empty()) return std::nullopt;
  Displacement m;
  m.at.assign(ds.front().at.size(), Vector2d::Zero());
  int used = 0;
  for (const auto& d : ds) {
    if (d.at.size() != m.at.size()) continue;
    for (size_t k = 0; k < m.at.size(); ++k) m.at[k] += d.at[k];
    ++used;
    m.passages += d.passages;
  }
  if (used == 0) return std::nullopt;
  for (auto& v : m.at) v /= static_cast<double>(used);
  return m;
}

}  // namespace lanemap::intersections
