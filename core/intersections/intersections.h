// Intersections (METHOD.md section 5, Algorithm 2): which lane of an incoming road connects to which
// lane of an outgoing road, and the reference trajectory of every connection as a Lanelet2
// intersection lanelet (kind kIntersection, turn_direction, virtual bounds) that shares its end
// points with the road lanelets it joins.
//
// Topology. For every incoming road E_in and outgoing road E_out of the intersection:
// - the movement is the heading change between the roads (straight below straight_max_deg, else
//   left/right); U-turns (E_out is E_in's reverse, or a heading change beyond uturn_min_deg: onto
//   the other carriageway of a dual carriageway) are skipped unless allowed; OSM turn
//   restrictions (no_* / only_*, via the intersection's node) remove movements;
// - straight: the lanes that may go straight pair k -> k counted from the inner side (the left in
//   right-hand traffic: METHOD.md's "left lanes to left lanes", k = 1..min(N_in, N_out));
// - left turns from the left-most lane (the lanes tagged left in turn:lanes, several when tagged)
//   into the out road's left-most lanes; right turns from the right-most into the right-most;
// - `turn:lanes` (`:forward`/`:backward` on two-way ways) of the incoming road says which lanes may
//   do what, when its count matches the lanes found (turn pockets found in the lanes, which OSM
//   does not list, are set aside first); a turn pocket with no tag is a turn lane (inner side:
//   the turn across traffic, outer side: the other);
// - where the car drove from the in road to the out road (passages: driven_passage.h), the lanes
//   it drove correct the rules of that road pair: the rules' pairs shift by the difference between
//   the driven out lane and the one the rules give the driven in lane (where they give it none but
//   pair another in lane with the driven out lane, their in lanes shift by that difference:
//   passage.shift_in_lanes), and the driven pair is one (passage.pairs);
// - a lane left with no connection continues into the straightest allowed way out (a lane drop
//   merges rather than ending in the middle of the intersection), when every way out of the
//   intersection is in the map (otherwise it may be headed for a road the drive did not map).
// Geometry: quadratic Bezier P0 -> P2 with P the tangents' intersection, cubic fallback (curve.h);
// bounds: each its own connection curve from the incoming lane's bound end to the outgoing lane's
// bound start (connectorBounds in curve.h), so end points are exactly the road lanelets' bound end
// points (successors share end points, as Lanelet2 requires); typed virtual. Where the car drove
// from the in road to the out road (passages: driven_passage.h), every connection of that road
// pair, centre and bounds, is moved by the displacement of the car's path from the Bezier of the
// lanes it drove (ends unchanged); a shaped lanelet that would not be sound (its outline not
// simple, its centre leaving it) keeps the Bezier.
#pragma once

#include "core/intersections/curve.h"
#include "core/intersections/driven_passage.h"
#include "core/map/lane_map.h"
#include "core/osm/osm_data.h"
#include "core/osm/turn_lanes.h"
#include "core/skeleton/skeleton.h"

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace lanemap::config { class YamlReader; }

namespace lanemap::intersections {

class IntersectionsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct IntersectionOptions {
  bool right_hand_traffic = true;  // false: left-hand traffic (inner side = right)
  bool allow_u_turns = false;      // a U-turn movement also needs lanes on both roads
  bool use_turn_lanes = true;      // honour turn:lanes tags
  bool use_restrictions = true;    // honour turn restriction relations
  bool pockets_are_turn_lanes = true;
  bool connect_orphan_lanes = true;
  double straight_max_deg = 40.0;  // |heading change| below this is straight
  double uturn_min_deg = 150.0;    // |heading change| above this is a U-turn
  // A lanelet with no successor on its road ends at the intersection when its end projects within
  // this of the road's s_end (for outgoing roads: starts within this of s_begin).
  double end_tolerance_m = 12.0;
  // A road whose mapped lanes all end (start) farther than end_tolerance_m from the intersection,
  // up to this far, still connects from its last (first) lanes: the drive did not see that part.
  double unseen_end_m = 30.0;
  double lane_tangent_m = 3.0;     // a lane's end direction over its last (first) metres
  double road_tangent_m = 15.0;    // a road's direction over this much past its ROI edge
  double pocket_min_m = 10.0;      // a lane that starts this far after its road's first lane (and into the road) is a pocket
  // Straight on, with different numbers of lanes mapped on the two roads and no turn:lanes: lanes
  // pair by their offsets from the roads' lines, within this (0: always k -> k from the left).
  double offset_match_m = 1.5;
  CurveOptions curve;
  PassageOptions passage;  // the car's paths through the intersection (passage_max_offset_m)
  // Ids of the fragment: id_base + 1, + 2, ... ; 0 = kIdBase + 100000 * (index of the
  // intersection in skeleton.intersections()), clear of core/lanes' (road_id + 1) * 100000 + k.
  int64_t id_base = 0;

  static IntersectionOptions fromYaml(const YAML::Node& node);  // throws IntersectionsError
  // From a config (config/intersections.yaml; strict: the caller's finish() refuses other keys);
  // throws config::ConfigError naming the file and key.
  static IntersectionOptions fromYaml(const config::YamlReader& r);
  void validate() const;                                         // throws IntersectionsError
};

inline constexpr int64_t kIdBase = 1000000000000;  // 1e12

// turn:lanes of one lane (OSM `turn:lanes` entry, e.g. "left;through").
using Movements = osm::LaneMovements;  // one lane's turn:lanes entry (core/osm/turn_lanes.h)
using osm::parseTurnLane;
// The turn:lanes entries of a road in its driving direction, left to right; empty when untagged.
std::vector<Movements> turnLanes(const skeleton::AtomicRoad& road);

// The lane pairing rules (METHOD.md section 5) of one movement: (in lane, out lane) index pairs,
// both counted from the left, from an approach whose lanes allow `in_lanes` (left to right, from
// turn:lanes; unspecified where untagged) to a road with n_out lanes. Straight: the lanes that may
// go straight, aligned at the kerb-far side (the left in right-hand traffic); a turn: the lanes
// tagged for it, else the edge lane on its side unless that one is tagged otherwise, aligned on
// the turn's side (a double left turn fills the two leftmost out lanes); a U-turn: one lane (tagged
// reverse, else the innermost) into the innermost out lane. Extra lanes on either side stay
// unpaired. The lane mapper's assumption, not the simulator's truth (core/sim has its own rules).
std::vector<std::pair<int, int>> pairLanes(const std::vector<Movements>& in_lanes, int n_out, map::TurnDirection movement,
                                           bool uturn, bool right_hand_traffic);

struct Connection {
  int64_t lanelet_id = -1;              // the intersection lanelet
  int64_t in_road = -1, out_road = -1;
  int64_t in_lanelet = -1, out_lanelet = -1;  // road lanelets it joins
  int in_index = -1, out_index = -1;    // lane index from the left at the road's end / start
  map::TurnDirection movement = map::TurnDirection::kNone;  // of the road pair
  map::TurnDirection turn = map::TurnDirection::kNone;      // the lanelet's own heading change
  bool quadratic = false;               // false: cubic fallback
  bool orphan = false;                  // added by connect_orphan_lanes
  int passages = 0;                     // driven passages that shaped it (0: the Bezier)
};

struct IntersectionResult {
  int64_t intersection_id = -1;
  map::LaneMap map;  // the intersection lanelets and their bounds (origin of the road maps)
  std::vector<Connection> connections;
  // Pairs the topology asked for whose lanelet Lanelet2 would misread (sharp connections between
  // overlapping lane ends): not in `map` nor in `connections`.
  struct NotBuilt {
    int64_t in_road = -1;
    int in_index = -1;
    int64_t out_road = -1;
    int out_index = -1;
  };
  std::vector<NotBuilt> not_built;
};

// One intersection. `roads`: road id -> that road's lanes (map::LaneMap as core/lanes'
// toLaneMap makes it, or a map's road lanelets grouped with roadsOf); roads absent from it, or
// with no lanelet reaching the intersection, take no part. `restrictions`: the OSM file's turn
// restrictions (osm::OsmData::restrictions; the skeleton does not keep them). `passages`: the car's
// paths through intersections (those of other intersections are ignored). Deterministic.
// Throws IntersectionsError for an unknown intersection id or bad options.
IntersectionResult buildIntersection(const skeleton::Skeleton& skeleton, int64_t intersection_id,
                                     const std::map<int64_t, map::LaneMap>& roads,
                                     const IntersectionOptions& options = {},
                                     const std::vector<osm::Restriction>& restrictions = {},
                                     const std::vector<DrivenPassage>& passages = {});

// The intersection at skeleton.intersections()[index] as buildIntersections builds it (ids from
// its own base): nullopt when it has no incoming or no outgoing road in `roads`, or when it
// connects nothing. Throws as buildIntersection. An intersection depends on the lanes of its own
// incoming and outgoing roads only, so one road's new lanes touch the two intersections at its ends.
std::optional<IntersectionResult> buildJoinedIntersection(const skeleton::Skeleton& skeleton, size_t index,
                                                          const std::map<int64_t, map::LaneMap>& roads,
                                                          const IntersectionOptions& options = {},
                                                          const std::vector<osm::Restriction>& restrictions = {},
                                     const std::vector<DrivenPassage>& passages = {});

// Every intersection with at least one incoming and one outgoing road in `roads`.
// One intersection whose building throws is left out, named in `failures` when given ("intersection
// ID: reason"): one junction's trouble never costs the rest of the map.
std::vector<IntersectionResult> buildIntersections(const skeleton::Skeleton& skeleton,
                                                   const std::map<int64_t, map::LaneMap>& roads,
                                                   const IntersectionOptions& options = {},
                                                   const std::vector<osm::Restriction>& restrictions = {},
                                                   std::vector<std::string>* failures = nullptr);

// Appends the fragment's lines and lanelets to `whole` and adds each intersection lanelet to the
// successors of its incoming road lanelet (when `whole` has it). Replaces an earlier fragment of
// the same intersection (lanelets and lines with the fragment's ids are removed first, and so are
// the successor links to them).
void appendIntersection(map::LaneMap& whole, const IntersectionResult& result);

// appendIntersection for each fragment in order, in one pass over `whole` (linear in its size,
// where calling appendIntersection per fragment is quadratic). Same result.
void appendIntersections(map::LaneMap& whole, const std::vector<const IntersectionResult*>& results);

// The road lanelets (kind kRoad, road_id >= 0) of a whole map grouped by road id, each with the
// lines it uses; the input buildIntersection takes, from e.g. the simulator's ground truth.
std::map<int64_t, map::LaneMap> roadsOf(const map::LaneMap& whole);

}  // namespace lanemap::intersections
