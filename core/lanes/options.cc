#include "core/lanes/options.h"

#include <cmath>
#include <set>
#include <string>

namespace lanemap::lanes {

namespace {

template <typename T>
void read(const YAML::Node& n, const char* key, T& v, std::set<std::string>& seen) {
  seen.insert(key);
  if (!n[key]) return;
  try {
    v = n[key].as<T>();
  } catch (const YAML::Exception& e) {
    throw LanesError(std::string("lane explorer option `") + key + "`: " + e.what());
  }
}

}  // namespace

ExplorerOptions ExplorerOptions::fromYaml(const YAML::Node& n) {
  ExplorerOptions o;
  if (!n || n.IsNull()) return o;
  if (!n.IsMap()) throw LanesError("lane explorer options must be a YAML map");
  std::set<std::string> k;
  read(n, "num_particles", o.num_particles, k);
  read(n, "footprint_length_m", o.footprint_length_m, k);
  read(n, "footprint_width_m", o.footprint_width_m, k);
  read(n, "v_min", o.v_min, k);
  read(n, "v_max", o.v_max, k);
  read(n, "w_min", o.w_min, k);
  read(n, "w_max", o.w_max, k);
  read(n, "dt_s", o.dt_s, k);
  read(n, "max_heading_rad", o.max_heading_rad, k);
  read(n, "seed", o.seed, k);
  read(n, "marking_fraction", o.marking_fraction, k);
  read(n, "separation_fraction", o.separation_fraction, k);
  read(n, "drivable_fraction", o.drivable_fraction, k);
  read(n, "drivable_min_count", o.drivable_min_count, k);
  read(n, "min_observations", o.min_observations, k);
  read(n, "corridor_half_width_m", o.corridor_half_width_m, k);
  read(n, "frame_spacing_m", o.frame_spacing_m, k);
  read(n, "frame_smoothing_m", o.frame_smoothing_m, k);
  read(n, "right_hand_traffic", o.right_hand_traffic, k);
  read(n, "divider_search_m", o.divider_search_m, k);
  read(n, "divider_bin_m", o.divider_bin_m, k);
  read(n, "carriageway_wall_m", o.carriageway_wall_m, k);
  read(n, "unnamed_lanes", o.unnamed_lanes, k);
  read(n, "lane_width_min_m", o.lane_width_min_m, k);
  read(n, "lane_width_max_m", o.lane_width_max_m, k);
  read(n, "birth_every_m", o.birth_every_m, k);
  read(n, "birth_min_free_m", o.birth_min_free_m, k);
  read(n, "birth_min_evidence", o.birth_min_evidence, k);
  read(n, "birth_particles", o.birth_particles, k);
  read(n, "dbscan_eps_m", o.dbscan_eps_m, k);
  read(n, "dbscan_min_points", o.dbscan_min_points, k);
  read(n, "track_tolerance_m", o.track_tolerance_m, k);
  read(n, "lane_gap_max_m", o.lane_gap_max_m, k);
  read(n, "same_lane_m", o.same_lane_m, k);
  read(n, "min_lane_length_m", o.min_lane_length_m, k);
  read(n, "short_road_min_m", o.short_road_min_m, k);
  read(n, "split_neighbour_m", o.split_neighbour_m, k);
  read(n, "bin_m", o.bin_m, k);
  read(n, "break_spacing_m", o.break_spacing_m, k);
  read(n, "break_penalty_m2", o.break_penalty_m2, k);
  read(n, "waypoint_spacing_m", o.waypoint_spacing_m, k);
  read(n, "probe_max_m", o.probe_max_m, k);
  read(n, "default_half_width_m", o.default_half_width_m, k);
  for (const auto& kv : n) {
    const std::string key = kv.first.as<std::string>();
    if (!k.count(key)) throw LanesError("unknown lane explorer option `" + key + "`");
  }
  o.validate();
  return o;
}

void ExplorerOptions::validate() const {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw LanesError(std::string("lane explorer option out of range: ") + what);
  };
  need(num_particles >= 10 && num_particles <= 100000, "num_particles in [10, 100000]");
  need(footprint_length_m > 0 && footprint_width_m > 0, "footprint > 0");
  need(v_min > 0 && v_max >= v_min, "0 < v_min <= v_max");
  need(w_max >= w_min, "w_min <= w_max");
  need(dt_s > 0 && dt_s <= 10, "dt_s in (0, 10]");
  need(max_heading_rad > 0 && max_heading_rad < 1.6, "max_heading_rad in (0, 1.6)");
  need(marking_fraction > 0 && marking_fraction <= 1, "marking_fraction in (0, 1]");
  need(separation_fraction > 0 && separation_fraction <= 1, "separation_fraction in (0, 1]");
  need(drivable_fraction >= 0 && drivable_fraction <= 1, "drivable_fraction in [0, 1]");
  need(drivable_min_count >= 0, "drivable_min_count >= 0");
  need(min_observations >= 1, "min_observations >= 1");
  need(corridor_half_width_m > footprint_width_m && corridor_half_width_m <= 60, "corridor_half_width_m");
  need(frame_spacing_m > 0.05 && frame_spacing_m <= 5, "frame_spacing_m in (0.05, 5]");
  need(frame_smoothing_m >= 0, "frame_smoothing_m >= 0");
  need(divider_search_m >= 0 && divider_bin_m > 0, "divider_search_m, divider_bin_m");
  need(carriageway_wall_m > 0, "carriageway_wall_m > 0");
  need(lane_width_min_m > 0 && lane_width_max_m >= lane_width_min_m, "0 < lane_width_min_m <= lane_width_max_m");
  need(birth_every_m > 0 && birth_min_free_m >= 0 && birth_particles >= 1, "births");
  need(birth_min_evidence >= 0 && birth_min_evidence <= 1, "birth_min_evidence in [0, 1]");
  need(dbscan_eps_m > 0 && dbscan_min_points >= 1, "dbscan");
  need(track_tolerance_m >= 0 && lane_gap_max_m >= 0 && same_lane_m >= 0 && min_lane_length_m >= 0, "tracking");
  need(short_road_min_m >= 1.0 && short_road_min_m <= 100.0, "short_road_min_m in [1, 100]");
  need(bin_m > 0 && break_spacing_m >= bin_m && break_penalty_m2 >= 0, "regression");
  need(waypoint_spacing_m > 0, "waypoint_spacing_m > 0");
  need(probe_max_m > 0 && default_half_width_m > 0, "probing");
  if (!std::isfinite(v_max) || !std::isfinite(w_max)) throw LanesError("lane explorer options must be finite");
}

}  // namespace lanemap::lanes
