// The car's path through each intersection (see passage_recorder.h).
#include "core/tracking/passage_recorder.h"

#include <algorithm>
#include <cmath>

namespace lanemap::tracking {

void PassageRecorder::addPosition(const Eigen::Vector2d& p) {
  if (!p.allFinite()) return;
  if (!trail_.empty() && (p - trail_.back()).norm() < o_.spacing_m) return;
  along_.push_back(trail_.empty() ? 0.0 : along_.back() + (p - trail_.back()).norm());
  trail_.push_back(p);
  // Keep what a passage can still need: from the intersection reached (if any), else lead_m.
  const double keep_from = reached_ ? along_[static_cast<size_t>(std::max<int64_t>(0, reached_->first - dropped_))]
                                    : along_.back() - o_.lead_m - o_.spacing_m;
  // (or, lingering, at most max_length_m + lead_m of it)
  while (trail_.size() > 2 && (along_[1] <= keep_from || along_.back() - along_.front() > o_.max_length_m + o_.lead_m)) {
    trail_.pop_front();
    along_.pop_front();
    ++dropped_;
  }
}

std::optional<intersections::DrivenPassage> PassageRecorder::onEvent(const RoadEvent& e) {
  switch (e.type) {
    case RoadEventType::kReachedIntersection: {
      Reached r;
      r.road = e.road_id;
      r.intersection = e.intersection_id;
      r.first = dropped_;
      if (!trail_.empty()) {
        const double from = along_.back() - o_.lead_m;
        size_t k = 0;
        while (k + 1 < trail_.size() && along_[k + 1] <= from) ++k;
        r.first = dropped_ + static_cast<int64_t>(k);
      }
      reached_ = r;
      return std::nullopt;
    }
    case RoadEventType::kEnteredRoad: {
      if (!reached_ || e.previous_road_id != reached_->road) {
        reached_.reset();
        return std::nullopt;
      }
      const Reached r = *reached_;
      reached_.reset();
      const int64_t first = r.first - dropped_;
      if (first < 0 || trail_.size() < 2 || static_cast<size_t>(first) + 2 > trail_.size()) return std::nullopt;
      if (along_.back() - along_[static_cast<size_t>(first)] > o_.max_length_m) return std::nullopt;
      intersections::DrivenPassage p;
      p.intersection_id = r.intersection;
      p.from_road = r.road;
      p.to_road = e.road_id;
      p.path.assign(trail_.begin() + first, trail_.end());
      return p;
    }
    case RoadEventType::kLeftMap:
    case RoadEventType::kPoseLost:
      reached_.reset();
      return std::nullopt;
    default:
      return std::nullopt;
  }
}

}  // namespace lanemap::tracking
