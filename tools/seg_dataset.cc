// lanemap-seg-dataset: renders camera frames and their truth labels with the simulator's core
// classes (core/seg/sim_frames.h), for training the segmentation model (tools/seg/train.py).
// Writes <out>/images/<name>.jpg (the JPEG as CAMERA_FRONT carries it), <out>/labels/<name>.png
// (label_image_t class ids) and appends one row per frame to <out>/index.csv:
//   name,osm,seed,region,t_s,east_m,north_m,light,sun_elevation_deg,pitch_offset_deg
#include "core/seg/sim_frames.h"
#include "processes/framework/share_dir.h"
#include "tools/cli_checks.h"

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace fs = std::filesystem;
using namespace lanemap;

int main(int argc, char** argv) {
  CLI::App app("lanemap-seg-dataset: render simulated camera frames + truth labels for segmentation training");
  seg::SimFrameOptions o;
  o.vehicle_yaml = "config/vehicle.yaml";
  o.world_yaml = "config/sim_world.yaml";
  o.drive_yaml = "config/sim_drive.yaml";
  std::string out_dir, region = "all", tag;
  uint64_t first_seed = 1, num_seeds = 1;
  bool plain = false;
  app.add_option("--osm", o.osm_path, "street network (.osm / .osm.pbf)")->required()->check(CLI::ExistingFile);
  app.add_option("--out", out_dir, "output folder (created; index.csv is appended to)")->required();
  app.add_option("--tag", tag, "name prefix of the frames (default: the OSM file's stem)");
  app.add_option("--first-seed", first_seed, "first seed");
  app.add_option("--seeds", num_seeds, "number of seeds (one drive each)")->check(lanemap::cli::kPositive);
  app.add_option("--frames", o.max_frames, "frames per seed")->check(lanemap::cli::kPositive);
  app.add_option("--spacing", o.frame_spacing_s, "mean seconds between frames")->check(lanemap::cli::kPositive);
  app.add_option("--duration", o.duration_s, "drive length per seed, seconds")->check(lanemap::cli::kPositive);
  app.add_option("--region", region, "all, train or validation (east split)")
      ->check(CLI::IsMember({"all", "train", "validation"}));
  app.add_option("--validation-fraction", o.validation_fraction, "western share of the network held out");
  app.add_option("--faded", o.faded_marking, "faded-marking probability override (>= 0)");
  app.add_flag("--plain", plain, "no lighting / camera jitter (the simulator's default look)");
  app.add_option("--vehicle", o.vehicle_yaml, "camera config");
  app.add_option("--world-config", o.world_yaml, "world generation config");
  app.add_option("--drive-config", o.drive_yaml, "driving config");
  CLI11_PARSE(app, argc, argv);
  o.vary_conditions = !plain;
  o.region = region == "train" ? seg::SimRegion::kTrain
             : region == "validation" ? seg::SimRegion::kValidation : seg::SimRegion::kAll;
  if (tag.empty()) tag = fs::path(o.osm_path).stem().stem().string();

  try {
    for (std::string* f : {&o.vehicle_yaml, &o.world_yaml, &o.drive_yaml}) *f = resolveShippedFile(*f);
    fs::create_directories(fs::path(out_dir) / "images");
    fs::create_directories(fs::path(out_dir) / "labels");
    const fs::path index_path = fs::path(out_dir) / "index.csv";
    const bool header = !fs::exists(index_path);
    std::ofstream index(index_path, std::ios::app);
    if (!index) throw std::runtime_error("cannot write " + index_path.string());
    if (header) index << "name,osm,seed,region,t_s,east_m,north_m,light,sun_elevation_deg,pitch_offset_deg\n";
    int total = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (uint64_t s = first_seed; s < first_seed + num_seeds; ++s) {
      o.seed = s;
      const int n = seg::renderSimFrames(o, [&](const seg::SimFrame& f) {
        char name[256];
        std::snprintf(name, sizeof(name), "%s_s%03llu_%04d", tag.c_str(), static_cast<unsigned long long>(s), f.index);
        {
          std::ofstream jpg(fs::path(out_dir) / "images" / (std::string(name) + ".jpg"), std::ios::binary);
          jpg.write(reinterpret_cast<const char*>(f.jpeg.data()), static_cast<std::streamsize>(f.jpeg.size()));
          if (!jpg) throw std::runtime_error("writing an image failed (disk full?)");
        }
        if (!cv::imwrite((fs::path(out_dir) / "labels" / (std::string(name) + ".png")).string(), f.labels))
          throw std::runtime_error("writing a label image failed");
        char row[512];
        std::snprintf(row, sizeof(row), "%s,%s,%llu,%s,%.2f,%.1f,%.1f,%.3f,%.1f,%.2f\n", name,
                      fs::path(o.osm_path).filename().c_str(), static_cast<unsigned long long>(s), region.c_str(),
                      f.t, f.position.x(), f.position.y(), f.light, f.sun_elevation_deg, f.pitch_offset_deg);
        index << row;
        return true;
      });
      index.flush();
      total += n;
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("lanemap-seg-dataset: %s seed %llu: %d frames (total %d, %.0f s)\n", tag.c_str(),
                  static_cast<unsigned long long>(s), n, total, secs);
      std::fflush(stdout);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-seg-dataset: error: %s\n", e.what());
    return 2;
  }
}
