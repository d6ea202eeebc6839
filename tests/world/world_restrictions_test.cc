// The simulator's truth honours OSM turn restrictions: a turn a type=restriction relation forbids
// at a junction node gets no intersection lanelet (no_*: that turn; only_*: every other turn out of
// the from way), while the same world built without the restrictions has it.
#include "core/sim/world_builder.h"
#include "tests/intersections/fixture.h"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <utility>

namespace lanemap::sim {
namespace {

// A four-way junction (node 1) of two-way residential streets, 80 m arms: west (way 10, from the
// west end to the junction), east (11), south (12), north (13).
testing::Net crossing() {
  testing::Net net;
  net.node(1, 0, 0);
  net.node(2, -80, 0);
  net.node(3, 80, 0);
  net.node(4, 0, -80);
  net.node(5, 0, 80);
  net.way(10, {2, 1});
  net.way(11, {1, 3});
  net.way(12, {4, 1});
  net.way(13, {1, 5});
  return net;
}

// The turns the truth built at the junction: (OSM way of the road in, OSM way of the road out).
std::set<std::pair<int64_t, int64_t>> turnsBuilt(const skeleton::Skeleton& sk, const SimWorld& w) {
  std::map<int64_t, int64_t> way_of_lanelet;  // road lanelets only
  for (const auto& l : w.truth().lanelets) {
    if (l.kind == map::LaneletKind::kRoad && l.road_id >= 0) way_of_lanelet[l.id] = sk.road(l.road_id)->way_id;
  }
  std::map<int64_t, int64_t> from_of_connector;  // intersection lanelet -> the road lanelet before it
  for (const auto& l : w.truth().lanelets) {
    if (l.kind != map::LaneletKind::kRoad) continue;
    for (const int64_t s : l.successors) from_of_connector[s] = l.id;
  }
  std::set<std::pair<int64_t, int64_t>> turns;
  for (const auto& l : w.truth().lanelets) {
    if (l.kind != map::LaneletKind::kIntersection || l.intersection_id != 1 || l.successors.empty()) continue;
    const auto from = from_of_connector.find(l.id);
    const auto to = way_of_lanelet.find(l.successors.front());
    if (from == from_of_connector.end() || to == way_of_lanelet.end()) continue;
    turns.emplace(way_of_lanelet.at(from->second), to->second);
  }
  return turns;
}

WorldOptions flatWorld() {
  WorldOptions o;
  o.seed = 3;
  o.flat = true;
  return o;
}

TEST(WorldRestrictions, NoTurnRestrictionRemovesThatTurnOnly) {
  testing::Net net = crossing();
  net.restriction("no_left_turn", 12, 1, 10);  // northbound from the south arm: no left into the west arm
  const skeleton::Skeleton sk = net.build();
  const auto free = turnsBuilt(sk, *buildWorld(sk, flatWorld()));
  const auto world = buildWorld(sk, flatWorld(), net.data.restrictions);
  const auto restricted = turnsBuilt(sk, *world);
  // Without restrictions: from each arm, the three other arms (no U-turns): 12 turns.
  ASSERT_EQ(free.size(), 12u);
  EXPECT_TRUE(free.count({12, 10}));
  EXPECT_FALSE(restricted.count({12, 10}));
  EXPECT_EQ(restricted.size(), 11u);
  EXPECT_TRUE(restricted.count({12, 11}));  // the right turn and straight on stay
  EXPECT_TRUE(restricted.count({12, 13}));
  EXPECT_EQ(world->stats().turns_restricted, 1u);
}

TEST(WorldRestrictions, OnlyRestrictionKeepsItsTurnAlone) {
  testing::Net net = crossing();
  net.restriction("only_straight_on", 10, 1, 11);  // eastbound from the west arm: straight on only
  net.restriction("no_right_turn", 13, 2, 10);     // its via node is not the junction: not applied
  const skeleton::Skeleton sk = net.build();
  const auto world = buildWorld(sk, flatWorld(), net.data.restrictions);
  const auto turns = turnsBuilt(sk, *world);
  EXPECT_TRUE(turns.count({10, 11}));
  EXPECT_FALSE(turns.count({10, 12}));
  EXPECT_FALSE(turns.count({10, 13}));
  EXPECT_EQ(turns.size(), 10u);  // 12 less the two turns out of the west arm the restriction forbids
  EXPECT_EQ(world->stats().turns_restricted, 2u);
  // Every lane into the junction still continues through it.
  for (const auto& l : world->truth().lanelets) {
    if (l.kind == map::LaneletKind::kRoad && l.to_node == 1) {
      EXPECT_FALSE(l.successors.empty()) << l.id;
    }
  }
}

}  // namespace
}  // namespace lanemap::sim
