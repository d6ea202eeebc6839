// The car's path through an intersection cut from its positions by the road tracker's events
// (core/tracking/passage_recorder.h): from lead_m before the intersection was reached to where the
// next road was entered; nothing when the events do not follow on (left the map between, another
// road before).
#include "core/tracking/passage_recorder.h"

#include <gtest/gtest.h>

namespace {

using Eigen::Vector2d;
using lanemap::tracking::PassageRecorder;
using lanemap::tracking::RoadEvent;
using lanemap::tracking::RoadEventType;

RoadEvent event(RoadEventType type, int64_t road, int64_t previous = -1) {
  RoadEvent e;
  e.type = type;
  e.road_id = road;
  e.previous_road_id = previous;
  e.intersection_id = 77;
  return e;
}

// North along x = 0 from y = -100 to y = 0 every 0.1 m, then east along y = 0 to x = 50; the
// intersection is reached at y = -12 (road 1) and road 2 entered at x = 20.
struct Drive {
  std::vector<Vector2d> points;
  Drive() {
    for (double y = -100.0; y < 0.0; y += 0.1) points.emplace_back(0.0, y);
    for (double x = 0.0; x <= 50.0; x += 0.1) points.emplace_back(x, 0.0);
  }
};

TEST(PassageRecorder, FromLeadMetresBeforeTheIntersectionToTheNextRoad) {
  PassageRecorder r;
  std::optional<lanemap::intersections::DrivenPassage> got;
  for (const auto& p : Drive().points) {
    r.addPosition(p);
    if (std::abs(p.y() + 12.0) < 0.05 && p.x() == 0.0) {
      EXPECT_FALSE(r.onEvent(event(RoadEventType::kReachedIntersection, 1)));
    }
    if (std::abs(p.x() - 20.0) < 0.05 && p.y() == 0.0) got = r.onEvent(event(RoadEventType::kEnteredRoad, 2, 1));
  }
  ASSERT_TRUE(got);
  EXPECT_EQ(got->from_road, 1);
  EXPECT_EQ(got->to_road, 2);
  EXPECT_EQ(got->intersection_id, 77);
  // Starts 15 m (lead_m) before y = -12, within one spacing; ends where road 2 was entered.
  EXPECT_NEAR(got->path.front().x(), 0.0, 1e-9);
  EXPECT_NEAR(got->path.front().y(), -27.0, 0.55);
  EXPECT_NEAR((got->path.back() - Vector2d(20.0, 0.0)).norm(), 0.0, 0.55);
  for (size_t k = 1; k < got->path.size(); ++k) EXPECT_GE((got->path[k] - got->path[k - 1]).norm(), 0.5 - 1e-9);
}

TEST(PassageRecorder, NothingWhenTheEventsDoNotFollowOn) {
  for (const auto broken : {RoadEventType::kLeftMap, RoadEventType::kPoseLost}) {
    PassageRecorder r;
    for (const auto& p : Drive().points) {
      r.addPosition(p);
      if (std::abs(p.y() + 12.0) < 0.05 && p.x() == 0.0) r.onEvent(event(RoadEventType::kReachedIntersection, 1));
      if (std::abs(p.x() - 5.0) < 0.05 && p.y() == 0.0) r.onEvent(event(broken, -1));
      if (std::abs(p.x() - 20.0) < 0.05 && p.y() == 0.0) {
        EXPECT_FALSE(r.onEvent(event(RoadEventType::kEnteredRoad, 2, 1)));
      }
    }
  }
  PassageRecorder r;  // entered from another road than the one that reached the intersection
  for (const auto& p : Drive().points) {
    r.addPosition(p);
    if (std::abs(p.y() + 12.0) < 0.05 && p.x() == 0.0) r.onEvent(event(RoadEventType::kReachedIntersection, 1));
    if (std::abs(p.x() - 20.0) < 0.05 && p.y() == 0.0) {
      EXPECT_FALSE(r.onEvent(event(RoadEventType::kEnteredRoad, 2, 9)));
    }
  }
  PassageRecorder lingering;  // 500 m driven between the intersection and the next road: no passage
  lingering.addPosition({0.0, -20.0});
  lingering.onEvent(event(RoadEventType::kReachedIntersection, 1));
  for (double x = 0.0; x < 500.0; x += 0.5) lingering.addPosition({x, 0.0});
  EXPECT_FALSE(lingering.onEvent(event(RoadEventType::kEnteredRoad, 2, 1)));
}

}  // namespace
