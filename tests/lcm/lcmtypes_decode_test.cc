// Guards the -fno-strict-aliasing flag in CMakeLists.txt: LCM 1.3.1 decodes double fields through
// int64_t pointers, and at -O2 GCC then returns the field's previous value (0 after value
// initialisation) instead of the decoded one.
#include "lanemap/pose_t.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace {

TEST(LcmTypes, DecodeIntoValueInitialisedMessageKeepsDoubles) {
  lanemap::pose_t in{};
  in.utime = 1234567;
  in.latitude = 37.8057;
  in.longitude = -122.3004;
  in.altitude = 12.5;
  in.orientation[0] = 0.5;
  in.velocity_enu[1] = -3.25;
  in.status = lanemap::pose_t::STATUS_RTK_FIXED;
  std::vector<uint8_t> buf(in.getEncodedSize());
  ASSERT_EQ(in.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));

  lanemap::pose_t out{};  // value-initialised: the case the optimiser got wrong
  ASSERT_EQ(out.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_EQ(out.utime, 1234567);
  EXPECT_DOUBLE_EQ(out.latitude, 37.8057);
  EXPECT_DOUBLE_EQ(out.longitude, -122.3004);
  EXPECT_DOUBLE_EQ(out.altitude, 12.5);
  EXPECT_DOUBLE_EQ(out.orientation[0], 0.5);
  EXPECT_DOUBLE_EQ(out.velocity_enu[1], -3.25);
  EXPECT_EQ(out.status, +lanemap::pose_t::STATUS_RTK_FIXED);
}

}  // namespace
