// Bad poses (issue 18): out of order, duplicated, NaN or infinite, a time jump backwards (a log
// restarted), a gap of seconds, and a camera frame older than every pose -- each counted and
// handled by the three places poses are consumed: pose_conversion.h (pose_t -> ENU), the BEV
// builder (core/bev: PoseBuffer + BevBuilder) and the road tracker (core/tracking). The restart
// cases fail without core/geo/time_order.h: every pose after a restart used to be "out of order"
// until the new time passed the old one, so nothing was mapped or tracked again.
#include "core/bev/bev_builder.h"
#include "core/bev/pose_buffer.h"
#include "core/camera/camera_model.h"
#include "core/geo/time_order.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/road_tracker.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace {

using namespace lanemap;
using geo::TimeOrder;
constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

const skeleton::Skeleton& westOakland() {
  static const skeleton::Skeleton s =
      skeleton::Skeleton::build(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"));
  return s;
}

TEST(TimeOrder, ClassifiesEachTimestamp) {
  TimeOrder o(1.0, 3);
  EXPECT_EQ(o.check(kT0), TimeOrder::Verdict::kInOrder);
  EXPECT_EQ(o.check(kT0 + 10'000), TimeOrder::Verdict::kInOrder);
  EXPECT_EQ(o.check(kT0 + 10'000), TimeOrder::Verdict::kDuplicate);
  EXPECT_EQ(o.check(kT0 + 5'000), TimeOrder::Verdict::kOutOfOrder);   // late by 5 ms
  EXPECT_EQ(o.check(kT0 - 60'000'000), TimeOrder::Verdict::kOutOfOrder);  // one stale pose ...
  EXPECT_EQ(o.check(kT0 + 20'000), TimeOrder::Verdict::kInOrder);        // ... is not a restart
  EXPECT_EQ(o.last(), kT0 + 20'000);
  // A restarted log: 3 increasing poses 60 s back; the third is accepted as the new time.
  EXPECT_EQ(o.check(kT0 - 60'000'000), TimeOrder::Verdict::kOutOfOrder);
  EXPECT_EQ(o.check(kT0 - 59'990'000), TimeOrder::Verdict::kOutOfOrder);
  EXPECT_EQ(o.check(kT0 - 59'980'000), TimeOrder::Verdict::kRestart);
  EXPECT_EQ(o.last(), kT0 - 59'980'000);
  EXPECT_EQ(o.check(kT0 - 59'970'000), TimeOrder::Verdict::kInOrder);
  // Hostile extremes do not overflow (UBSan would report it) and are classified.
  TimeOrder x(1.0, 1);
  EXPECT_EQ(x.check(std::numeric_limits<int64_t>::max()), TimeOrder::Verdict::kInOrder);
  EXPECT_EQ(x.check(std::numeric_limits<int64_t>::min()), TimeOrder::Verdict::kRestart);
}

TEST(PoseConversion, NonFiniteOrInvalidPosesAreMarkedInvalid) {
  const geo::LocalFrame frame(geo::LatLonAlt{37.81, -122.29, 0});
  pose_t m{};
  m.utime = kT0;
  m.latitude = 37.81;
  m.longitude = -122.29;
  m.orientation[0] = 1;
  m.status = pose_t::STATUS_RTK_FIXED;
  EXPECT_TRUE(toEnuPose(m, frame).valid);
  for (double bad : {kNaN, kInf, -kInf}) {
    pose_t b = m;
    b.latitude = bad;
    const EnuPose p = toEnuPose(b, frame);
    EXPECT_FALSE(p.valid);
    EXPECT_FALSE(p.position.allFinite());
    EXPECT_FALSE(toPoseInput(p).valid);
  }
  pose_t lost = m;
  lost.status = pose_t::STATUS_INVALID;
  EXPECT_FALSE(toEnuPose(lost, frame).valid);
}

TEST(PoseBuffer, RejectsBadPosesAndSaysWhyALookupFails) {
  bev::PoseBuffer b(10.0, 0.25);
  auto pose = [](int64_t u) {
    bev::TimedPose p;
    p.utime = u;
    p.position = Eigen::Vector3d(1e-5 * static_cast<double>(u - kT0), 0, 0);
    return p;
  };
  Eigen::Isometry3d t;
  EXPECT_EQ(b.lookup(kT0, &t), bev::PoseBuffer::Lookup::kEmpty);
  for (int i = 0; i <= 10; ++i) EXPECT_TRUE(b.add(pose(kT0 + i * 10'000)));
  bev::TimedPose nan = pose(kT0 + 110'000);
  nan.position.y() = kNaN;
  EXPECT_FALSE(b.add(nan));
  bev::TimedPose inf = pose(kT0 + 110'000);
  inf.orientation.w() = kInf;
  EXPECT_FALSE(b.add(inf));
  EXPECT_FALSE(b.add(pose(kT0 + 50'000)));   // out of order
  EXPECT_FALSE(b.add(pose(kT0 + 100'000)));  // duplicate
  EXPECT_EQ(b.size(), 11u);
  EXPECT_EQ(b.lookup(kT0 - 1, &t), bev::PoseBuffer::Lookup::kTooOld);  // older than every pose
  EXPECT_EQ(b.lookup(kT0 + 100'001, &t), bev::PoseBuffer::Lookup::kTooNew);
  ASSERT_EQ(b.lookup(kT0 + 55'000, &t), bev::PoseBuffer::Lookup::kOk);
  EXPECT_NEAR(t.translation().x(), 0.55, 1e-9);
  EXPECT_TRUE(b.add(pose(kT0 + 3'100'000)));  // a gap of 3 s
  EXPECT_EQ(b.lookup(kT0 + 1'600'000, &t), bev::PoseBuffer::Lookup::kGap);
  // Extreme times: no signed overflow (UBSan) and a finite interpolation.
  bev::PoseBuffer x(10.0, 1e30);
  bev::TimedPose lo = pose(kT0), hi = pose(kT0);
  lo.utime = std::numeric_limits<int64_t>::min();
  hi.utime = std::numeric_limits<int64_t>::max();
  EXPECT_TRUE(x.add(lo));
  EXPECT_TRUE(x.add(hi));
  ASSERT_EQ(x.lookup(0, &t), bev::PoseBuffer::Lookup::kOk);
  EXPECT_TRUE(t.translation().allFinite());
  x.clear();
  EXPECT_TRUE(x.empty());
}

// BevBuilder: the whole list, in one stream, with the counts that show each was handled.
TEST(BevBuilderBadPoses, EachIsCountedAndMappingResumesAfterALogRestart) {
  const std::string src = LANEMAP_SOURCE_DIR;
  const auto camera = camera::CameraModel::fromYaml(loadYamlFile(src + "/config/vehicle.yaml")["camera"]);
  bev::BevBuilderOptions o = bev::BevBuilderOptions::fromYaml(loadYamlFile(src + "/config/bev_builder.yaml"));
  o.use_lidar = false;
  o.async_mesh = false;
  ASSERT_DOUBLE_EQ(o.time_jump_s, 1.0);
  bev::BevBuilder b(westOakland(), camera, o);
  auto pose = [](int64_t u) {
    bev::TimedPose p;
    p.utime = u;
    p.position = Eigen::Vector3d(1e-5 * static_cast<double>(u % 100'000'000), 0.0, 0.0);
    return p;
  };
  const cv::Mat labels(camera.height(), camera.width(), CV_8UC1, cv::Scalar(1));
  for (int64_t u = kT0; u <= kT0 + 1'000'000; u += 10'000) b.addPose(pose(u));  // 101 poses
  b.addFrame(kT0 + 500'000, labels);
  EXPECT_EQ(b.stats().frames_projected, 1);
  b.addPose(pose(kT0 + 1'000'000));  // duplicated
  b.addPose(pose(kT0 - 5'000'000));  // one stale pose from 5 s before: out of order
  b.addPose(pose(kT0 + 990'000));    // 10 ms late: out of order
  bev::TimedPose nan = pose(kT0 + 1'010'000);
  nan.position.x() = kNaN;
  b.addPose(nan);
  bev::TimedPose inf = pose(kT0 + 1'010'000);
  inf.orientation.x() = kInf;
  b.addPose(inf);
  b.addFrame(kT0 + 1'500'000, labels);  // waits for a later pose, which never comes in this time
  EXPECT_EQ(b.pendingFrames(), 1u);
  // The log restarts 60 s earlier: after 3 poses the builder starts over.
  const int64_t r0 = kT0 - 60'000'000;
  for (int64_t u = r0; u < r0 + 30'000; u += 10'000) b.addPose(pose(u));
  auto s = b.stats();
  EXPECT_EQ(s.pose_time_jumps, 1);
  EXPECT_EQ(s.frames_time_jump, 1);
  EXPECT_EQ(b.pendingFrames(), 0u);
  b.addFrame(r0 + 10'000, labels);  // older than every pose of the new time (the first two were
                                    // confirming the restart): late
  for (int64_t u = r0 + 30'000; u <= r0 + 1'000'000; u += 10'000) b.addPose(pose(u));
  b.addFrame(r0 + 500'000, labels);  // projected: mapping resumed in the new time
  // A gap of 3 s in the poses: a frame inside it has no pose; one after it is projected.
  for (int64_t u = r0 + 4'000'000; u <= r0 + 4'500'000; u += 10'000) b.addPose(pose(u));
  b.addFrame(r0 + 2'500'000, labels);
  b.addFrame(r0 + 4'200'000, labels);
  s = b.stats();
  EXPECT_EQ(s.frames_received, 6);
  EXPECT_EQ(s.frames_projected, 3);
  EXPECT_EQ(s.frames_late, 1);
  EXPECT_EQ(s.frames_no_pose, 1);
  EXPECT_EQ(s.frames_out_of_order, 0);
  EXPECT_EQ(s.poses_duplicate, 1);
  EXPECT_EQ(s.poses_out_of_order, 2 + 2);  // stale + late, and the 2 poses confirming the restart
  EXPECT_EQ(s.poses_invalid, 2);
  EXPECT_EQ(s.poses_received, 101 + 5 + 3 + 98 + 51);
}

// RoadTracker on a real road of West Oakland: the car drives along it; each bad pose is counted,
// and after a log restart or a gap the tracker reports POSE_LOST and finds the road again.
TEST(RoadTrackerBadPoses, EachIsCountedAndTrackingResumes) {
  const auto& sk = westOakland();
  const skeleton::AtomicRoad* road = nullptr;
  for (const auto& r : sk.roads())
    if (r.s_end - r.s_begin > 120.0 && (!road || r.s_end - r.s_begin > road->s_end - road->s_begin)) road = &r;
  ASSERT_NE(road, nullptr);
  tracking::RoadTracker tracker(sk);
  const double speed = 8.0;
  auto at = [&](int64_t t0, int64_t u, double s0) {
    tracking::PoseInput p;
    p.utime = u;
    const double s = s0 + speed * static_cast<double>(u - t0) * 1e-6;
    p.position = sk.pointAt(*road, s);
    const Eigen::Vector2d d = sk.tangentAt(*road, s);
    p.heading = std::atan2(d.y(), d.x());
    p.velocity = d * speed;
    return p;
  };
  std::vector<tracking::RoadEvent> events;
  auto feed = [&](const tracking::PoseInput& p) {
    for (auto& e : tracker.update(p)) events.push_back(e);
  };
  const double s0 = road->s_begin + 5.0;
  int64_t u = kT0;
  for (; u < kT0 + 3'000'000; u += 100'000) feed(at(kT0, u, s0));  // 30 poses, 24 m
  ASSERT_EQ(tracker.currentRoad(), road->id);
  const auto before = tracker.stats();
  feed(at(kT0, u - 100'000, s0));   // duplicated
  feed(at(kT0, u - 250'000, s0));   // out of order
  feed(at(kT0, kT0 - 30'000'000, s0));  // one stale pose 30 s back
  tracking::PoseInput nan = at(kT0, u, s0);
  nan.position.x() = kNaN;
  feed(nan);
  u += 100'000;
  tracking::PoseInput inf = at(kT0, u, s0);
  inf.heading = kInf;
  feed(inf);
  u += 100'000;
  EXPECT_EQ(tracker.currentRoad(), road->id);  // nothing of that threw the car off its road
  EXPECT_TRUE(events.size() == 1 && events[0].type == tracking::RoadEventType::kEnteredRoad);
  auto s = tracker.stats();
  EXPECT_EQ(s.duplicates - before.duplicates, 1);
  EXPECT_EQ(s.out_of_order - before.out_of_order, 2);
  EXPECT_EQ(s.invalid - before.invalid, 2);

  // The log restarts 100 s earlier, at the start of the road.
  const int64_t r0 = kT0 - 100'000'000;
  events.clear();
  for (u = r0; u < r0 + 3'000'000; u += 100'000) feed(at(r0, u, s0));
  s = tracker.stats();
  EXPECT_EQ(s.time_jumps, 1);
  ASSERT_GE(events.size(), 2u);
  EXPECT_EQ(events[0].type, tracking::RoadEventType::kPoseLost);
  EXPECT_EQ(events[0].road_id, road->id);
  EXPECT_EQ(events[0].detail.rfind("time jumped back by", 0), 0u) << events[0].detail;
  EXPECT_EQ(events[1].type, tracking::RoadEventType::kEnteredRoad);
  EXPECT_EQ(events[1].road_id, road->id);
  EXPECT_EQ(tracker.currentRoad(), road->id);

  // A gap of 3 s without any pose: POSE_LOST, then the road again.
  events.clear();
  const int64_t g0 = u + 3'000'000;
  for (u = g0; u < g0 + 2'000'000; u += 100'000) feed(at(r0, u, s0));
  ASSERT_GE(events.size(), 2u);
  EXPECT_EQ(events[0].type, tracking::RoadEventType::kPoseLost);
  EXPECT_EQ(events[0].detail.rfind("no valid pose for 3.", 0), 0u) << events[0].detail;
  EXPECT_EQ(events[1].type, tracking::RoadEventType::kEnteredRoad);
  EXPECT_EQ(tracker.currentRoad(), road->id);
}

}  // namespace
