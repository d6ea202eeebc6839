// The simulator's world built from a Lanelet2 map that someone else drew (lanemap-sim --lanelet2),
// instead of from OSM road tags: the lanes, markings, curbs, crosswalks, stop lines and junctions
// are the map's own, and the ground truth is the map's own vehicle lanelets. The road-level OSM
// that lanemap is given (roads.osm) is derived from the lanelets, so the team's OSM-to-lanes rules
// make neither the world nor the truth.
//
// How the map is read (buildLanelet2World):
//  - vehicle lanelets: subtype road, highway, bus_lane, play_street. A two-way lanelet (one_way=no;
//    play_street without one_way) is split along its middle into one lanelet per direction (the
//    drawn direction keeps the map's id; right-hand traffic drives on the right half), joined by
//    a virtual line.
//  - junction lanelets: vehicle lanelets whose centre line runs inside another vehicle lanelet
//    that is neither a lateral neighbour (shared bound) nor a successor/predecessor: crossing,
//    branching and merging movements. The rest are road lanelets.
//  - junction areas: junction lanelets joined by overlap, succession, a shared bound or a shared
//    predecessor/successor; one OSM junction node each, at the mean of its lanelets' centre lines,
//    or on a road's middle line where the road passes the junction, or on a one-way carriageway
//    that runs through it (a roundabout's ring at an entry), as OSM draws it.
//  - roads: road lanelets joined by a shared bound or succession form one road; its OSM way runs
//    along the middle of the road's whole cross-section (all lanes, both directions) from the
//    junction node at one end to the one at the other (or a dead end), through the junction
//    nodes of the junctions it passes (moved onto the way), tagged highway, lanes,
//    lanes:forward/backward or oneway=yes from the lanelets. A road under 8 m beside one junction
//    is part of the junction. Junction pieces drawn in a chain become one intersection lanelet.
//  - the skeleton is built from that OSM as lanemap builds it from roads.osm; each road lanelet
//    gets road_id/from_node/to_node (the atomic road of its way in its direction) and
//    index_from_left (same-direction neighbours on its left), each junction lanelet
//    intersection_id (the skeleton intersection of its area's node) and turn (from the heading
//    change of its centre line).
//  - the scene: vehicle lanelets as lane (road) or intersection (junction) asphalt, bicycle lanes,
//    markings painted along the bounds by their type (line_thin/line_thick dashed: dashes of
//    kDashLength every kDashPeriod; solid, solid_solid, dashed_solid: solid; curbstone,
//    road_border, wall, fence, guard_rail: curb), a sidewalk band behind every curb, stop_line
//    ways, crosswalk lanelets as zebra stripes. Flat ground, no obstacles.
#pragma once

#include "core/geo/local_frame.h"
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace lanemap::sim {

struct Lanelet2WorldStats {
  size_t map_lanelets = 0;        // every lanelet relation read (all subtypes)
  size_t map_vehicle_lanelets = 0;// of them road/highway/bus_lane/play_street
  size_t two_way_split = 0;       // vehicle lanelets drivable both ways, split in two
  size_t road_lanelets = 0;       // truth lanelets of kind road
  size_t junction_lanelets = 0;   // truth lanelets of kind intersection
  size_t junction_areas = 0;
  size_t roads = 0;               // OSM ways derived
  size_t unassigned_lanelets = 0; // road lanelets whose way the skeleton dropped (made junction)
  size_t joined_junction_paths = 0; // truth junction lanelets joined from several drawn pieces
  size_t stubs_in_junctions = 0;  // roads under 8 m beside one junction, made part of it
  size_t through_junctions = 0;   // junction nodes put onto a one-way carriageway running through
  size_t crosswalks = 0, stop_lines = 0, painted_lines = 0, curbs = 0;
};

struct Lanelet2World {
  std::unique_ptr<SimWorld> world;                 // truth(): the map's vehicle lanelets, labelled
  osm::OsmData roads;                              // the derived road-level OSM (roads.osm)
  std::unique_ptr<skeleton::Skeleton> skeleton;    // built from `roads` in the map's frame
  Lanelet2WorldStats stats;
  std::map<int64_t, int64_t> split_twin;           // two-way lanelet id -> its reverse half's id
  std::map<int64_t, std::vector<int64_t>> joined;  // truth junction lanelet -> the drawn pieces
};

// The centre of a Lanelet2 file's node bounds (a default ENU origin); throws io::Lanelet2Error
// (from the reader) or std::runtime_error for a file with no node.
geo::LatLonAlt lanelet2MapCentre(const std::string& path);

// Reads the Lanelet2 map at `path` in the ENU frame of `origin` and builds the world. `options`:
// seed, tile and raster settings (the ground is always flat: options.flat is forced). Throws
// io::Lanelet2Error for an unreadable map, std::runtime_error when it has no vehicle lanelet or no
// road can be derived from it.
Lanelet2World buildLanelet2World(const std::string& path, const geo::LatLonAlt& origin,
                                 const WorldOptions& options);

}  // namespace lanemap::sim
