// The one reader of OSM turn:lanes (core/osm/turn_lanes.h), shared by the mapper's lane pairing and
// the simulator's world: entries split left to right, each entry's movements.
#include "core/osm/turn_lanes.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using lanemap::osm::LaneMovements;
using lanemap::osm::parseTurnLane;

std::string moves(const LaneMovements& m) {
  if (!m.specified) return "-";
  std::string s;
  if (m.left) s += "L";
  if (m.straight) s += "S";
  if (m.right) s += "R";
  if (m.reverse) s += "U";
  return s;
}

TEST(TurnLanes, EachEntrySaysItsMovements) {
  EXPECT_EQ(moves(parseTurnLane("")), "-");
  EXPECT_EQ(moves(parseTurnLane("none")), "-");
  EXPECT_EQ(moves(parseTurnLane("left")), "L");
  EXPECT_EQ(moves(parseTurnLane("slight_left")), "L");
  EXPECT_EQ(moves(parseTurnLane("sharp_right")), "R");
  EXPECT_EQ(moves(parseTurnLane("through")), "S");
  EXPECT_EQ(moves(parseTurnLane("left;through")), "LS");
  EXPECT_EQ(moves(parseTurnLane("through;slight_right")), "SR");
  EXPECT_EQ(moves(parseTurnLane("left;through;right")), "LSR");
  EXPECT_EQ(moves(parseTurnLane("reverse;left")), "LU");
  // A lane that ends by merging goes on straight, whichever side it merges to.
  EXPECT_EQ(moves(parseTurnLane("merge_to_left")), "S");
  EXPECT_EQ(moves(parseTurnLane("merge_to_right")), "S");
  // Spaces around the movements (seen in hand-edited data) change nothing; unknown words are no movement.
  EXPECT_EQ(moves(parseTurnLane(" left ; through ")), "LS");
  EXPECT_EQ(moves(parseTurnLane("none;right")), "R");
  EXPECT_EQ(moves(parseTurnLane("bogus")), "-");
}

TEST(TurnLanes, AValueIsItsLanesLeftToRightEmptyEntriesKept) {
  EXPECT_EQ(lanemap::osm::splitTurnLanes("left|through|through;right"),
            (std::vector<std::string>{"left", "through", "through;right"}));
  EXPECT_EQ(lanemap::osm::splitTurnLanes("left||"), (std::vector<std::string>{"left", "", ""}));
  EXPECT_EQ(lanemap::osm::splitTurnLanes("through"), (std::vector<std::string>{"through"}));
  EXPECT_EQ(lanemap::osm::turnLaneCount("left||"), 3);
  EXPECT_EQ(lanemap::osm::turnLaneCount("through"), 1);
  EXPECT_EQ(lanemap::osm::turnLaneCount(""), -1) << "no tag: no count";
}

}  // namespace
