// Map evaluation: MapTR's Chamfer AP (see evaluate.h for the definition): the instances of the two
// classes (centre lines, boundaries), resampled to chamfer_points points, and the AP of each class.
#include "core/eval/evaluate_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace lanemap::eval::internal {

namespace {

Instance instance(const Polyline& pts, const EvalOptions& o) {
  Instance in;
  in.pts = resampleCount(pts, o.chamfer_points);
  in.box.add(in.pts);
  in.score = polylineLength(pts);
  return in;
}

}  // namespace

void makeChamferInstances(Prepared& p, const std::vector<Polyline>& intersection_centres, const EvalOptions& o) {
  for (const auto& lane : p.lanes) {
    if (lane.centre.size() >= 2) p.centres.push_back(instance(lane.centre, o));
  }
  for (const Polyline& c : intersection_centres) {
    if (c.size() >= 2) p.centres.push_back(instance(c, o));
  }
  for (const auto& lane : p.lanes) {
    for (const Polyline* b : {&lane.left, &lane.right}) {
      if (b->size() < 2) continue;
      Instance in = instance(*b, o);
      const bool dup = std::any_of(p.bounds.begin(), p.bounds.end(), [&](const Instance& k) {
        return k.box.gap(in.box) < o.duplicate_chamfer_m && chamferDistance(k.pts, in.pts) < o.duplicate_chamfer_m;
      });
      if (!dup) p.bounds.push_back(std::move(in));
    }
  }
}

ApResult averagePrecision(const std::vector<Instance>& truth, const std::vector<Instance>& pred,
                          const std::vector<double>& thresholds) {
  ApResult r;
  r.truth_instances = truth.size();
  r.predictions = pred.size();
  std::vector<size_t> order(pred.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return pred[a].score > pred[b].score; });
  // Nearest truth instance of every prediction (independent of the threshold).
  std::vector<long> nearest(pred.size(), -1);
  std::vector<double> dist(pred.size(), std::numeric_limits<double>::infinity());
  for (size_t p = 0; p < pred.size(); ++p) {
    for (size_t g = 0; g < truth.size(); ++g) {
      if (pred[p].box.gap(truth[g].box) >= dist[p]) continue;
      const double cd = chamferDistance(pred[p].pts, truth[g].pts);
      if (cd < dist[p]) {
        dist[p] = cd;
        nearest[p] = static_cast<long>(g);
      }
    }
  }
  for (double thr : thresholds) {
    if (truth.empty()) {
      r.ap[thr] = kNaN;
      continue;
    }
    std::vector<bool> covered(truth.size(), false);
    std::vector<double> rec, prec;
    size_t tp = 0, fp = 0;
    for (size_t p : order) {
      if (nearest[p] >= 0 && dist[p] < thr && !covered[nearest[p]]) {
        covered[nearest[p]] = true;
        ++tp;
      } else {
        ++fp;
      }
      rec.push_back(static_cast<double>(tp) / static_cast<double>(truth.size()));
      prec.push_back(static_cast<double>(tp) / static_cast<double>(tp + fp));
    }
    std::vector<double> mrec{0.0}, mpre{0.0};
    mrec.insert(mrec.end(), rec.begin(), rec.end());
    mpre.insert(mpre.end(), prec.begin(), prec.end());
    mrec.push_back(1.0);
    mpre.push_back(0.0);
    for (size_t i = mpre.size() - 1; i > 0; --i) mpre[i - 1] = std::max(mpre[i - 1], mpre[i]);
    double ap = 0.0;
    for (size_t i = 0; i + 1 < mrec.size(); ++i) {
      if (mrec[i + 1] != mrec[i]) ap += (mrec[i + 1] - mrec[i]) * mpre[i + 1];
    }
    r.ap[thr] = ap;
  }
  return r;
}

void scoreChamferAp(const Prepared& truth, const Prepared& built, const EvalOptions& o, EvalReport& r) {
  r.ap_centre = averagePrecision(truth.centres, built.centres, o.chamfer_thresholds);
  r.ap_boundary = averagePrecision(truth.bounds, built.bounds, o.chamfer_thresholds);
  for (double thr : o.chamfer_thresholds) {
    std::vector<double> v;
    for (const ApResult* a : {&r.ap_centre, &r.ap_boundary}) {
      if (std::isfinite(a->ap.at(thr))) v.push_back(a->ap.at(thr));
    }
    r.chamfer_ap[thr] = meanOf(v);
  }
}

}  // namespace lanemap::eval::internal
