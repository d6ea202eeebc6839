// The lane pairing rules on their own (intersections::pairLanes, METHOD.md section 5): which in
// lane goes to which out lane for one movement, from turn:lanes or the defaults.
#include "core/intersections/intersections.h"

#include <gtest/gtest.h>

#include <utility>
#include <vector>

namespace {

using lanemap::intersections::Movements;
using lanemap::intersections::pairLanes;
using lanemap::intersections::parseTurnLane;
using lanemap::map::TurnDirection;
using Pairs = std::vector<std::pair<int, int>>;

std::vector<Movements> lanes(std::initializer_list<const char*> entries) {
  std::vector<Movements> out;
  for (const char* e : entries) out.push_back(parseTurnLane(e));
  return out;
}

TEST(PairLanes, UntaggedLanesGoStraightSideBySideAndTurnFromTheirEdge) {
  const auto two = lanes({"", ""});
  EXPECT_EQ(pairLanes(two, 2, TurnDirection::kStraight, false, true), (Pairs{{0, 0}, {1, 1}}));
  // Into one lane: the left one continues (right-hand traffic), the other is unpaired.
  EXPECT_EQ(pairLanes(two, 1, TurnDirection::kStraight, false, true), (Pairs{{0, 0}}));
  // Into three: the leftmost two out lanes.
  EXPECT_EQ(pairLanes(two, 3, TurnDirection::kStraight, false, true), (Pairs{{0, 0}, {1, 1}}));
  // Turns: the edge lane on the turn's side into the out road's lane on that side.
  EXPECT_EQ(pairLanes(two, 3, TurnDirection::kLeft, false, true), (Pairs{{0, 0}}));
  EXPECT_EQ(pairLanes(two, 3, TurnDirection::kRight, false, true), (Pairs{{1, 2}}));
  // Left-hand traffic: straight lanes align on the right.
  EXPECT_EQ(pairLanes(two, 3, TurnDirection::kStraight, false, false), (Pairs{{1, 2}, {0, 1}}));
}

TEST(PairLanes, TurnLanesTagsChooseTheLanesOfEachMovement) {
  const auto tagged = lanes({"left", "through", "through;right"});
  EXPECT_EQ(pairLanes(tagged, 2, TurnDirection::kStraight, false, true), (Pairs{{1, 0}, {2, 1}}));
  EXPECT_EQ(pairLanes(tagged, 2, TurnDirection::kLeft, false, true), (Pairs{{0, 0}}));
  EXPECT_EQ(pairLanes(tagged, 2, TurnDirection::kRight, false, true), (Pairs{{2, 1}}));
  // A double left turn fills the two leftmost out lanes.
  const auto double_left = lanes({"left", "left", "through"});
  EXPECT_EQ(pairLanes(double_left, 3, TurnDirection::kLeft, false, true), (Pairs{{0, 0}, {1, 1}}));
  EXPECT_EQ(pairLanes(double_left, 3, TurnDirection::kStraight, false, true), (Pairs{{2, 0}}));
  // No lane tagged right and the right edge lane is tagged: no right turn at all.
  EXPECT_TRUE(pairLanes(double_left, 2, TurnDirection::kRight, false, true).empty());
  // An untagged edge lane among tagged ones may still turn.
  EXPECT_EQ(pairLanes(lanes({"left", ""}), 2, TurnDirection::kRight, false, true), (Pairs{{1, 1}}));
}

TEST(PairLanes, AUturnTakesOneLaneIntoTheInnermostOutLane) {
  EXPECT_EQ(pairLanes(lanes({"", ""}), 2, TurnDirection::kLeft, true, true), (Pairs{{0, 0}}));
  EXPECT_EQ(pairLanes(lanes({"through", "reverse;left"}), 2, TurnDirection::kLeft, true, true), (Pairs{{1, 0}}));
  EXPECT_EQ(pairLanes(lanes({"", ""}), 2, TurnDirection::kRight, true, false), (Pairs{{1, 1}}));
}

TEST(PairLanes, NoLanesNoPairs) {
  EXPECT_TRUE(pairLanes({}, 2, TurnDirection::kStraight, false, true).empty());
  EXPECT_TRUE(pairLanes(lanes({""}), 0, TurnDirection::kStraight, false, true).empty());
}

}  // namespace
