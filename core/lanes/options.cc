#include "core/lanes/options.h"

#include "core/config/yaml_reader.h"

#include <cmath>
#include <string>

namespace lanemap::lanes {

ExplorerOptions ExplorerOptions::fromYaml(const YAML::Node& n) {
  try {
    const config::YamlReader r(n);
    ExplorerOptions o = fromYaml(r);
    r.finish();
    return o;
  } catch (const config::ConfigError& e) {
    throw LanesError(e.what());
  }
}

ExplorerOptions ExplorerOptions::fromYaml(const config::YamlReader& r) {
  ExplorerOptions o;
  r.read("num_particles", o.num_particles);
  r.read("footprint_length_m", o.footprint_length_m);
  r.read("footprint_width_m", o.footprint_width_m);
  r.read("v_min", o.v_min);
  r.read("v_max", o.v_max);
  r.read("w_min", o.w_min);
  r.read("w_max", o.w_max);
  r.read("dt_s", o.dt_s);
  r.read("max_heading_rad", o.max_heading_rad);
  r.read("seed", o.seed);
  r.read("marking_fraction", o.marking_fraction);
  r.read("separation_fraction", o.separation_fraction);
  r.read("kill_min_count", o.kill_min_count);
  r.read("drivable_fraction", o.drivable_fraction);
  r.read("drivable_min_count", o.drivable_min_count);
  r.read("min_observations", o.min_observations);
  r.read("corridor_half_width_m", o.corridor_half_width_m);
  for (const char* moved : {"frame_spacing_m", "frame_smoothing_m"}) {
    double unused = 0.0;
    if (r.read(moved, unused)) r.fail(moved, "is the map block's now: road_frame {spacing_m, smoothing_m} in config/map.yaml");
  }
  r.read("right_hand_traffic", o.right_hand_traffic);
  r.read("divider_search_m", o.divider_search_m);
  r.read("divider_bin_m", o.divider_bin_m);
  r.read("divider_reach_m", o.divider_reach_m);
  r.read("carriageway_wall_m", o.carriageway_wall_m);
  r.read("kerb_wall_fraction", o.kerb_wall_fraction);
  r.read("unnamed_lanes", o.unnamed_lanes);
  r.read("lane_width_min_m", o.lane_width_min_m);
  r.read("lane_width_max_m", o.lane_width_max_m);
  r.read("blocked_lane_beyond_dashed_edge", o.blocked_lane_beyond_dashed_edge);
  r.read("line_tolerance_m", o.line_tolerance_m);
  r.read("birth_every_m", o.birth_every_m);
  r.read("birth_min_free_m", o.birth_min_free_m);
  r.read("birth_min_evidence", o.birth_min_evidence);
  r.read("birth_particles", o.birth_particles);
  r.read("dbscan_eps_m", o.dbscan_eps_m);
  r.read("dbscan_min_points", o.dbscan_min_points);
  r.read("track_tolerance_m", o.track_tolerance_m);
  r.read("lane_gap_max_m", o.lane_gap_max_m);
  r.read("flat_beyond_samples", o.flat_beyond_samples);
  r.read("same_lane_m", o.same_lane_m);
  r.read("min_lane_length_m", o.min_lane_length_m);
  r.read("short_road_min_m", o.short_road_min_m);
  r.read("short_road_line_run_m", o.short_road_line_run_m);
  r.read("partial_min_driven_m", o.partial_min_driven_m);
  r.read("carry_lanes_max_m", o.carry_lanes_max_m);
  r.read("carry_max_turn_rad", o.carry_max_turn_rad);
  r.read("lanes_from_osm_way", o.lanes_from_osm_way);
  r.read("drop_lanes_apart_from_carried", o.drop_lanes_apart_from_carried);
  r.read("add_carried_lanes_not_found", o.add_carried_lanes_not_found);
  r.read("split_neighbour_m", o.split_neighbour_m);
  r.read("pocket_taper_max_m", o.pocket_taper_max_m);
  r.read("pocket_min_width_m", o.pocket_min_width_m);
  r.read("pocket_to_junction", o.pocket_to_junction);
  r.read("bulge_density_fraction", o.bulge_density_fraction);
  r.read("min_drivable_share", o.min_drivable_share);
  r.read("weak_density_fraction", o.weak_density_fraction);
  r.read("join_gap_max_m", o.join_gap_max_m);
  r.read("join_min_drivable_share", o.join_min_drivable_share);
  r.read("floating_lane_max_m", o.floating_lane_max_m);
  r.read("lanes_beyond_dashed", o.lanes_beyond_dashed);
  r.read("bin_m", o.bin_m);
  r.read("break_spacing_m", o.break_spacing_m);
  r.read("break_penalty_m2", o.break_penalty_m2);
  r.read("waypoint_spacing_m", o.waypoint_spacing_m);
  r.read("probe_max_m", o.probe_max_m);
  r.read("default_half_width_m", o.default_half_width_m);
  r.read("boundary_outlier_m", o.boundary_outlier_m);
  r.read("boundary_median_window", o.boundary_median_window);
  r.read("recentre_max_m", o.recentre_max_m);
  try {
    o.validate();
  } catch (const LanesError& e) {
    r.failHere(e.what());
  }
  return o;
}

void ExplorerOptions::validate() const {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw LanesError(std::string("lane explorer option out of range: ") + what);
  };
  need(num_particles >= 10 && num_particles <= 100000, "num_particles in [10, 100000]");
  need(pocket_taper_max_m >= 0 && pocket_min_width_m > 0, "pocket_taper_max_m >= 0 and pocket_min_width_m > 0");
  need(footprint_length_m > 0 && footprint_width_m > 0, "footprint > 0");
  need(v_min > 0 && v_max >= v_min, "0 < v_min <= v_max");
  need(w_max >= w_min, "w_min <= w_max");
  need(dt_s > 0 && dt_s <= 10, "dt_s in (0, 10]");
  need(max_heading_rad > 0 && max_heading_rad < 1.6, "max_heading_rad in (0, 1.6)");
  need(marking_fraction > 0 && marking_fraction <= 1, "marking_fraction in (0, 1]");
  need(separation_fraction > 0 && separation_fraction <= 1, "separation_fraction in (0, 1]");
  need(carry_lanes_max_m >= 0 && carry_max_turn_rad >= 0 && carry_max_turn_rad < 1.6,
       "carry_lanes_max_m >= 0 and carry_max_turn_rad in [0, 1.6)");
  need(min_drivable_share >= 0 && min_drivable_share <= 1, "min_drivable_share in [0, 1]");
  need(floating_lane_max_m >= 0, "floating_lane_max_m >= 0");
  need(lanes_beyond_dashed >= 0 && lanes_beyond_dashed <= 8, "lanes_beyond_dashed in [0, 8]");
  need(join_gap_max_m >= 0 && std::isfinite(join_gap_max_m), "join_gap_max_m >= 0");
  need(join_min_drivable_share >= 0 && join_min_drivable_share <= 1, "join_min_drivable_share in [0, 1]");
  need(kill_min_count >= 1, "kill_min_count >= 1");
  need(drivable_fraction >= 0 && drivable_fraction <= 1, "drivable_fraction in [0, 1]");
  need(drivable_min_count >= 0, "drivable_min_count >= 0");
  need(min_observations >= 1, "min_observations >= 1");
  need(corridor_half_width_m > footprint_width_m && corridor_half_width_m <= 60, "corridor_half_width_m");
  need(frame_spacing_m > 0.05 && frame_spacing_m <= 5, "frame_spacing_m in (0.05, 5]");
  need(frame_smoothing_m >= 0, "frame_smoothing_m >= 0");
  need(divider_search_m >= 0 && divider_bin_m > 0 && divider_reach_m >= 0, "divider_search_m, divider_bin_m, divider_reach_m");
  need(carriageway_wall_m > 0, "carriageway_wall_m > 0");
  need(kerb_wall_fraction >= 0 && kerb_wall_fraction <= 1, "kerb_wall_fraction in [0, 1]");
  need(lane_width_min_m > 0 && lane_width_max_m >= lane_width_min_m, "0 < lane_width_min_m <= lane_width_max_m");
  need(line_tolerance_m >= 0 && line_tolerance_m < 0.5 * lane_width_min_m, "0 <= line_tolerance_m < lane_width_min_m / 2");
  need(birth_every_m > 0 && birth_min_free_m >= 0 && birth_particles >= 1, "births");
  need(birth_min_evidence >= 0 && birth_min_evidence <= 1, "birth_min_evidence in [0, 1]");
  need(dbscan_eps_m > 0 && dbscan_min_points >= 1, "dbscan");
  need(track_tolerance_m >= 0 && lane_gap_max_m >= 0 && same_lane_m >= 0 && min_lane_length_m >= 0 && bulge_density_fraction >= 0 && weak_density_fraction >= 0, "tracking");
  need(short_road_min_m >= 1.0 && short_road_min_m <= 100.0, "short_road_min_m in [1, 100]");
  need(short_road_line_run_m >= 0.0 && short_road_line_run_m <= 100.0, "short_road_line_run_m in [0, 100]");
  need(partial_min_driven_m >= 0 && std::isfinite(partial_min_driven_m), "partial_min_driven_m >= 0");
  need(bin_m > 0 && break_spacing_m >= bin_m && break_penalty_m2 >= 0, "regression");
  need(waypoint_spacing_m > 0, "waypoint_spacing_m > 0");
  need(probe_max_m > 0 && default_half_width_m > 0, "probing");
  need(recentre_max_m >= 0 && recentre_max_m <= 2, "recentre_max_m in [0, 2]");
  need(boundary_outlier_m >= 0 && boundary_median_window >= 1 && boundary_median_window % 2 == 1,
       "boundary_outlier_m >= 0 and an odd boundary_median_window >= 1");
  if (!std::isfinite(v_max) || !std::isfinite(w_max)) throw LanesError("lane explorer options must be finite");
}

}  // namespace lanemap::lanes
