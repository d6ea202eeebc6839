// Lanelet2 OSM <-> map::LaneMap. The writer produces a file Lanelet2's own loader reads without
// errors, with only tags and values Lanelet2's validator (lanelet2_validate) knows (positive ids,
// lat/lon with 10 decimals, `ele` on every node, typed line strings, lanelet relations with
// left/right members); the reader reads any Lanelet2 map (ours or someone else's, e.g. the
// Lanelet2 project's Karlsruhe example) with libosmium.
//
// Conventions (see also writeLanelet2/readLanelet2 below):
// - lanemap's own metadata (a lanelet's kind, road_id, from/to node, intersection id, lane index,
//   stop line, "partial": {station_m, road_length_m} on a road mapped as far as a drive went,
//   "confidence" of the lane) and the mm-precise ENU coordinates of the nodes are not in the OSM file but in a
//   sidecar beside it: MAP.osm -> MAP.lanemap.json (lanelet2SidecarPath), keyed by lanelet id and
//   bound to the OSM file by the FNV-1a hash of its bytes. readLanelet2 uses it transparently;
//   a copy of the OSM file under another name in the same folder finds its sidecar by the hash.
//   Without a (matching) sidecar the reader takes `lanemap:*` lanelet tags (files written before
//   the sidecar) and lat/lon, which libosmium keeps to 1e-7 degrees (~1 cm).
// - Coordinates: a node's lat/lon is the point's horizontal position, `ele` = origin_alt + ENU z
//   (Lanelet2 uses `ele` as z). Autoware's `local_x`/`local_y` node tags are written on request
//   (Lanelet2WriteOptions::local_xy_tags; the validator calls them unknown tags) and read when
//   they agree with lat/lon in the reader's frame.
// - Points closer than 5.01 cm (Lanelet2's points_too_close limit, 5 cm, with a margin for the
//   UTM scale its validator measures in) are one node in the file.
// - Lanelet2 has no successor tags; successors are recovered from shared end/start points.
// - Stop lines are ways type=stop_line; the lanelet that ends at one names it in the sidecar (and
//   in Autoware's layout, when no regulatory element below has it as ref_line, references a
//   road_marking regulatory element referring to it). The
//   reader also takes a stop line from a regulatory element's `ref_line` member (traffic lights,
//   right of way) or a road_marking's `refers` in foreign maps.
// - Regulatory elements (map::RegulatoryElement): a stop sign is a `traffic_sign` with
//   sign_type=stop_sign (Autoware's value; Lanelet2 takes the type from sign_type when no sign is
//   mapped) and the stop line as `ref_line`; give way is a `right_of_way` (yield = the lanelets
//   ending at the stop line, right_of_way = the priority lanelets, ref_line = the stop line), or a
//   traffic_sign sign_type=give_way when no lanelet has priority; a traffic light is a
//   `traffic_light` whose `refers` is a way type=traffic_light (its bottom edge, `height`) and
//   whose ref_line is the stop line. Every lanelet an element applies to references it (role
//   regulatory_element). That a light's position is an estimate (the camera maps none) is in the
//   sidecar ("light_position": "estimated"): Lanelet2's validator knows no tag for it.
// - Crosswalks (map::Crosswalk) are lanelets subtype=crosswalk, one_way=no, with virtual edges;
//   Autoware's layout adds its crosswalk regulatory element (crosswalk_regulatory_elements). The
//   reader puts every subtype=crosswalk lanelet into map.crosswalks (never into map.lanelets,
//   whatever Lanelet2ReadOptions::subtypes says) and reads the elements above back.
// - The centre line is written as a way (type=virtual) with member role `centerline`, which
//   Lanelet2 loads as the lanelet's centreline; without it the reader averages the two bounds.
// - Autoware's tags: `lane_change` (yes on a dashed line between two same-direction lanes, no on
//   any other line between them), `speed_limit` (km/h), `location`, `one_way`, `subtype` on every
//   lanelet; `turn_direction` on every intersection lanelet (from its centre line when the model
//   has none) only on request (turn_direction_tags, Autoware's folder layout): Lanelet2's
//   validator does not know it.
#pragma once

#include "core/geo/local_frame.h"
#include "core/io/atomic_file.h"
#include "core/io/lanelet2_orientation.h"
#include "core/map/lane_map.h"

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lanemap::io {

class Lanelet2Error : public IoError {
 public:
  using IoError::IoError;
};

struct Lanelet2WriteOptions {
  bool write_centre_lines = true;  // the model's centre line as a `centerline` member way
  bool check_orientation = true;   // throw when a lanelet's bounds do not run in one direction
                                   // with the left bound on the left (see orientationProblems)
  bool write_sidecar = true;       // MAP.lanemap.json beside MAP.osm (lanemap's metadata)
  bool write_projector_info = true;// map_projector_info.yaml in the map's folder (Autoware)
  bool local_xy_tags = false;      // Autoware's local_x/local_y on every node (for its `Local`
                                   // projector; Lanelet2's validator warns: unknown tags)
  // Autoware's `turn_direction` on every intersection lanelet. Lanelet2's validator does not know
  // the tag (one unknown_tags warning per intersection lanelet), so a plain map leaves it out (the
  // sidecar keeps the model's turn); writeAutowareMapFolder writes it.
  bool turn_direction_tags = false;
  // Each stop line as the `refers` member of Autoware's regulatory element subtype=road_marking,
  // referenced by the lanelet it ends. Plain Lanelet2 implements no road_marking (its loader
  // reports an error per element and per lanelet referencing one), and none of the elements it
  // has fits a stop line alone (a traffic sign or light needs its sign, right of way the priority
  // of the roads); so only Autoware's folder layout writes them.
  bool stop_line_road_markings = false;
  // Autoware's crosswalk regulatory element (refers = the crosswalk lanelet, crosswalk_polygon =
  // a polygon way type=crosswalk_polygon) referenced by the road lanelets the crosswalk crosses.
  // Plain Lanelet2 implements no crosswalk element (a load error each), so only Autoware's layout
  // writes them; the crosswalk lanelet itself (subtype=crosswalk) is in every map.
  bool crosswalk_regulatory_elements = false;
  std::string location = "urban";  // `location` of every lanelet (urban, nonurban, private)
  // `speed_limit` (km/h) of a road's lanelets: OSM maxspeed by lanelet road_id (speedLimitsKmh),
  // else this default (40 km/h = 25 mph, the US residential default; intersection lanelets take
  // the slower of the roads they join, else the default).
  double default_speed_limit_kmh = 40.0;
  std::map<int64_t, double> speed_limit_kmh_by_road;
};

// The sidecar of a map file: "DIR/NAME.osm" -> "DIR/NAME.lanemap.json" (other names: + ".lanemap.json").
std::string lanelet2SidecarPath(const std::string& osm_path);
// The writer's ENU origin of a lanemap file, from its matching sidecar; nullopt without one.
std::optional<geo::LatLonAlt> lanelet2WriterOrigin(const std::string& osm_path);
// Parses an OSM maxspeed value to km/h: "50", "50 km/h", "25 mph", "30 knots"; nullopt for
// "none", "signals", "walk", country codes ("DE:urban") and anything else.
std::optional<double> parseMaxspeedKmh(const std::string& value);

// Writes `map` as Lanelet2 OSM to `path`, atomically, after its sidecar (write_sidecar) and with
// map_projector_info.yaml beside it (write_projector_info). Throws Lanelet2Error (message names the
// path and the offending id) on an inconsistent map: a missing bound or stop line, a bound with
// fewer than 2 points, duplicate line or lanelet ids, or (check_orientation) a wrongly oriented
// lanelet. Ids: ways keep the LineString ids and relations the Lanelet ids when all are positive
// and distinct; otherwise everything is renumbered (deterministically, in vector order).
void writeLanelet2(const map::LaneMap& map, const std::string& path);
void writeLanelet2(const map::LaneMap& map, const std::string& path,
                   const Lanelet2WriteOptions& options);
// The same document as a string (what writeLanelet2 writes). `name` is used in error messages.
std::string toLanelet2Xml(const map::LaneMap& map, const Lanelet2WriteOptions& options = {},
                          const std::string& name = "<lanelet2>");
struct Lanelet2Document {
  std::string osm;      // the OSM file
  std::string sidecar;  // its MAP.lanemap.json (bound to `osm` by its hash)
};
Lanelet2Document toLanelet2Document(const map::LaneMap& map, const Lanelet2WriteOptions& options = {},
                                    const std::string& name = "<lanelet2>");
// Autoware's map_projector_info.yaml for the map's origin: projector_type LocalCartesian (the ENU
// frame of lanemap, GeographicLib's LocalCartesian), vertical_datum WGS84, map_origin lat/lon/alt.
std::string autowareProjectorInfo(const map::LaneMap& map);
// Autoware's map folder layout: DIR/lanelet2_map.osm (+ its sidecar) and DIR/map_projector_info.yaml,
// with turn_direction_tags and stop_line_road_markings set.
void writeAutowareMapFolder(const map::LaneMap& map, const std::string& dir,
                            const Lanelet2WriteOptions& options = {});

struct Lanelet2ReadOptions {
  std::vector<std::string> subtypes;  // lanelet subtypes to keep ("road", ...); empty = all
  double centre_spacing_m = 1.0;      // sample spacing of a centre line computed from the bounds
  double origin_alt = 0.0;            // ENU origin altitude: z = ele - origin_alt
};

// Everything the reader found, including what LaneMap has no field for.
struct Lanelet2File {
  map::LaneMap map;
  std::map<int64_t, std::string> lanelet_subtype;  // lanelet id -> `subtype` ("road", "crosswalk")
  std::map<int64_t, std::string> line_tag;         // line id -> "type" or "type:subtype" as read
  // A way used against its own direction by some lanelet (e.g. the border between two opposite
  // lanes) is copied, reversed, under a fresh id, so every bound runs in its lanelet's driving
  // direction as LaneMap requires: copy id -> way id.
  std::map<int64_t, int64_t> reversed_copy_of;
  bool used_local_xy = false;  // coordinates came from the sidecar or local_x/local_y (mm precision)
  std::string sidecar;         // the sidecar used (empty: none matched)
  bool stale_sidecar = false;  // MAP.lanemap.json exists but belongs to another version of MAP.osm
  size_t computed_centres = 0; // lanelets whose centre was averaged from the bounds
};

// Reads a Lanelet2 OSM file (XML) into ENU metres around (origin_lat, origin_lon,
// options.origin_alt = 0 by default; a missing `ele` reads as z = 0). All lanelets
// are read (every subtype); bounds are aligned like Lanelet2 does (right bound turned to run like
// the left one; both turned when the left one lies on the right), `inverted` member roles are
// honoured. Throws Lanelet2Error with the path for a missing, unreadable or malformed file or a
// lanelet that references a missing way or node.
map::LaneMap readLanelet2(const std::string& path, double origin_lat, double origin_lon);
map::LaneMap readLanelet2(const std::string& path, double origin_lat, double origin_lon,
                          const Lanelet2ReadOptions& options);
Lanelet2File readLanelet2File(const std::string& path, double origin_lat, double origin_lon,
                              const Lanelet2ReadOptions& options = {});

// The coordinate convention of lanemap's OSM files: `enu` of `frame` -> lat, lon and
// ele = origin alt + z; and back (the point on the vertical through lat/lon whose ENU z equals
// ele - origin alt), so a round trip is exact.
geo::LatLonAlt enuToLatLonEle(const geo::LocalFrame& frame, const Eigen::Vector3d& enu);
Eigen::Vector3d latLonEleToEnu(const geo::LocalFrame& frame, double lat, double lon, double ele);

}  // namespace lanemap::io
