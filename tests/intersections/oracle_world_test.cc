// Intersections on the simulator's world (West Oakland, built in-process): the ground truth's own
// road lanelets go in (oracle lanes, grouped with roadsOf), buildIntersections joins them, and
// core/eval scores the result against the ground truth's intersection lanelets. The simulator
// lays out its connections with rules close to ours (turn pockets, turn:lanes, lane drops), so the
// topology must come out nearly perfect; the trajectories differ where the simulator's lane ends
// and curve parameters differ from ours. Also checks the assembled map (road lanelets + every
// intersection) is one Lanelet2 file that our writer accepts and the reader reads back with the
// same topology.
#include "core/eval/evaluate.h"
#include "core/intersections/intersections.h"
#include "core/io/lanelet2.h"
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/truth_world.h"

#include <gtest/gtest.h>

#include <chrono>
#include <set>

namespace {

using namespace lanemap;

struct Fixture {
  const lanemap::testing::TruthWorld* w = nullptr;  // West Oakland, seed 3
  const sim::SimWorld* world = nullptr;
  map::LaneMap built;  // truth road lanelets + our intersections
  size_t fragments = 0, connections = 0, quadratic = 0;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture f;
    f.w = &lanemap::testing::westOaklandTruthWorld();
    f.world = f.w->world.get();
    const map::LaneMap& truth = f.world->truth();
    const auto& roads = f.w->roads;
    f.built.origin_lat = truth.origin_lat;
    f.built.origin_lon = truth.origin_lon;
    f.built.origin_alt = truth.origin_alt;
    std::set<int64_t> lines;  // a line two roads share (the centre line) is in both road maps
    for (const auto& [id, m] : roads) {
      for (const auto& l : m.lines) {
        if (lines.insert(l.id).second) f.built.lines.push_back(l);
      }
      for (auto ll : m.lanelets) {
        // Keep the road-internal successors only (splits, merges, pieces).
        std::vector<int64_t> keep;
        for (int64_t s : ll.successors) {
          const auto* x = truth.lanelet(s);
          if (x && x->kind == map::LaneletKind::kRoad) keep.push_back(s);
        }
        ll.successors = keep;
        f.built.lanelets.push_back(ll);
      }
    }
    for (const auto& r : intersections::buildIntersections(*f.w->sk, roads, {}, f.w->data.restrictions)) {
      ++f.fragments;
      f.connections += r.connections.size();
      for (const auto& c : r.connections) f.quadratic += c.quadratic ? 1 : 0;
      intersections::appendIntersection(f.built, r);
    }
    return f;
  }();
  return f;
}

TEST(OracleWorld, TopologyMatchesTheSimulatorsGroundTruth) {
  const Fixture& f = fixture();
  const auto& truth = f.world->truth();
  const eval::EvalReport r = eval::evaluate(truth, f.built);
  std::printf("intersections %zu, connections %zu (quadratic %zu), truth intersection lanelets %zu\n",
              f.fragments, f.connections, f.quadratic, r.truth_intersection_lanelets);
  std::printf("%s", eval::summary(r).c_str());
  // The road lanes are the truth's own.
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 1.0);
  ASSERT_GT(r.intersection_recall.total, 50u);
  // The paper reports 0.91 / 0.80 (Berkeley) on its own lanes; on oracle lanes we must do better.
  EXPECT_GE(r.intersection_precision.value(), 0.95);
  EXPECT_GE(r.intersection_recall.value(), 0.95);
  // Same end points, tangents and curve family as the simulator: trajectories within decimetres.
  EXPECT_LT(r.intersection_rms_m, 0.25);
  EXPECT_GT(f.quadratic, 0u);
}

TEST(OracleWorld, AssembledMapRoundTripsThroughLanelet2) {
  const Fixture& f = fixture();
  lanemap::testing::TempDir dir("oracle-world");
  const std::string path = dir.str("map.osm");
  io::writeLanelet2(f.built, path);  // throws on a wrongly oriented lanelet
  io::Lanelet2ReadOptions ro;
  ro.origin_alt = f.built.origin_alt;
  const auto back = io::readLanelet2(path, f.built.origin_lat, f.built.origin_lon, ro);
  ASSERT_EQ(back.lanelets.size(), f.built.lanelets.size());
  // Successors recovered from shared points give the same intersection topology.
  const eval::EvalReport r = eval::evaluate(f.built, back);
  EXPECT_DOUBLE_EQ(r.intersection_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.intersection_recall.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.graph_precision.value(), 1.0);
  // (Not graph recall: the simulator's turn-pocket splits do not share both bounds' end points, so
  // Lanelet2's rule cannot recover those road-internal successors from a file.)
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 1.0);
  // No intersection lanelet both diverges and merges (Lanelet2's routing graph forbids it).
  std::map<int64_t, int> preds;
  for (const auto& ll : back.lanelets) {
    for (int64_t s : ll.successors) ++preds[s];
  }
  for (const auto& ll : back.lanelets) {
    if (ll.kind != map::LaneletKind::kIntersection) continue;
    EXPECT_EQ(ll.successors.size(), 1u) << ll.id;
    EXPECT_EQ(preds[ll.id], 1) << ll.id;
  }
}

}  // namespace
