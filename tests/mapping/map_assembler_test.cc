// MapAssembler's incremental update (issue 14: closing a road rebuilds the two intersections at its
// ends, not every junction): on the simulator's West Oakland world (its ground truth's road
// lanelets as the mapped lanes), roads set one at a time in a shuffled order, some first with
// other lanes and then again with their own, must give exactly the map the full rebuild gives
// (every road's lanelets + buildIntersections over all roads + appendIntersection one by one):
// same lanelets, lines, successors and geometry. A road that marked only one of its ends, or an
// intersection kept from before a road changed, shows up as a difference.
#include "core/intersections/intersections.h"
#include "core/mapping/map_assembler.h"
#include "core/mapping/shared_dividers.h"
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/truth_world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <set>
#include <sstream>

namespace {

using namespace lanemap;

using World = lanemap::testing::TruthWorld;

const World& world() { return lanemap::testing::westOaklandTruthWorld(); }

// The map as the assembler built it before it was incremental: every road's lanelets, then every
// intersection rebuilt from all roads and appended one at a time (then, as since, the bounds of
// opposite lanes on top of each other made one line).
map::LaneMap fullRebuild(const World& w, const std::map<int64_t, map::LaneMap>& roads,
                         std::vector<std::string>* failures, bool share_dividers = true) {
  map::LaneMap all;
  const auto& o = w.sk->frame().origin();
  all.origin_lat = o.lat;
  all.origin_lon = o.lon;
  all.origin_alt = o.alt;
  std::set<int64_t> line_ids;
  for (const auto& [id, m] : roads) {
    for (const auto& l : m.lines) {
      if (line_ids.insert(l.id).second) all.lines.push_back(l);
    }
    all.lanelets.insert(all.lanelets.end(), m.lanelets.begin(), m.lanelets.end());
  }
  for (const auto& r : intersections::buildIntersections(*w.sk, roads, {}, w.data.restrictions, failures)) {
    intersections::appendIntersection(all, r);
  }
  if (share_dividers) mapping::shareDividers(all, *w.sk);  // as map() does: one line for two bounds on top of each other
  return all;
}

// Everything a writer would write, in order, as text: a difference anywhere is a mismatch.
std::string describe(const map::LaneMap& m) {
  std::ostringstream s;
  char buf[96];
  const auto point = [&](const Eigen::Vector3d& p) {
    std::snprintf(buf, sizeof buf, " %.6f,%.6f,%.6f", p.x(), p.y(), p.z());
    s << buf;
  };
  for (const auto& l : m.lines) {
    s << "line " << l.id << " " << static_cast<int>(l.type);
    for (const auto& p : l.points) point(p);
    s << "\n";
  }
  for (const auto& ll : m.lanelets) {
    s << "lanelet " << ll.id << " kind " << static_cast<int>(ll.kind) << " bounds " << ll.left_id << "," << ll.right_id
      << " road " << ll.road_id << " at " << ll.intersection_id << " turn " << static_cast<int>(ll.turn) << " next";
    for (const int64_t n : ll.successors) s << " " << n;
    s << " centre";
    for (const auto& p : ll.centre) point(p);
    s << "\n";
  }
  return s.str();
}

size_t countKind(const map::LaneMap& m, map::LaneletKind kind) {
  return static_cast<size_t>(std::count_if(m.lanelets.begin(), m.lanelets.end(),
                                           [&](const map::Lanelet& ll) { return ll.kind == kind; }));
}

TEST(MapAssembler, RoadsSetOneAtATimeInAnyOrderGiveTheFullRebuild) {
  const World& w = world();
  ASSERT_GT(w.roads.size(), 50u);
  std::vector<std::string> ref_failures;
  const map::LaneMap ref = fullRebuild(w, w.roads, &ref_failures);
  ASSERT_GT(countKind(ref, map::LaneletKind::kIntersection), 100u);

  std::vector<int64_t> order;
  for (const auto& [id, m] : w.roads) order.push_back(id);
  std::mt19937 rng(7);
  std::shuffle(order.begin(), order.end(), rng);

  mapping::MapAssembler a(*w.sk, {}, w.data.restrictions);
  // Every fifth road is first mapped with its neighbour's lanes shifted away (a wrong first
  // drive), its junctions built on those, then mapped again with its own lanes later on.
  std::vector<int64_t> again;
  for (size_t k = 0; k < order.size(); ++k) {
    const int64_t id = order[k];
    if (k % 5 == 0) {
      map::LaneMap wrong = w.roads.at(id);
      for (auto& ll : wrong.lanelets) {
        for (auto& p : ll.centre) p.x() += 1.5;
      }
      for (auto& l : wrong.lines) {
        for (auto& p : l.points) p.x() += 1.5;
      }
      a.setRoad(id, wrong);
      again.push_back(id);
    } else {
      a.setRoad(id, w.roads.at(id));
    }
    const size_t rebuilt = a.update();
    EXPECT_GE(rebuilt, 1u) << "road " << id;
    EXPECT_LE(rebuilt, 2u) << "road " << id;  // its two ends, never more
    EXPECT_EQ(a.update(), 0u);                 // nothing marked since
    if (k == order.size() / 2) {
      // A map exported half-way does not disturb what follows.
      const auto half = a.map();
      EXPECT_LT(half.lanelets.size(), ref.lanelets.size());
    }
  }
  const map::LaneMap before_again = a.map();
  EXPECT_NE(describe(before_again), describe(ref));  // the wrong lanes are in it
  for (const int64_t id : again) {
    a.setRoad(id, w.roads.at(id));
    EXPECT_LE(a.update(), 2u);
  }
  std::vector<std::string> failures;
  const map::LaneMap got = a.map(&failures);
  EXPECT_EQ(failures, ref_failures);
  EXPECT_EQ(got.lanelets.size(), ref.lanelets.size());
  EXPECT_EQ(got.lines.size(), ref.lines.size());
  EXPECT_EQ(countKind(got, map::LaneletKind::kIntersection), countKind(ref, map::LaneletKind::kIntersection));
  EXPECT_EQ(describe(got), describe(ref));
  EXPECT_EQ(a.roads().size(), w.roads.size());
}

TEST(MapAssembler, MovingOneRoadRebuildsTheIntersectionsAtItsEnds) {
  const World& w = world();
  mapping::MapAssembler a(*w.sk, {}, w.data.restrictions);
  for (const auto& [id, m] : w.roads) a.setRoad(id, m);
  a.update();
  std::map<int64_t, std::string> before;  // intersection id -> its fragment as text
  for (const auto* r : a.intersections()) before[r->intersection_id] = describe(r->map);
  ASSERT_GT(before.size(), 10u);

  // Shift one road's lanes 0.8 m: update() builds its two ends, and those fragments follow the
  // moved lanes; every other fragment is as before; the whole map is the full rebuild's on the
  // moved road.
  std::map<int64_t, map::LaneMap> moved_roads = w.roads;
  const int64_t id = w.roads.begin()->first;
  const auto* road = w.sk->road(id);
  ASSERT_NE(road, nullptr);
  ASSERT_NE(road->from, road->to);
  map::LaneMap& moved = moved_roads.at(id);
  for (auto& ll : moved.lanelets) {
    for (auto& p : ll.centre) p.y() += 0.8;
  }
  for (auto& l : moved.lines) {
    for (auto& p : l.points) p.y() += 0.8;
  }
  a.setRoad(id, moved);
  EXPECT_EQ(a.update(), 2u);
  size_t changed = 0;
  for (const auto* r : a.intersections()) {
    const auto it = before.find(r->intersection_id);
    ASSERT_NE(it, before.end());
    const bool differs = describe(r->map) != it->second;
    if (r->intersection_id == road->from || r->intersection_id == road->to) {
      changed += differs ? 1 : 0;
    } else {
      EXPECT_FALSE(differs) << "intersection " << r->intersection_id << " changed though no road of it did";
    }
  }
  EXPECT_GE(changed, 1u);
  EXPECT_EQ(describe(a.map()), describe(fullRebuild(w, moved_roads, nullptr)));
}

TEST(MapAssembler, AppendIntersectionsInOnePassEqualsAppendingOneByOne) {
  const World& w = world();
  std::vector<std::string> failures;
  const map::LaneMap ref = fullRebuild(w, w.roads, &failures, false);
  const auto results = intersections::buildIntersections(*w.sk, w.roads, {}, w.data.restrictions);
  std::vector<const intersections::IntersectionResult*> ptrs;
  for (const auto& r : results) ptrs.push_back(&r);

  // Onto the road lanelets alone (the one-pass path).
  map::LaneMap roads_only = ref;
  roads_only.lanelets.erase(std::remove_if(roads_only.lanelets.begin(), roads_only.lanelets.end(),
                                           [](const map::Lanelet& ll) { return ll.kind == map::LaneletKind::kIntersection; }),
                            roads_only.lanelets.end());
  std::set<int64_t> used;
  for (const auto& ll : roads_only.lanelets) used.insert({ll.left_id, ll.right_id});
  roads_only.lines.erase(std::remove_if(roads_only.lines.begin(), roads_only.lines.end(),
                                        [&](const map::LineString& l) { return used.count(l.id) == 0; }),
                         roads_only.lines.end());
  for (auto& ll : roads_only.lanelets) {
    ll.successors.erase(std::remove_if(ll.successors.begin(), ll.successors.end(),
                                       [&](int64_t s) {
                                         const auto* x = ref.lanelet(s);
                                         return x && x->kind == map::LaneletKind::kIntersection;
                                       }),
                        ll.successors.end());
  }
  map::LaneMap one_by_one = roads_only, one_pass = roads_only;
  for (const auto* r : ptrs) intersections::appendIntersection(one_by_one, *r);
  intersections::appendIntersections(one_pass, ptrs);
  EXPECT_EQ(describe(one_pass), describe(one_by_one));
  EXPECT_GT(countKind(one_pass, map::LaneletKind::kIntersection), 100u);

  // Onto a map that already holds them (replaced, as appendIntersection replaces).
  map::LaneMap twice = ref;
  intersections::appendIntersections(twice, ptrs);
  EXPECT_EQ(describe(twice), describe(ref));
}

TEST(MapAssembler, RefusesBadOptionsWhenMade) {
  const World& w = world();
  intersections::IntersectionOptions o;
  o.end_tolerance_m = -1.0;
  EXPECT_THROW(mapping::MapAssembler(*w.sk, o), intersections::IntersectionsError);
}

}  // namespace
