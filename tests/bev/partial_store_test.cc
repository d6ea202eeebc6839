// Partial roads in the map store (issue 14, core/bev/bev_store.h): the road a drive ended on is
// stored partial with the station it reached; two drives ending on it merge there; a drive that
// closes it completes it (its partial evidence merged, aligned, into the road's grid, the partial
// files gone), and a crash between saving the road's grid and removing the partial does not merge
// the partial a second time.
#include "core/bev/bev_store.h"

#include "tests/bev/synthetic_road.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace lanemap::bev {
namespace {

using testing::solidLine;
using testing::traversal;

// A traversal of road 7 over east x0..x1 with a pose offset, 30 frames.
RoadBev pass(const Eigen::Vector2d& offset, uint32_t seed, double x0 = 0, double x1 = 60) {
  RoadBev r;
  r.road_id = 7;
  r.grid = traversal(offset, seed, true, x0, x1);
  return r;
}

TEST(PartialStore, ADriveEndingOnARoadStoresItPartialAndALaterDriveCompletesIt) {
  lanemap::testing::TempDir dir("partial-store");
  const std::string store = dir.str();
  EXPECT_FALSE(partialRoad(store, 7).has_value());

  // Drive 1 ends 25 m into the road (its camera saw to 35 m).
  StoredRoad s = storePartialRoad(store, pass({0.3, -0.4}, 1, 0, 35), 25.0, 60.0);
  EXPECT_TRUE(s.partial);
  EXPECT_FALSE(s.merged);
  EXPECT_EQ(s.path, partialGridPath(store, 7));
  EXPECT_FALSE(std::filesystem::exists(roadGridPath(store, 7)));
  auto p = partialRoad(store, 7);
  ASSERT_TRUE(p.has_value());
  EXPECT_DOUBLE_EQ(p->station_m, 25.0);
  EXPECT_DOUBLE_EQ(p->road_length_m, 60.0);
  EXPECT_EQ(p->frames, 30);
  EXPECT_EQ(partialRoads(store).size(), 1u);
  EXPECT_EQ(BevGrid::readHeader(partialGridPath(store, 7)).traversals, 1);

  // Drive 2 ends on it too, less far: merged (aligned), the further station kept.
  s = storePartialRoad(store, pass({-0.2, 0.3}, 2, 0, 30), 18.0, 60.0);
  EXPECT_TRUE(s.partial);
  EXPECT_TRUE(s.merged);
  ASSERT_TRUE(s.alignment.ok) << s.alignment.why;
  EXPECT_NEAR(s.alignment.shift_m.y(), -0.4 - 0.3, 0.101);
  EXPECT_DOUBLE_EQ(s.station_m, 25.0);
  p = partialRoad(store, 7);
  ASSERT_TRUE(p.has_value());
  EXPECT_DOUBLE_EQ(p->station_m, 25.0);
  EXPECT_EQ(p->frames, 60);
  EXPECT_EQ(BevGrid::readHeader(partialGridPath(store, 7)).traversals, 2);

  // Drive 3 closes the road: the partial evidence joins it, the road is complete.
  s = storeRoad(store, pass({0.1, 0.1}, 3));
  EXPECT_FALSE(s.merged);  // no complete grid before
  EXPECT_TRUE(s.completed_partial);
  ASSERT_TRUE(s.partial_alignment.ok) << s.partial_alignment.why;
  EXPECT_EQ(s.frames, 90);
  EXPECT_FALSE(partialRoad(store, 7).has_value());
  EXPECT_FALSE(std::filesystem::exists(partialGridPath(store, 7)));
  EXPECT_TRUE(partialRoads(store).empty());
  const BevGrid stored = BevGrid::load(roadGridPath(store, 7));
  EXPECT_EQ(stored.frames(), 90);
  EXPECT_EQ(stored.traversals(), 3) << "two partial drives and the one that closed it";
  // Aligned: the line stays sharp (the three passes' offsets differ by up to 0.7 m).
  EXPECT_LT(solidLine(stored).second, solidLine(traversal({0, 0}, 9)).second + 0.05);

  // A road complete in the store: a drive ending on it adds its evidence there, nothing partial.
  s = storePartialRoad(store, pass({0.1, 0.1}, 4, 0, 20), 12.0, 60.0);
  EXPECT_FALSE(s.partial);
  EXPECT_TRUE(s.merged);
  EXPECT_EQ(s.frames, 120);
  EXPECT_FALSE(std::filesystem::exists(partialGridPath(store, 7)));
  const auto header = BevGrid::readHeader(roadGridPath(store, 7));
  EXPECT_EQ(header.frames, 120);
  EXPECT_EQ(header.traversals, 4);
}

TEST(PartialStore, ACrashAfterCompletingDoesNotMergeThePartialTwice) {
  lanemap::testing::TempDir dir("partial-crash");
  const std::string store = dir.str();
  storePartialRoad(store, pass({0, 0}, 1, 0, 35), 25.0, 60.0);
  // Keep a copy of the partial's files, as a crash between saving the road's grid and removing
  // them would leave them (with the JSON naming the grid it went into).
  const std::string grid_copy = dir.str("partial.bev"), meta = partialGridPath(store, 7).substr(0, partialGridPath(store, 7).size() - 4) + ".json";
  std::filesystem::copy_file(partialGridPath(store, 7), grid_copy);
  const StoredRoad s = storeRoad(store, pass({0, 0}, 2));
  ASSERT_TRUE(s.completed_partial);
  ASSERT_EQ(s.frames, 60);
  std::filesystem::copy_file(grid_copy, partialGridPath(store, 7));
  nlohmann::json j{{"road_id", 7}, {"station_m", 25.0}, {"road_length_m", 60.0}, {"frames", 30},
                   {"completed_into", std::to_string(gridHash(BevGrid::load(roadGridPath(store, 7))))}};
  std::ofstream(meta) << j.dump();
  EXPECT_FALSE(partialRoad(store, 7).has_value()) << "the partial is in the road's grid already";
  EXPECT_FALSE(std::filesystem::exists(partialGridPath(store, 7))) << "and is removed";
  EXPECT_EQ(storeRoad(store, pass({0, 0}, 3)).frames, 90) << "a later drive adds its own frames only";

  // A crash before the road's grid was saved (the JSON names a grid that is not on disk): the
  // partial is still pending and merged by the next storeRoad.
  lanemap::testing::TempDir dir2("partial-crash2");
  storePartialRoad(dir2.str(), pass({0, 0}, 1, 0, 35), 25.0, 60.0);
  const std::string meta2 = partialGridPath(dir2.str(), 7).substr(0, partialGridPath(dir2.str(), 7).size() - 4) + ".json";
  std::ofstream(meta2) << nlohmann::json{{"road_id", 7}, {"station_m", 25.0}, {"road_length_m", 60.0}, {"frames", 30},
                                         {"completed_into", "12345"}}.dump();
  ASSERT_TRUE(partialRoad(dir2.str(), 7).has_value());
  const StoredRoad s2 = storeRoad(dir2.str(), pass({0, 0}, 2));
  EXPECT_TRUE(s2.completed_partial);
  EXPECT_EQ(s2.frames, 60);

  // A partial grid without its JSON (a crash between the two): its station is unknown, no partial.
  lanemap::testing::TempDir dir3("partial-crash3");
  storePartialRoad(dir3.str(), pass({0, 0}, 1, 0, 35), 25.0, 60.0);
  std::filesystem::remove(partialGridPath(dir3.str(), 7).substr(0, partialGridPath(dir3.str(), 7).size() - 4) + ".json");
  EXPECT_FALSE(partialRoad(dir3.str(), 7).has_value());
}

}  // namespace
}  // namespace lanemap::bev
