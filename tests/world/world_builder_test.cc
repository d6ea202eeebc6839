// The simulator's world built from west-oakland.osm: lane counts follow the OSM tags, lane widths,
// shared boundaries, successor continuity, what sample() and height() return, obstacles, and
// determinism for a seed.
#include "core/geo/polyline.h"
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <thread>

namespace lanemap::sim {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using map::Lanelet;
using map::LaneletKind;
using map::LineType;

const std::string kOsm = std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm";

const skeleton::Skeleton& oakland() {
  static const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(kOsm));
  return sk;
}

WorldOptions optionsWithSeed(uint64_t seed, bool flat = false) {
  WorldOptions o;
  o.seed = seed;
  o.flat = flat;
  return o;
}

const SimWorld& world() {
  static const std::unique_ptr<SimWorld> w = buildWorld(oakland(), optionsWithSeed(3));
  return *w;
}

double distToPolyline(const Vector2d& q, const std::vector<Vector3d>& p) {
  double best = 1e300;
  for (size_t i = 1; i < p.size(); ++i) {
    const Vector2d a = p[i - 1].head<2>(), b = p[i].head<2>();
    const Vector2d ab = b - a;
    const double u = ab.squaredNorm() > 0 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (a + u * ab - q).norm());
  }
  return best;
}

Vector2d pointAtLength(const std::vector<Vector3d>& p, double s) {
  for (size_t i = 1; i < p.size(); ++i) {
    const double l = (p[i] - p[i - 1]).head<2>().norm();
    if (s <= l && l > 0) return p[i - 1].head<2>() + (s / l) * (p[i] - p[i - 1]).head<2>();
    s -= l;
  }
  return p.back().head<2>();
}

Vector2d tangentAtLength(const std::vector<Vector3d>& p, double s) {
  for (size_t i = 1; i < p.size(); ++i) {
    const double l = (p[i] - p[i - 1]).head<2>().norm();
    if (s <= l && l > 0) return (p[i] - p[i - 1]).head<2>() / l;
    s -= l;
  }
  return (p.back() - p[p.size() - 2]).head<2>().normalized();
}

// A pocket lanelet opens with zero width; everything else starts full width.
bool isPocket(const SimWorld& w, const Lanelet& l) {
  const auto* lb = w.line(l.left_id);
  const auto* rb = w.line(l.right_id);
  auto startOf = [&](const map::LineString* ls) {
    const Vector2d a = ls->points.front().head<2>(), b = ls->points.back().head<2>();
    const Vector2d c = l.centre.front().head<2>();
    return (a - c).norm() < (b - c).norm() ? a : b;
  };
  return l.kind == LaneletKind::kRoad && (startOf(lb) - startOf(rb)).norm() < 0.05;
}

// Road lanelets of one atomic road that start its first section (their predecessors, if any, are
// intersection lanelets): one per lane of the road.
int lanesOfRoad(const SimWorld& w, int64_t road_id) {
  int n = 0;
  for (const auto& l : w.truth().lanelets) {
    if (l.kind != LaneletKind::kRoad || l.road_id != road_id) continue;
    bool from_same_road = false;
    for (int64_t p : w.predecessors(l.id)) {
      const Lanelet* pl = w.lanelet(p);
      if (pl && pl->kind == LaneletKind::kRoad && pl->road_id == road_id) from_same_road = true;
    }
    if (!from_same_road) ++n;
  }
  return n;
}

TEST(LaneCounts, FollowTagsAndClassDefaults) {
  EXPECT_EQ(laneCountsFor({{"highway", "residential"}}, false).forward, 1);
  EXPECT_EQ(laneCountsFor({{"highway", "residential"}}, false).backward, 1);
  EXPECT_EQ(laneCountsFor({{"highway", "primary"}}, false).forward, 2);
  EXPECT_EQ(laneCountsFor({{"highway", "motorway"}}, true).forward, 2);
  EXPECT_EQ(laneCountsFor({{"highway", "motorway"}}, true).backward, 0);
  // Odd `lanes` on a two-way road: the extra lane goes forward.
  const LaneCounts odd = laneCountsFor({{"highway", "secondary"}, {"lanes", "3"}}, false);
  EXPECT_EQ(odd.forward, 2);
  EXPECT_EQ(odd.backward, 1);
  const LaneCounts fb = laneCountsFor({{"highway", "primary"}, {"lanes", "5"}, {"lanes:backward", "2"}}, false);
  EXPECT_EQ(fb.forward, 3);
  EXPECT_EQ(fb.backward, 2);
  // turn:lanes entries are the lanes when `lanes` is absent.
  EXPECT_EQ(laneCountsFor({{"highway", "tertiary"}, {"turn:lanes", "left|through|right"}}, true).forward, 3);
  EXPECT_EQ(laneCountsFor({{"highway", "tertiary"}, {"turn:lanes:forward", "left|"}}, false).forward, 2);
  EXPECT_EQ(laneCountsFor({{"highway", "residential"}, {"lanes", "1"}}, false).backward, 1);
}

TEST(WorldOptions, FromYamlReadsTheConfigAndRejectsBadValues) {
  const WorldOptions o = WorldOptions::fromYamlFile(std::string(LANEMAP_DATA_DIR) + "/../config/sim_world.yaml");
  EXPECT_DOUBLE_EQ(o.lane_width_min_m, 2.8);
  EXPECT_DOUBLE_EQ(o.lane_width_max_m, 3.7);
  EXPECT_DOUBLE_EQ(o.crown_slope, 0.02);
  EXPECT_TRUE(o.right_hand_traffic);
  EXPECT_THROW(WorldOptions::fromYaml(YAML::Load("irregularities: {bus_bay: 1.5}")), WorldConfigError);
  EXPECT_THROW(WorldOptions::fromYaml(YAML::Load("surface: {max_grade: 0.2}")), WorldConfigError);
  EXPECT_THROW(WorldOptions::fromYaml(YAML::Load("lanes: {widht_min_m: 3}")), WorldConfigError);
  EXPECT_THROW(WorldOptions::fromYamlFile("/nonexistent/world.yaml"), WorldConfigError);
  EXPECT_EQ(WorldOptions::fromYaml(YAML::Node()).seed, WorldOptions().seed);
}

TEST(World, LaneCountsFollowTheOsmTagsOnWestOakland) {
  const SimWorld& w = world();
  // way id -> expected lanes per direction (forward, backward; backward -1 = one-way).
  const std::map<int64_t, std::pair<int, int>> expected = {
      {202455451, {2, -1}},  // 7th Street, lanes=2, oneway
      {393667837, {3, -1}},  // lanes=3, oneway, turn:lanes=left||
      {417704456, {3, -1}},  // lanes=3, oneway, turn:lanes=left|left;through|
      {202455449, {2, -1}},  // secondary, oneway, no lanes tag: class default 2
      {6340506, {1, 1}},     // Campbell Street, residential two-way: 1 + 1
      {162921793, {1, 1}},   // Willow Street, residential two-way
      {52538632, {1, -1}},   // service, oneway
  };
  for (const auto& [way, lanes] : expected) {
    int roads = 0;
    for (const auto& r : oakland().roads()) {
      if (r.way_id != way) continue;
      ++roads;
      EXPECT_EQ(r.reverse_id >= 0, lanes.second >= 0) << "way " << way;
      const int want = r.reverse_id < 0 ? lanes.first : (r.along_way ? lanes.first : lanes.second);
      EXPECT_EQ(lanesOfRoad(w, r.id), want) << "way " << way << " road " << r.id;
    }
    EXPECT_GT(roads, 0) << "way " << way << " is not in the skeleton";
  }
}

TEST(World, LaneWidthsAreWithinLimits) {
  const SimWorld& w = world();
  int checked = 0;
  for (const auto& l : w.truth().lanelets) {
    if (l.kind != LaneletKind::kRoad) continue;
    // The middle sample of the centre is a sample of both bounds (same station), so the width
    // there is exact up to rounding: 1 cm tolerance.
    const Vector2d c = l.centre[l.centre.size() / 2].head<2>();
    const double width = distToPolyline(c, w.line(l.left_id)->points) + distToPolyline(c, w.line(l.right_id)->points);
    EXPECT_GE(width, 2.8 - 0.01) << "lanelet " << l.id;
    EXPECT_LE(width, 3.7 + 0.01) << "lanelet " << l.id;
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

TEST(World, IdsArePositiveAndUnique) {
  const SimWorld& w = world();
  std::set<int64_t> ids;
  for (const auto& l : w.truth().lines) {
    EXPECT_GT(l.id, 0);
    EXPECT_TRUE(ids.insert(l.id).second) << l.id;
  }
  for (const auto& l : w.truth().lanelets) {
    EXPECT_GT(l.id, 0);
    EXPECT_TRUE(ids.insert(l.id).second) << l.id;
    EXPECT_NE(w.line(l.left_id), nullptr);
    EXPECT_NE(w.line(l.right_id), nullptr);
    for (int64_t s : l.successors) EXPECT_NE(w.lanelet(s), nullptr);
    if (l.stop_line_id) {
      EXPECT_EQ(w.line(*l.stop_line_id)->type, LineType::kStopLine);
    }
    if (l.kind == LaneletKind::kRoad) {
      EXPECT_NE(oakland().road(l.road_id), nullptr);
      EXPECT_EQ(oakland().road(l.road_id)->from, l.from_node);
      EXPECT_EQ(oakland().road(l.road_id)->to, l.to_node);
      EXPECT_GE(l.index_from_left, 0);
    } else {
      EXPECT_NE(oakland().intersection(l.intersection_id), nullptr);
      EXPECT_EQ(w.line(l.left_id)->type, LineType::kVirtual);
      EXPECT_NE(l.turn, map::TurnDirection::kNone);
    }
  }
}

TEST(World, AdjacentLanesShareTheirBoundary) {
  const SimWorld& w = world();
  int same_dir = 0, centre_lines = 0;
  for (const auto& a : w.truth().lanelets) {
    if (a.kind != LaneletKind::kRoad) continue;
    for (const auto& b : w.truth().lanelets) {
      if (b.kind != LaneletKind::kRoad || &a == &b) continue;
      const bool same_start = (a.centre.front() - b.centre.front()).head<2>().norm() < 8.0 &&
                              (a.centre.back() - b.centre.back()).head<2>().norm() < 8.0;
      const bool opposite = (a.centre.front() - b.centre.back()).head<2>().norm() < 8.0 &&
                            (a.centre.back() - b.centre.front()).head<2>().norm() < 8.0;
      if (b.road_id == a.road_id && b.index_from_left == a.index_from_left + 1 && same_start) {
        EXPECT_EQ(a.right_id, b.left_id) << a.id << " | " << b.id;
        ++same_dir;
      }
      const auto* ra = oakland().road(a.road_id);
      if (ra && ra->reverse_id == b.road_id && a.index_from_left == 0 && b.index_from_left == 0 && opposite) {
        EXPECT_EQ(a.left_id, b.left_id) << "centre line of " << a.id << " and " << b.id;
        const auto t = w.line(a.left_id)->type;
        EXPECT_TRUE(t == LineType::kSolid || t == LineType::kSolidSolid);
        ++centre_lines;
      }
    }
  }
  EXPECT_GT(same_dir, 5);
  EXPECT_GT(centre_lines, 10);
}

TEST(World, SuccessorsJoinWithoutGaps) {
  const SimWorld& w = world();
  int joints = 0, pockets = 0, splits = 0;
  for (const auto& l : w.truth().lanelets) {
    int road_successors = 0;
    for (int64_t sid : l.successors) {
      const Lanelet& s = *w.lanelet(sid);
      road_successors += s.kind == LaneletKind::kRoad ? 1 : 0;
      const double gap = (l.centre.back() - s.centre.front()).head<2>().norm();
      if (isPocket(w, s)) {
        // A pocket opens at zero width on the predecessor's end cross line (< 1 cm).
        const auto* lb = w.line(l.left_id);
        const auto* rb = w.line(l.right_id);
        const Vector2d e = l.centre.back().head<2>();
        auto endOf = [&](const map::LineString* ls) {
          const Vector2d a = ls->points.front().head<2>(), b = ls->points.back().head<2>();
          return (a - e).norm() < (b - e).norm() ? a : b;
        };
        const Vector2d p = s.centre.front().head<2>(), a = endOf(lb), b = endOf(rb);
        const double u = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
        EXPECT_LT((a + u * (b - a) - p).norm(), 0.01) << l.id << " -> pocket " << s.id;
        ++pockets;
      } else {
        EXPECT_LT(gap, 0.01) << l.id << " -> " << s.id;
        ++joints;
      }
    }
    if (road_successors >= 2) {
      ++splits;
      // No lanelet may both diverge and merge.
      EXPECT_LE(w.predecessors(l.id).size(), 1u) << "lanelet " << l.id << " splits and merges";
    }
  }
  EXPECT_GT(joints, 100);
  EXPECT_EQ(pockets, splits);
  EXPECT_EQ(static_cast<size_t>(pockets), w.stats().turn_pockets);
  EXPECT_GT(pockets, 0) << "no turn pocket with this seed";
}

TEST(World, EveryIncomingLaneContinuesThroughItsIntersection) {
  const SimWorld& w = world();
  int turns[4] = {0, 0, 0, 0};
  for (const auto& l : w.truth().lanelets) {
    if (l.kind == LaneletKind::kIntersection) {
      ++turns[static_cast<int>(l.turn)];
      ASSERT_EQ(l.successors.size(), 1u);
      const Lanelet& out = *w.lanelet(l.successors[0]);
      // No U-turn: the outgoing road is not the reverse of the incoming one.
      for (int64_t p : w.predecessors(l.id)) {
        const auto* in_road = oakland().road(w.lanelet(p)->road_id);
        EXPECT_NE(in_road->reverse_id, out.road_id);
      }
      continue;
    }
    const auto* road = oakland().road(l.road_id);
    const auto* to = oakland().intersection(road->to);
    if (l.to_node >= 0 && !to->dead_end && l.successors.empty()) {
      // Only roads whose far end offers no way on (other than turning back) may end.
      size_t ways_on = 0;
      for (int64_t o : to->outgoing) ways_on += o != road->reverse_id ? 1 : 0;
      EXPECT_EQ(ways_on, 0u) << "lanelet " << l.id << " stops at intersection " << to->id;
    }
  }
  EXPECT_GT(turns[static_cast<int>(map::TurnDirection::kStraight)], 10);
  EXPECT_GT(turns[static_cast<int>(map::TurnDirection::kLeft)], 10);
  EXPECT_GT(turns[static_cast<int>(map::TurnDirection::kRight)], 10);
}

TEST(World, SampleAtALaneCentreIsThatLanelet) {
  const SimWorld& w = world();
  int ok = 0, n = 0;
  for (const auto& l : w.truth().lanelets) {
    if (l.kind != LaneletKind::kRoad || geo::polylineLengthXy(l.centre) < 8.0) continue;
    const Vector2d c = pointAtLength(l.centre, geo::polylineLengthXy(l.centre) / 2.0);
    const GroundSample g = w.sample(c.x(), c.y());
    ++n;
    if (g.lanelet == l.id && g.surface == Surface::kAsphalt) ++ok;
    const map::Lanelet* at = w.laneletAt(c.x(), c.y());
    if (at) {
      EXPECT_EQ(at->id, g.lanelet);
    }
  }
  std::printf("lane centre samples: %d of %d in their own lanelet on asphalt\n", ok, n);
  // Where two OSM ways run closer than their widths, one road's lanes cover the other's; allow 2 %.
  EXPECT_GT(n, 50);
  EXPECT_GE(ok, 0.98 * n) << ok << " of " << n;
}

TEST(World, SampleOnABoundaryIsItsPaintUnlessWornOrMissing) {
  const SimWorld& w = world();
  std::map<int64_t, std::vector<MarkingGap>> gaps;
  for (const auto& g : w.markingGaps()) gaps[g.line_id].push_back(g);
  int painted = 0, bare = 0, n = 0, wrong = 0;
  for (const auto& ls : w.truth().lines) {
    if (ls.type != LineType::kSolid && ls.type != LineType::kDashed && ls.type != LineType::kSolidSolid) continue;
    const double L = geo::polylineLengthXy(ls.points);
    if (L < 20.0) continue;
    // Mid-dash station near the middle (dashes: [k*9, k*9+3]), away from crosswalks at the ends.
    const double s = std::floor(L / 2.0 / kDashPeriod) * kDashPeriod + kDashLength / 2.0;
    int state = 0;  // 0 paint, 1 faded, 2 missing
    for (const auto& g : gaps[ls.id]) {
      if (s >= g.s0 - 0.2 && s <= g.s1 + 0.2) state = g.missing ? 2 : 1;
    }
    const Vector2d t = tangentAtLength(ls.points, s);
    const Vector2d nrm(-t.y(), t.x());
    const double off = ls.type == LineType::kSolidSolid ? kDoubleLineOffset : 0.0;
    const Vector2d p = pointAtLength(ls.points, s) + off * nrm;
    const Surface want = ls.type == LineType::kDashed ? Surface::kDashedPaint : Surface::kSolidPaint;
    const GroundSample g = w.sample(p.x(), p.y());
    ++n;
    if (state == 0) {
      if (g.surface == want) ++painted;
      else ++wrong;
    } else if (state == 2) {
      if (g.surface == Surface::kAsphalt) ++bare;
      else ++wrong;
    } else if (g.surface != want && g.surface != Surface::kAsphalt) {
      ++wrong;
    }
  }
  EXPECT_GT(n, 30);
  EXPECT_GT(painted, 20);
  EXPECT_LE(wrong, 0.03 * n) << wrong << " of " << n;  // other roads' paint may cross a few
  EXPECT_GT(w.stats().missing + w.stats().faded, 0u);
}

TEST(World, StopLinesAndCrosswalksArePainted) {
  const SimWorld& w = world();
  int stop = 0, hit = 0;
  for (const auto& ls : w.truth().lines) {
    if (ls.type != LineType::kStopLine) continue;
    ++stop;
    const Vector2d mid = (ls.points.front() + ls.points.back()).head<2>() / 2.0;
    if (w.sample(mid.x(), mid.y()).surface == Surface::kStopLinePaint) ++hit;
  }
  EXPECT_GT(stop, 3);
  EXPECT_GE(hit, stop - 1);
  EXPECT_GT(w.stats().crosswalks, 2u);
}

TEST(World, CrownDropsTwoPercentFromTheCentreLine) {
  const SimWorld& w = world();
  int checked = 0;
  for (const auto& a : w.truth().lanelets) {
    if (a.kind != LaneletKind::kRoad || a.index_from_left != 0 || a.centre.size() < 30) continue;
    const auto* road = oakland().road(a.road_id);
    if (!road || road->reverse_id < 0) continue;
    // The right-most lanelet of the same section: same road, starting where `a` starts.
    const Lanelet* edge = nullptr;
    for (const auto& b : w.truth().lanelets) {
      if (b.road_id == a.road_id && (b.centre.front() - a.centre.front()).head<2>().norm() < 8.0 &&
          (!edge || b.index_from_left > edge->index_from_left)) {
        edge = &b;
      }
    }
    const auto& centre_line = w.line(a.left_id)->points;
    const auto& edge_line = w.line(edge->right_id)->points;
    const size_t i = centre_line.size() / 2;
    const Vector2d pc = centre_line[i].head<2>();
    Vector2d pe = edge_line[0].head<2>();
    for (const auto& q : edge_line) {
      if ((q.head<2>() - pc).norm() < (pe - pc).norm()) pe = q.head<2>();
    }
    const Vector2d q = pe + 0.3 * (pc - pe).normalized();  // just inside the curb
    const double d = (q - pc).norm();
    const double drop = (w.height(pc.x(), pc.y()) - w.terrainHeight(pc.x(), pc.y())) -
                        (w.height(q.x(), q.y()) - w.terrainHeight(q.x(), q.y()));
    // Bilinear interpolation of the 0.25 m height grid rounds the crown's peak by <= 2.5 mm.
    EXPECT_NEAR(drop, 0.02 * d, 0.005 + 0.05 * 0.02 * d) << "lanelet " << a.id << " offset " << d;
    ++checked;
  }
  EXPECT_GT(checked, 5);
}

TEST(World, FlatWorldHasZeroHeight) {
  const auto flat = buildWorld(oakland(), optionsWithSeed(3, true));
  for (const auto& l : flat->truth().lanelets) {
    for (const auto& p : l.centre) {
      ASSERT_EQ(p.z(), 0.0);
      ASSERT_EQ(flat->height(p.x(), p.y()), 0.0);
    }
  }
  EXPECT_EQ(flat->height(12.3, -45.6), 0.0);
}

TEST(World, GradesStayBelowTenPercent) {
  const SimWorld& w = world();
  double worst = 0.0, range_lo = 1e9, range_hi = -1e9;
  for (const auto& l : w.truth().lanelets) {
    const double L = geo::polylineLengthXy(l.centre);
    for (double s = 0.0; s + 5.0 <= L; s += 2.5) {
      const Vector2d a = pointAtLength(l.centre, s), b = pointAtLength(l.centre, s + 5.0);
      const double run = (b - a).norm();
      if (run < 4.0) continue;
      const double ha = w.height(a.x(), a.y()), hb = w.height(b.x(), b.y());
      worst = std::max(worst, std::abs(hb - ha) / run);
      range_lo = std::min(range_lo, ha);
      range_hi = std::max(range_hi, ha);
    }
  }
  std::printf("steepest 5 m grade %.3f, heights %.2f .. %.2f m\n", worst, range_lo, range_hi);
  EXPECT_LE(worst, 0.10);
  EXPECT_GT(range_hi - range_lo, 1.0);  // it is not flat
}

TEST(World, ObstaclesNeverOverlapADrivingLane) {
  const SimWorld& w = world();
  EXPECT_GT(w.stats().parked_cars, 5u);
  EXPECT_GT(w.stats().buildings, 10u);
  struct Poly {
    std::vector<Vector2d> p;
    Eigen::AlignedBox2d box;
  };
  std::vector<Poly> lanes;
  for (const auto& l : w.truth().lanelets) {
    Poly poly;
    for (const auto& q : w.line(l.left_id)->points) poly.p.push_back(q.head<2>());
    auto right = w.line(l.right_id)->points;
    // Walk the right bound back from the end where the left bound stops.
    if ((right.front() - w.line(l.left_id)->points.back()).head<2>().norm() <
        (right.back() - w.line(l.left_id)->points.back()).head<2>().norm()) {
      // already starts there
    } else {
      std::reverse(right.begin(), right.end());
    }
    for (const auto& q : right) poly.p.push_back(q.head<2>());
    for (const auto& q : poly.p) poly.box.extend(q);
    lanes.push_back(poly);
  }
  auto inside = [](const Vector2d& p, const std::vector<Vector2d>& poly) {
    bool in = false;
    for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
      if ((poly[i].y() > p.y()) != (poly[j].y() > p.y()) &&
          p.x() < poly[i].x() + (p.y() - poly[i].y()) * (poly[j].x() - poly[i].x()) / (poly[j].y() - poly[i].y())) {
        in = !in;
      }
    }
    return in;
  };
  for (const auto& o : w.obstacles()) {
    const Vector2d ax(std::cos(o.yaw), std::sin(o.yaw)), ay(-ax.y(), ax.x());
    Eigen::AlignedBox2d box;
    for (int sx = -1; sx <= 1; sx += 2) {
      for (int sy = -1; sy <= 1; sy += 2) box.extend(o.centre.head<2>() + sx * o.half_extent.x() * ax + sy * o.half_extent.y() * ay);
    }
    std::vector<const Poly*> near;
    for (const auto& lane : lanes) {
      if (lane.box.intersects(box)) near.push_back(&lane);
    }
    // Footprint sampled every 0.25 m for cars, 0.5 m for buildings (lanes are >= 2.8 m wide, so a
    // lane cannot hide between samples).
    const double step = o.kind == Obstacle::Kind::kParkedCar ? 0.25 : 0.5;
    for (double u = -o.half_extent.x(); u <= o.half_extent.x() + 1e-9; u += step) {
      for (double v = -o.half_extent.y(); v <= o.half_extent.y() + 1e-9; v += step) {
        const Vector2d p = o.centre.head<2>() + u * ax + v * ay;
        for (const Poly* lane : near) {
          if (!lane->box.contains(p)) continue;
          ASSERT_FALSE(inside(p, lane->p)) << "obstacle at " << o.centre.transpose() << " on a lane";
        }
        const Surface s = w.sample(p.x(), p.y()).surface;
        ASSERT_NE(s, Surface::kAsphalt);
      }
    }
  }
  // obstaclesNear finds each obstacle from its own centre.
  for (const auto& o : w.obstacles()) {
    std::vector<const Obstacle*> near;
    w.obstaclesNear(o.centre.head<2>(), 1.0, &near);
    EXPECT_NE(std::find(near.begin(), near.end(), &o), near.end());
  }
}

TEST(World, LaneOffsetCountsLanesLeftToRight) {
  const SimWorld& w = world();
  int same = 0, opposite = 0;
  for (const auto& a : w.truth().lanelets) {
    if (a.kind != LaneletKind::kRoad) continue;
    EXPECT_EQ(w.laneOffset(a.id, a.id), 0);
    for (const auto& b : w.truth().lanelets) {
      if (b.kind != LaneletKind::kRoad || b.id == a.id) continue;
      const bool same_start = (a.centre.front() - b.centre.front()).head<2>().norm() < 8.0;
      if (b.road_id == a.road_id && same_start) {
        EXPECT_EQ(w.laneOffset(a.id, b.id), b.index_from_left - a.index_from_left);
        ++same;
      }
      const auto* ra = oakland().road(a.road_id);
      if (ra->reverse_id == b.road_id && a.index_from_left == 0 && b.index_from_left == 0) {
        const auto off = w.laneOffset(a.id, b.id);
        ASSERT_TRUE(off.has_value());
        EXPECT_EQ(*off, -1);  // right-hand traffic: the oncoming lane is on the left
        ++opposite;
      }
      const auto* rb = oakland().road(b.road_id);
      if (b.road_id != a.road_id && ra->reverse_id != b.road_id && rb) {
        EXPECT_FALSE(w.laneOffset(a.id, b.id));
      }
    }
  }
  EXPECT_GT(same, 5);
  EXPECT_GT(opposite, 10);
  EXPECT_FALSE(w.laneOffset(-5, -6));
}

TEST(World, SameSeedSameWorldOtherSeedOtherWorld) {
  const auto a = buildWorld(oakland(), optionsWithSeed(11));
  const auto b = buildWorld(oakland(), optionsWithSeed(11));
  const auto c = buildWorld(oakland(), optionsWithSeed(12));
  ASSERT_EQ(a->truth().lanelets.size(), b->truth().lanelets.size());
  ASSERT_EQ(a->truth().lines.size(), b->truth().lines.size());
  for (size_t i = 0; i < a->truth().lines.size(); ++i) {
    ASSERT_EQ(a->truth().lines[i].id, b->truth().lines[i].id);
    ASSERT_EQ(a->truth().lines[i].points, b->truth().lines[i].points);
  }
  for (size_t i = 0; i < a->truth().lanelets.size(); ++i) {
    ASSERT_EQ(a->truth().lanelets[i].successors, b->truth().lanelets[i].successors);
  }
  ASSERT_EQ(a->obstacles().size(), b->obstacles().size());
  for (size_t i = 0; i < a->obstacles().size(); ++i) ASSERT_EQ(a->obstacles()[i].centre, b->obstacles()[i].centre);
  const Vector2d p = a->truth().lanelets[0].centre[0].head<2>();
  EXPECT_EQ(a->height(p.x(), p.y()), b->height(p.x(), p.y()));
  const bool differs = a->truth().lines.size() != c->truth().lines.size() ||
                       a->obstacles().size() != c->obstacles().size() ||
                       a->height(p.x(), p.y()) != c->height(p.x(), p.y());
  EXPECT_TRUE(differs);
}

TEST(World, TileCacheStaysBoundedAndIsThreadSafe) {
  WorldOptions o = optionsWithSeed(3);
  o.tile_cache_size = 4;
  const auto w = buildWorld(oakland(), o);
  // Reference answers from one thread.
  // Lane points in a 3 x 3 block of 64 m tiles around the origin (more tiles than the cache
  // holds), visited tile by tile as a renderer would.
  std::vector<Vector2d> pts;
  for (const auto& l : w->truth().lanelets) {
    for (size_t i = 0; i < l.centre.size(); i += 2) {
      const Vector2d p = l.centre[i].head<2>();
      if (std::abs(p.x()) < 96.0 && std::abs(p.y()) < 96.0) pts.push_back(p);
    }
  }
  auto tileOf = [](const Vector2d& p) {
    return std::make_pair(std::floor(p.x() / 64.0), std::floor(p.y() / 64.0));
  };
  std::sort(pts.begin(), pts.end(), [&](const Vector2d& a, const Vector2d& b) { return tileOf(a) < tileOf(b); });
  ASSERT_GT(pts.size(), 100u);
  std::vector<GroundSample> want;
  std::vector<double> want_h;
  for (const auto& p : pts) {
    want.push_back(w->sample(p.x(), p.y()));
    want_h.push_back(w->height(p.x(), p.y()));
  }
  EXPECT_LE(w->cachedTiles(), 4u);
  std::vector<std::thread> threads;
  std::vector<int> mismatches(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int rep = 0; rep < 1; ++rep) {
        for (size_t i = 0; i < pts.size(); ++i) {
          const size_t j = (i + t * pts.size() / 4) % pts.size();  // coherent walks, different starts
          const GroundSample g = w->sample(pts[j].x(), pts[j].y());
          if (g.lanelet != want[j].lanelet || g.surface != want[j].surface ||
              w->height(pts[j].x(), pts[j].y()) != want_h[j]) {
            ++mismatches[t];
          }
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int m : mismatches) EXPECT_EQ(m, 0);
  EXPECT_LE(w->cachedTiles(), 4u);
}

TEST(World, LeftHandTrafficMirrorsTheLayout) {
  WorldOptions o = optionsWithSeed(3);
  o.right_hand_traffic = false;
  const auto w = buildWorld(oakland(), o);
  int checked = 0;
  for (const auto& l : w->truth().lanelets) {
    if (l.kind != LaneletKind::kRoad || l.centre.size() < 4) continue;
    const auto* road = oakland().road(l.road_id);
    if (road->reverse_id < 0) continue;
    // The lane lies left of its road's OSM polyline (driving direction).
    const Vector2d c = l.centre[l.centre.size() / 2].head<2>();
    double best = 1e300;
    Vector2d side = Vector2d::Zero();
    for (size_t i = 1; i < road->polyline.size(); ++i) {
      const Vector2d a = road->polyline[i - 1], b = road->polyline[i];
      const double u = std::clamp((c - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      const double d = (a + u * (b - a) - c).norm();
      if (d < best) {
        best = d;
        side = b - a;
        side = Vector2d(side.x() * (c - a).y() - side.y() * (c - a).x(), 0.0);
      }
    }
    EXPECT_GT(side.x(), 0.0) << "lanelet " << l.id;
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

}  // namespace
}  // namespace lanemap::sim
