#include "core/bev/projector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

namespace lanemap::bev {

uint8_t layerBits(uint8_t c) {
  uint8_t b = bit(Layer::kObserved);
  if (isLaneClass(c)) return b | bit(Layer::kDrivable);
  switch (c) {
    case 6: return b | bit(Layer::kDashedLine);
    case 7: return b | bit(Layer::kSolidLine);
    case 8: return b | bit(Layer::kCrosswalk);
    case 9: return b | bit(Layer::kCurb);
    case 10: return b | bit(Layer::kStopLine);
    default: return b;
  }
}

void addSplat(const FrameSplat& splat, BevGrid& grid) {
  for (const auto& c : splat.cells) {
    for (int l = 0; l < kNumLayers; ++l) {
      if (c.layers & (1u << l)) grid.add(BevGrid::Cell(c.x, c.y), static_cast<Layer>(l));
    }
  }
  grid.addFrame();
}

const char* toString(LabelCheck c) {
  switch (c) {
    case LabelCheck::kOk: return "ok";
    case LabelCheck::kWrongSize: return "wrong_size";
    case LabelCheck::kWrongType: return "wrong_type";
    case LabelCheck::kUnknownClass: return "unknown_class";
  }
  return "?";
}

Projector::Projector(const camera::CameraModel& camera, const ProjectorOptions& options)
    : camera_(camera), options_(options) {
  if (!(options_.resolution_m > 0.0) || !(options_.max_range_m > 0.0) || options_.sample_spacing_m < 0.0) {
    throw BevError("Projector: resolution_m and max_range_m must be > 0, sample_spacing_m >= 0");
  }
  centre_ = camera_.opticalCentreVehicle().cast<float>();
  buildRays();
  buildLattice();
  buildRaster();
}

void Projector::buildRays() {
  const int w = camera_.width(), h = camera_.height();
  rays_.resize(static_cast<size_t>(w) * h);
  candidate_.assign(rays_.size(), 0);
  const Eigen::Vector3d c = camera_.opticalCentreVehicle();
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      const Eigen::Vector3d d = camera_.rayVehicle(Eigen::Vector2d(u, v));
      rays_[i].dir = d.cast<float>();
      rays_[i].flat_hit.setZero();
      if (d.z() >= -1e-9) continue;  // at or above the horizon
      const Eigen::Vector3d hit = c + (-c.z() / d.z()) * d;
      rays_[i].flat_hit = hit.cast<float>();
      if ((hit - c).head<2>().norm() <= options_.max_range_m) {
        candidate_[i] = 1;
        ++candidates_;
      }
    }
  }
}

void Projector::buildLattice() {
  const int w = camera_.width(), h = camera_.height();
  const double spacing = options_.sample_spacing_m;
  const int uc = std::clamp(static_cast<int>(std::lround(camera_.intrinsics().cx)), 0, w - 2);
  bool have_last = false;
  Eigen::Vector3f last_hit = Eigen::Vector3f::Zero();
  for (int v = h - 1; v >= 0; --v) {  // from the car outwards
    Row r;
    r.v = v;
    for (int u = 0; u < w; ++u) {
      if (!candidate_[static_cast<size_t>(v) * w + u]) continue;
      if (r.u1 < 0) r.u0 = u;
      r.u1 = u;
    }
    if (r.u1 < 0) continue;
    const size_t ic = static_cast<size_t>(v) * w + uc;
    const Eigen::Vector3f hit = rays_[ic].flat_hit;
    if (spacing > 0.0 && have_last && (hit - last_hit).norm() < spacing) continue;
    have_last = true;
    last_hit = hit;
    int step = 1;
    if (spacing > 0.0) {
      const double across = (rays_[ic + 1].flat_hit - hit).norm();
      step = std::max(1, static_cast<int>(std::floor(spacing / std::max(across, 1e-6))));
    }
    r.step = step;
    rows_.push_back(r);
    for (int u = r.u0; u <= r.u1; u += step) {
      const int i = v * w + u;
      if (candidate_[i]) lattice_.push_back(i);
    }
  }
}

void Projector::buildRaster() {
  const int w = camera_.width();
  const Eigen::Matrix3f r_cv = camera_.vehicleToCamera().linear().cast<float>();
  compact_.assign(rays_.size(), -1);
  raster_row_of_v_.assign(camera_.height(), -1);
  std::vector<Row> rows(rows_.rbegin(), rows_.rend());  // v ascending
  qx_min_ = qy_min_ = std::numeric_limits<float>::infinity();
  qx_max_ = qy_max_ = -qx_min_;
  raster_ok_ = true;
  for (const Row& r : rows) {
    RasterRow rr;
    rr.v = r.v;
    rr.u0 = r.u0;
    rr.u1 = r.u1;
    rr.step = r.step;
    rr.offset = static_cast<int>(rqx_.size());
    rr.qy_lo = std::numeric_limits<float>::infinity();
    rr.qy_hi = -rr.qy_lo;
    for (int u = r.u0; u <= r.u1; u += r.step) {  // the lattice pixels of the row
      const size_t i = static_cast<size_t>(r.v) * w + u;
      if (!candidate_[i]) continue;
      const Eigen::Vector3f dc = r_cv * rays_[i].dir;
      // The raster needs rays in front of the camera and x increasing along the row.
      if (!(dc.z() > 1e-6f)) raster_ok_ = false;
      const float qx = dc.x() / dc.z(), qy = dc.y() / dc.z();
      if (static_cast<int>(rqx_.size()) > rr.offset && !(qx > rqx_.back())) raster_ok_ = false;
      compact_[i] = static_cast<int32_t>(rqx_.size());
      rqx_.push_back(qx);
      rqy_.push_back(qy);
      rr.qy_lo = std::min(rr.qy_lo, qy);
      rr.qy_hi = std::max(rr.qy_hi, qy);
    }
    if (!raster_ok_) break;
    const int n = static_cast<int>(rqx_.size()) - rr.offset;
    if (n == 0) continue;
    rr.n = n;
    rr.qx_lo = rqx_[rr.offset];
    const float qx_hi = rqx_.back();
    rr.lut_n = n;
    rr.lut_step = n > 1 ? (qx_hi - rr.qx_lo) / static_cast<float>(n - 1) : 1.0f;
    if (!(rr.lut_step > 0.0f)) rr.lut_step = 1.0f;
    rr.lut_inv_step = 1.0f / rr.lut_step;
    rr.lut_begin = static_cast<int>(lut_.size());
    int j = 0;
    for (int k = 0; k < rr.lut_n; ++k) {
      const float start = rr.qx_lo + static_cast<float>(k) * rr.lut_step;
      while (j < n && rqx_[rr.offset + j] < start) ++j;
      // Float rounding of `start` may put it a hair past a pixel: step back to stay conservative.
      lut_.push_back(std::max(0, j - 1));
    }
    qx_min_ = std::min(qx_min_, rr.qx_lo);
    qx_max_ = std::max(qx_max_, qx_hi);
    qy_min_ = std::min(qy_min_, rr.qy_lo);
    qy_max_ = std::max(qy_max_, rr.qy_hi);
    raster_row_of_v_[rr.v] = static_cast<int32_t>(raster_rows_.size());
    raster_rows_.push_back(rr);
  }
  if (!raster_ok_ || raster_rows_.empty()) {
    raster_ok_ = false;
    raster_rows_.clear();
    rqx_.clear();
    rqy_.clear();
    lut_.clear();
    compact_.assign(rays_.size(), -1);
    raster_row_of_v_.assign(camera_.height(), -1);
    return;
  }
  const size_t nr = raster_rows_.size();
  row_qy_hi_max_.resize(nr);
  row_qy_lo_min_.resize(nr);
  for (size_t k = 0; k < nr; ++k) {
    row_qy_hi_max_[k] = std::max(raster_rows_[k].qy_hi, k ? row_qy_hi_max_[k - 1] : -std::numeric_limits<float>::infinity());
  }
  for (size_t k = nr; k-- > 0;) {
    row_qy_lo_min_[k] = std::min(raster_rows_[k].qy_lo, k + 1 < nr ? row_qy_lo_min_[k + 1] : std::numeric_limits<float>::infinity());
  }
}

namespace {

constexpr float kEdge = 1e-6f;  // barycentric tolerance at triangle edges (relative)

// The z-buffer pass of one triangle over compact pixels [first, last) of a row: each pixel the
// triangle covers (barycentric weights a, b, g >= -kEdge (a + b + g)) and that it is nearer at than
// the nearest so far (inverse depth a + b + g above z) takes it. Branch-free, so it vectorises.
void rasterSpan(const std::array<Eigen::Vector3f, 3>& l, int32_t vi, const float* __restrict qxs,
                const float* __restrict qys, int first, int last, float* __restrict z, int32_t* __restrict owner) {
  const float l0x = l[0].x(), l0y = l[0].y(), l0z = l[0].z();
  const float l1x = l[1].x(), l1y = l[1].y(), l1z = l[1].z();
  const float l2x = l[2].x(), l2y = l[2].y(), l2z = l[2].z();
  for (int ci = first; ci < last; ++ci) {
    const float qx = qxs[ci], qy = qys[ci];
    const float a = l0x * qx + l0y * qy + l0z;
    const float b = l1x * qx + l1y * qy + l1z;
    const float g = l2x * qx + l2y * qy + l2z;
    const float s = a + b + g;
    const float tol = -kEdge * s;
    const bool take = (s > z[ci]) & !(a < tol) & !(b < tol) & !(g < tol);
    z[ci] = take ? s : z[ci];
    owner[ci] = take ? vi : owner[ci];
  }
}

// 1 / camera depth of the hit of ray (qx, qy, 1) on a triangle (ViewTriangle::l), 0 when it misses.
inline float rayWeight(const std::array<Eigen::Vector3f, 3>& l, float qx, float qy) {
  const float a = l[0].x() * qx + l[0].y() * qy + l[0].z();
  const float b = l[1].x() * qx + l[1].y() * qy + l[1].z();
  const float g = l[2].x() * qx + l[2].y() * qy + l[2].z();
  const float s = a + b + g, tol = -kEdge * s;
  return s > 0.0f && a >= tol && b >= tol && g >= tol ? s : 0.0f;
}

// Bounding box in undistorted normalised coordinates of {q : l_k . (q, 1) >= 0, k = 0..2} inside the
// box [x0, x1] x [y0, y1] (Sutherland-Hodgman on the box). False when empty.
bool clippedBox(const std::array<Eigen::Vector3f, 3>& l, float& x0, float& y0, float& x1, float& y1) {
  std::array<Eigen::Vector2f, 8> a, b;
  a[0] = {x0, y0};
  a[1] = {x1, y0};
  a[2] = {x1, y1};
  a[3] = {x0, y1};
  int n = 4;
  for (const auto& e : l) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2f& p = a[i];
      const Eigen::Vector2f& q = a[(i + 1) % n];
      const float fp = e.x() * p.x() + e.y() * p.y() + e.z(), fq = e.x() * q.x() + e.y() * q.y() + e.z();
      if (fp >= 0 && m < 8) b[m++] = p;
      if ((fp >= 0) != (fq >= 0) && m < 8) b[m++] = p + (fp / (fp - fq)) * (q - p);
    }
    n = m;
    if (n == 0) return false;
    a = b;
  }
  x0 = y0 = std::numeric_limits<float>::infinity();
  x1 = y1 = -x0;
  for (int i = 0; i < n; ++i) {
    x0 = std::min(x0, a[i].x());
    x1 = std::max(x1, a[i].x());
    y0 = std::min(y0, a[i].y());
    y1 = std::max(y1, a[i].y());
  }
  return true;
}

}  // namespace

void Projector::rasterise(const ground::MeshGround& mesh, const Eigen::Isometry3d& vehicle_to_enu,
                          MeshRaster& out) const {
  const auto& m = mesh.mesh();
  out.tri.assign(rqx_.size(), -1);
  out.view.clear();
  std::vector<float> zw(rqx_.size(), 0.0f);  // inverse depth of the nearest triangle so far
  const Eigen::Vector3d c = vehicle_to_enu * centre_.cast<double>();
  const Eigen::Matrix3d r_ce = camera_.vehicleToCamera().linear() * vehicle_to_enu.linear().transpose();
  // Range cull: a triangle whose (x, y) box is farther than max_range_m from the camera cannot be
  // hit within range (the ray cast stops there).
  const double range = options_.max_range_m + 1e-3, range2 = range * range;
  // Per vertex: camera frame, image (x, y) when well in front, and flags whose AND over a triangle
  // culls it: all behind the camera, all on the outer side of one edge of the image's box, all
  // beyond range (then the triangle's box decides).
  enum : uint8_t { kBehind = 1, kNotFront = 2, kFar = 4, kLeft = 8, kRight = 16, kAbove = 32, kBelow = 64 };
  struct Vert {
    Eigen::Vector3f p;
    Eigen::Vector2f q;
    uint8_t flags;
  };
  std::vector<Vert> vs(m.vertices.size());
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const Eigen::Vector3d e = m.vertices[i] - c;
    Vert& v = vs[i];
    v.p = (r_ce * e).cast<float>();
    v.flags = e.head<2>().squaredNorm() > range2 ? kFar : 0;
    if (v.p.z() <= 0.0f) v.flags |= kBehind;
    if (v.p.z() > 1e-3f) {
      v.q = v.p.head<2>() * (1.0f / v.p.z());
      v.flags |= (v.q.x() < qx_min_ ? kLeft : 0) | (v.q.x() > qx_max_ ? kRight : 0) | (v.q.y() < qy_min_ ? kAbove : 0) |
                 (v.q.y() > qy_max_ ? kBelow : 0);
    } else {
      v.flags |= kNotFront;
    }
  }
  const int nr = static_cast<int>(raster_rows_.size());
  // The first lattice row whose y range reaches up to y or beyond (nr: none).
  const auto firstRowReaching = [&](float y) {
    return static_cast<int>(std::lower_bound(row_qy_hi_max_.begin(), row_qy_hi_max_.end(), y) - row_qy_hi_max_.begin());
  };
  for (int32_t ti = 0; ti < static_cast<int32_t>(m.triangles.size()); ++ti) {
    const auto& t = m.triangles[ti];
    const Vert& va = vs[t[0]];
    const Vert& vb = vs[t[1]];
    const Vert& vc = vs[t[2]];
    const uint8_t all = va.flags & vb.flags & vc.flags;
    if (all & (kBehind | kLeft | kRight | kAbove | kBelow)) continue;
    if (all & kFar) {
      const auto& pa = m.vertices[t[0]];
      const auto& pb = m.vertices[t[1]];
      const auto& pc = m.vertices[t[2]];
      const double dx = std::max({0.0, std::min({pa.x(), pb.x(), pc.x()}) - c.x(), c.x() - std::max({pa.x(), pb.x(), pc.x()})});
      const double dy = std::max({0.0, std::min({pa.y(), pb.y(), pc.y()}) - c.y(), c.y() - std::max({pa.y(), pb.y(), pc.y()})});
      if (dx * dx + dy * dy > range2) continue;
    }
    const Eigen::Vector3f& A = va.p;
    const Eigen::Vector3f& B = vb.p;
    const Eigen::Vector3f& C = vc.p;
    // In front of the camera: the triangle's image, for exact spans per row; else its clipped box.
    const bool front = !((va.flags | vb.flags | vc.flags) & kNotFront);
    float x0 = qx_min_, y0 = qy_min_, x1 = qx_max_, y1 = qy_max_;
    if (front) {
      x0 = std::max(x0, std::min({va.q.x(), vb.q.x(), vc.q.x()}));
      x1 = std::min(x1, std::max({va.q.x(), vb.q.x(), vc.q.x()}));
      y0 = std::max(y0, std::min({va.q.y(), vb.q.y(), vc.q.y()}));
      y1 = std::min(y1, std::max({va.q.y(), vb.q.y(), vc.q.y()}));
      if (x0 > x1 || y0 > y1) continue;
    }
    // No lattice row in the triangle's y range (most far triangles fall between rows): nothing to do.
    const int r_first = firstRowReaching(y0);
    if (r_first >= nr || row_qy_lo_min_[r_first] > y1) continue;
    std::array<Eigen::Vector3f, 3> l{B.cross(C), C.cross(A), A.cross(B)};
    const float det = A.dot(l[0]);
    // A plane through the optical centre: rays meet it edge-on or not at all.
    if (!(det * det > 1e-14f * A.squaredNorm() * B.squaredNorm() * C.squaredNorm())) continue;
    for (auto& e : l) e /= det;
    if (!front && !clippedBox(l, x0, y0, x1, y1)) continue;
    const int32_t vi = static_cast<int32_t>(out.view.size());
    {
      ViewTriangle vt;
      vt.l = l;
      const Eigen::Vector3d& pa = m.vertices[t[0]];
      vt.n = (m.vertices[t[1]] - pa).cross(m.vertices[t[2]] - pa);
      vt.nd = vt.n.dot(pa - c);
      vt.index = ti;
      out.view.push_back(vt);
    }
    // Edges for the row spans: a point, the y range and dx/dy.
    struct Edge {
      float x, y, y_lo, y_hi, slope;
    };
    std::array<Edge, 3> edges{};
    if (front) {
      const std::array<const Eigen::Vector2f*, 3> q{&va.q, &vb.q, &vc.q};
      for (int e = 0; e < 3; ++e) {
        const Eigen::Vector2f& p = *q[e];
        const Eigen::Vector2f& o = *q[(e + 1) % 3];
        edges[e] = Edge{p.x(), p.y(), std::min(p.y(), o.y()), std::max(p.y(), o.y()),
                        o.y() != p.y() ? (o.x() - p.x()) / (o.y() - p.y()) : 0.0f};
      }
    }
    // Rows whose y range meets [y0, y1] (r_first unless clippedBox raised y0).
    int r = front ? r_first : firstRowReaching(y0);
    for (; r < nr && row_qy_lo_min_[r] <= y1; ++r) {
      const RasterRow& row = raster_rows_[r];
      if (row.qy_hi < y0 || row.qy_lo > y1) continue;
      float xa = x0, xb = x1;
      if (front) {
        // x extent of the triangle's image within the row's band of y (vertices inside the band,
        // edges crossing its two lines), a hair wider so rounding never loses a pixel.
        const float ya = std::max(row.qy_lo, y0), yb = std::min(row.qy_hi, y1);
        xa = std::numeric_limits<float>::infinity();
        xb = -xa;
        // Each edge's part inside the band: its x at both ends (a horizontal edge's far end is
        // the next edge's start). Branch-free: a miss contributes +-infinity.
        for (const Edge& e : edges) {
          const float lo = std::max(ya, e.y_lo), hi = std::min(yb, e.y_hi);
          const float x_lo = e.x + (lo - e.y) * e.slope, x_hi = e.x + (hi - e.y) * e.slope;
          const bool in = lo <= hi;
          xa = std::min(xa, in ? std::min(x_lo, x_hi) : std::numeric_limits<float>::infinity());
          xb = std::max(xb, in ? std::max(x_lo, x_hi) : -std::numeric_limits<float>::infinity());
        }
        if (xa > xb) continue;
        xa = std::max(x0, xa - 1e-5f);
        xb = std::min(x1, xb + 1e-5f);
      }
      // The row's pixels [first, last): from xa's lookup-table bin (truncation is floor here: negative
      // values clamp to bin 0) up to the last with qx <= xb, found from xb's bin on.
      const auto bin = [&](float x) {
        const float kf = (x - row.qx_lo) * row.lut_inv_step;
        return kf <= 0.0f ? 0 : static_cast<int>(std::min(kf, static_cast<float>(row.lut_n - 1)));
      };
      const int end = row.offset + row.n;
      const float* __restrict qxs = rqx_.data();
      const float* __restrict qys = rqy_.data();
      const int first = row.offset + lut_[row.lut_begin + bin(xa)];
      int last = std::max(first, row.offset + lut_[row.lut_begin + bin(xb)]);
      while (last < end && qxs[last] <= xb) ++last;
      rasterSpan(l, vi, qxs, qys, first, last, zw.data(), out.tri.data());
    }
  }
}

LabelCheck Projector::check(const cv::Mat& labels) const {
  if (labels.type() != CV_8UC1) return LabelCheck::kWrongType;
  if (labels.cols != camera_.width() || labels.rows != camera_.height()) return LabelCheck::kWrongSize;
  double lo = 0.0, hi = 0.0;
  cv::minMaxLoc(labels, &lo, &hi);
  return hi >= kNumClasses ? LabelCheck::kUnknownClass : LabelCheck::kOk;
}

void Projector::separationPixels(const cv::Mat& labels, const Row& r, std::vector<std::pair<int, uint8_t>>& out) const {
  const int w = camera_.width();
  const uint8_t* row = labels.ptr<uint8_t>(r.v);
  const uint8_t sep = bit(Layer::kLaneSeparation);
  const float max_gap = static_cast<float>(options_.max_separation_gap_m);
  int last_u = -1;
  uint8_t last_c = 0;
  bool paint_only = true;
  for (int u = r.u0; u <= r.u1; ++u) {
    const uint8_t c = row[u];
    if (!isLaneClass(c)) {
      if (c != kClassDashed && c != kClassSolid) paint_only = false;
      continue;
    }
    if (last_u >= 0 && c != last_c && paint_only) {
      const int base = r.v * w;
      const float gap = (rays_[base + u].flat_hit - rays_[base + last_u].flat_hit).norm();
      if (gap <= max_gap) {
        const int a = u == last_u + 1 ? last_u : last_u + 1;
        const int b = u == last_u + 1 ? u : u - 1;
        for (int k = a; k <= b; ++k) out.emplace_back(base + k, layerBits(row[k]) | sep);
      }
    }
    last_u = u;
    last_c = c;
    paint_only = true;
  }
}

FrameSplat Projector::project(const cv::Mat& labels, const Eigen::Isometry3d& vehicle_to_enu,
                              const ground::MeshGround* mesh, const RoadCrown* crown) const {
  FrameSplat splat;
  splat.resolution = options_.resolution_m;
  const cv::Mat lab = labels.isContinuous() ? labels : labels.clone();
  const uint8_t* L = lab.ptr<uint8_t>(0);
  std::vector<std::pair<int, uint8_t>> px;
  px.reserve(lattice_.size() + 4096);
  for (int i : lattice_) px.emplace_back(i, layerBits(L[i]));
  if (options_.lane_separation) {
    for (const Row& r : rows_) separationPixels(lab, r, px);
  }
  // A local raster of layer bits around the camera deduplicates the cells (at most once per frame).
  const double res = options_.resolution_m;
  const Eigen::Vector3d c = vehicle_to_enu * centre_.cast<double>();
  const int R = static_cast<int>(std::ceil(options_.max_range_m / res)) + 2, n = 2 * R + 1;
  const int x0 = static_cast<int>(std::floor(c.x() / res)) - R, y0 = static_cast<int>(std::floor(c.y() / res)) - R;
  std::vector<uint8_t> raster(static_cast<size_t>(n) * n, 0);
  int bx0 = n, bx1 = -1, by0 = n, by1 = -1;  // the box of the raster cells set
  const Eigen::Matrix3d rot = vehicle_to_enu.linear();
  const int w = camera_.width();
  const bool use_raster = mesh && rasterises();
  const double range2 = options_.max_range_m * options_.max_range_m;
  MeshRaster mr;
  if (use_raster) rasterise(*mesh, vehicle_to_enu, mr);
  const Eigen::Matrix3f r_cv = camera_.vehicleToCamera().linear().cast<float>();
  // A pixel's point on the flat ground plane (ENU x, y).
  const auto flatPoint = [&](const Ray& ray) -> Eigen::Vector2d {
    return (vehicle_to_enu * ray.flat_hit.cast<double>()).head<2>();
  };
  size_t crown_hint = 0;  // RoadCrown::hit's segment, carried from pixel to pixel
  for (const auto& [i, bits] : px) {
    const Ray& ray = rays_[i];
    Eigen::Vector2d p;  // the pixel's ground point (ENU x, y)
    if (mesh) {
      const Eigen::Vector3d d = rot * ray.dir.cast<double>();
      // Range limit on t: horizontal distance t |d_xy| <= max_range_m (squared here; the ray cast
      // below takes it as max_t).
      const double dxy2 = d.x() * d.x() + d.y() * d.y();
      std::optional<double> t;
      bool settled = false;
      if (use_raster) {
        int32_t k = -1;
        if (compact_[i] >= 0) {  // a lattice pixel: its z-buffer triangle
          k = mr.tri[compact_[i]];
          settled = k < 0;  // no triangle in front of the camera on this ray within range
        } else if (const int32_t r = raster_row_of_v_[i / w]; r >= 0) {
          // A separation pixel between two lattice pixels: the nearer of their triangles that
          // this pixel's ray meets (none: ray-cast).
          const Eigen::Vector3f dc = r_cv * ray.dir;
          if (dc.z() > 1e-6f) {
            const float qx = dc.x() / dc.z(), qy = dc.y() / dc.z();
            const RasterRow& row = raster_rows_[r];
            const int u = i % w, ul = row.u0 + (u - row.u0) / row.step * row.step;
            float best = 0.0f;
            for (const int uu : {ul, ul + row.step}) {
              if (uu > row.u1 || compact_[static_cast<size_t>(i - u + uu)] < 0) continue;
              const int32_t kk = mr.tri[compact_[static_cast<size_t>(i - u + uu)]];
              if (kk < 0) continue;
              const float s = rayWeight(mr.view[kk].l, qx, qy);
              if (s > best) {
                best = s;
                k = kk;
              }
            }
          }
        }
        if (k >= 0) {
          // The hit on the triangle's plane, in double (the ray cast's t up to rounding).
          const ViewTriangle& vt = mr.view[k];
          const double h = vt.nd / vt.n.dot(d);
          if (h > 0.0 && std::isfinite(h)) {
            settled = true;
            if (h * h * dxy2 <= range2) t = h;  // the nearest hit; beyond range every hit is
          }
        }
      }
      if (!settled) {
        t = mesh->intersect(c, d, options_.max_range_m / std::max(std::sqrt(dxy2), 1e-9));
        ++splat.raycast;
      }
      if (t) {
        p = c.head<2>() + *t * d.head<2>();
        ++splat.mesh_hits;
      } else {
        p = flatPoint(ray);
        if (mesh->covers(p.x(), p.y())) {
          ++splat.dropped;
          continue;
        }
        ++splat.flat;
      }
    } else if (crown) {
      const Eigen::Vector3d d = rot * ray.dir.cast<double>();
      const double dxy = std::max(std::hypot(d.x(), d.y()), 1e-9);
      const double t_flat = (ray.flat_hit - centre_).norm();
      // The crowned ground lies below the plane beyond the crown: its hit may be a little farther
      // than the flat one (the raster below drops what leaves it).
      if (const auto h = crown->hit(c, d, t_flat, 1.5 * options_.max_range_m / dxy, crown_hint)) {
        p = *h;
        ++splat.crowned;
      } else {
        p = flatPoint(ray);
        ++splat.flat;
      }
    } else {
      p = flatPoint(ray);
      ++splat.flat;
    }
    const int cx = static_cast<int>(std::floor(p.x() / res)) - x0, cy = static_cast<int>(std::floor(p.y() / res)) - y0;
    if (cx < 0 || cy < 0 || cx >= n || cy >= n) {
      ++splat.dropped;
      continue;
    }
    raster[static_cast<size_t>(cy) * n + cx] |= bits;
    bx0 = std::min(bx0, cx), bx1 = std::max(bx1, cx), by0 = std::min(by0, cy), by1 = std::max(by1, cy);
  }
  splat.pixels = px.size();
  // The cells in (y, x) order, from the box the pixels touched (the camera sees a part of the raster).
  splat.cells.reserve(px.size());
  for (int y = by0; y <= by1; ++y) {
    const uint8_t* row = &raster[static_cast<size_t>(y) * n];
    for (int x = bx0; x <= bx1; ++x) {
      if (row[x]) splat.cells.push_back(SplatCell{x + x0, y + y0, row[x]});
    }
  }
  return splat;
}

}  // namespace lanemap::bev
