// lanemap-city: many drives into one map store, on every core of the machine or on a Slurm cluster.
//
//   lanemap-city --store S --osm city.osm [--jobs N] [--oracle | --semantic-channel C | --model M]
//                [--no-lidar] [--no-align | --no-drive-offsets] [--align-rotation] DRIVE.lcmlog...
//   lanemap-city --store S --osm city.osm --slurm [--slurm-dry-run] [--shards N] DRIVE.lcmlog...
//   lanemap-city --store S --osm city.osm --shards N DRIVE.lcmlog...   (the fusion in N shards of roads)
//
// Two stages over lanemap-offline; with --no-drive-offsets a city's map is the map
// `lanemap-offline --log A --log B ...` makes of the same drives in the same order, byte for byte
// (tested). By default the fusion first solves each drive's own pose offset over the roads drives
// share and moves its grids by it (lanemap-offline --drive-offsets, core/bev/drive_offsets.h):
// `--log` cannot, it maps each drive before it has projected the next.
//   1. projection, one drive a job, N at once: `lanemap-offline --log D --project-only` segments
//      the drive's frames, projects them and keeps what its BEV builder hands over per road
//      (S/projections/NNNN: grids and projection.json). Most of the time goes here.
//   2. fusion, once: `lanemap-offline --traversals S/projections/0000 ... --drive-offsets --out S/map`: every
//      drive's traversals in the store's order, aligned onto the roads' evidence, explored, the
//      junctions built, the map written (S/map: map.osm, map.geojson, map.png, summary.json).
// The store keeps every drive's projection: a later run with new drives projects only those, then
// fuses all of them again (fusion is the cheap stage). A drive already in the store (the same log
// path and size) is not projected twice. One run at a time: a second one on the same store stops
// with an error naming the first (S/.lock). Each projection is written into NNNN.partial and renamed
// when whole; the map into map.partial and swapped in: an interrupted run leaves the store as it
// was before it, plus the projections that finished.
//
// --shards N fuses in N shards of roads: a road's evidence is fused from its own traversals only
// and explored on its own, so each shard (the roads whose id is K modulo N) is fused and explored
// apart (lanemap-offline --shard K/N, N at once on the cores here, or a Slurm array), after the
// drives' offsets were solved once (--offsets-out); then one assembly (lanemap-offline --assemble)
// gives the short roads left with no lane their neighbours' lanes, builds the junctions and writes
// the map: the map one fusion process makes, byte for byte, whatever N (tested), its summary's
// roads in road order. S/fusion holds the steps' work (plan.json, offsets.json, shard-K) until
// the map is in place. `--fuse-step prepare|shard|assemble` runs one step (what the Slurm jobs run).
//
// --slurm writes S/slurm/project.sbatch (an array job, one task per new drive) and fuse.sbatch
// (one task, after the array has succeeded: --dependency=afterok), or with --shards N
// fuse-prepare.sbatch, fuse-shards.sbatch (an array of N) and fuse-assemble.sbatch, each after
// the one before has succeeded, and submits them with sbatch;
// the store, the logs, the OSM file and lanemap's programs must be at the same paths on every
// node (a shared filesystem); a partition or account comes from sbatch's environment
// (SBATCH_PARTITION, SBATCH_ACCOUNT). --slurm-dry-run writes them without submitting.
#include "core/io/atomic_file.h"
#include "processes/framework/share_dir.h"
#include "processes/framework/spawn_logged.h"
#include "tools/cli_checks.h"

#include <CLI/CLI.hpp>
#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct Options {
  std::string store, osm, semantic_channel, model;
  std::vector<std::string> drives;
  int jobs = 0;  // 0: every core
  int shards = 0;  // > 0: the fusion in that many shards of roads, then an assembly (0: one process)
  std::string fuse_step;  // a sharded fusion's step on its own (Slurm's jobs): prepare, shard, assemble
  int shard_index = -1;   // --fuse-step shard: which (else SLURM_ARRAY_TASK_ID)
  bool oracle = false, no_lidar = false, no_align = false, align_rotation = false, drive_offsets = false,
       no_drive_offsets = false, slurm = false, slurm_dry_run = false;
};

// The store's folder of projections: NNNN (whole) in the order the drives were added.
std::vector<fs::path> projections(const fs::path& store) {
  std::vector<fs::path> out;
  const fs::path dir = store / "projections";
  if (!fs::is_directory(dir)) return out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (e.is_directory() && name.size() == 4 && name.find_first_not_of("0123456789") == std::string::npos) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The next free slot number: after every NNNN and NNNN.partial there (a drive that failed to
// project leaves its number unused; a Slurm task still projecting holds its NNNN.partial).
size_t nextSlot(const fs::path& store) {
  size_t next = 0;
  for (const auto& e : fs::directory_iterator(store / "projections")) {
    std::string name = e.path().filename().string();
    if (name.size() == 12 && name.compare(4, 8, ".partial") == 0) name.resize(4);
    if (e.is_directory() && name.size() == 4 && name.find_first_not_of("0123456789") == std::string::npos) {
      next = std::max(next, std::stoul(name) + 1);
    }
  }
  return next;
}

std::string slot(size_t index) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%04zu", index);
  return buf;
}

nlohmann::json manifest(const fs::path& projection) {
  std::ifstream in(projection / "projection.json");
  nlohmann::json m = nlohmann::json::parse(in, nullptr, false);
  return m.is_discarded() ? nlohmann::json::object() : m;
}

// The label options, as lanemap-offline takes them (both stages get the same).
std::vector<std::string> labelArgs(const Options& o) {
  std::vector<std::string> a;
  if (o.oracle) a.push_back("--oracle");
  if (!o.semantic_channel.empty()) a.insert(a.end(), {"--semantic-channel", o.semantic_channel});
  if (!o.model.empty()) a.insert(a.end(), {"--model", o.model});
  if (o.no_lidar) a.push_back("--no-lidar");
  return a;
}

std::string tail(const std::string& path, size_t bytes = 1500) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string s = ss.str();
  return s.size() > bytes ? "..." + s.substr(s.size() - bytes) : s;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string join(const std::vector<std::string>& args) {
  std::string s;
  for (const auto& a : args) s += (s.empty() ? "" : " ") + quote(a);
  return s;
}

// Runs n jobs, at most `jobs` at once: start(i) starts job i (its pid; throws when it cannot),
// done(i, exit code, seconds it ran) is called as each ends, in the order they end.
void runJobs(size_t n, int jobs, const std::function<pid_t(size_t)>& start,
             const std::function<void(size_t, int, double)>& done) {
  std::map<pid_t, std::pair<size_t, Clock::time_point>> running;
  auto reap = [&]() {
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) return;
    const auto [i, t0] = running.at(pid);
    running.erase(pid);
    done(i, lanemap::exitCode(status), std::chrono::duration<double>(Clock::now() - t0).count());
  };
  for (size_t i = 0; i < n; ++i) {
    while (static_cast<int>(running.size()) >= jobs) reap();
    const auto t0 = Clock::now();
    running[start(i)] = {i, t0};
  }
  while (!running.empty()) reap();
}

// Runs args with their output in `log`; the exit code (-1: could not start).
int runLogged(const std::vector<std::string>& args, const std::string& log) {
  const pid_t pid = lanemap::spawnLogged(args, log);
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0) return -1;
  return lanemap::exitCode(status);
}

// Holds S/.lock (flock) for the run: a second run on the store stops with the first one's pid.
class StoreLock {
 public:
  explicit StoreLock(const fs::path& store) {
    const std::string path = (store / ".lock").string();
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT, 0644);
    if (fd_ < 0) throw std::runtime_error("cannot open " + path);
    if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      char buf[32] = {0};
      const ssize_t n = pread(fd_, buf, sizeof(buf) - 1, 0);
      ::close(fd_);
      throw std::runtime_error("the store " + store.string() + " is in use by another lanemap-city (pid " +
                               (n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string("?")) + "); wait for it to end");
    }
    const std::string pid = std::to_string(getpid());
    if (ftruncate(fd_, 0) != 0 || pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
      // the pid is only a courtesy to whoever is refused
    }
  }
  ~StoreLock() { ::close(fd_); }  // releases the lock

 private:
  int fd_ = -1;
};

// A fusion in shards of roads (--shards N): S/fusion/ holds the plan (plan.json: the projections
// and how to fuse them, fixed when it was prepared), the drives' offsets (offsets.json), and each
// shard's roads (shard-K, from shard-K.partial when whole); the assembly builds the map from every
// shard into map.partial, swaps it in and removes S/fusion. Steps: prepare (once), shard K (N of
// them, at once: on the cores here, or as a Slurm array), assemble (once).
class ShardedFusion {
 public:
  ShardedFusion(fs::path store, fs::path offline, std::string osm, std::vector<std::string> labels)
      : store_(std::move(store)), offline_(std::move(offline)), osm_(std::move(osm)), labels_(std::move(labels)) {}

  fs::path dir() const { return store_ / "fusion"; }

  // The plan, and the drives' offsets solved over all of them (when `offsets`).
  void prepare(const std::vector<fs::path>& all, int shards, bool offsets, bool no_align, bool align_rotation) {
    fs::remove_all(dir());
    fs::create_directories(dir());
    nlohmann::json plan = {{"shards", shards},
                           {"offsets", offsets},
                           {"no_align", no_align},
                           {"align_rotation", align_rotation},
                           {"projections", nlohmann::json::array()}};
    for (const auto& p : all) plan["projections"].push_back(p.string());
    lanemap::io::writeFileAtomically((dir() / "plan.json").string(), plan.dump(1) + "\n");
    if (!offsets) return;
    auto a = base(plan);
    a.insert(a.end(), {"--drive-offsets", "--offsets-out", (dir() / "offsets.json").string()});
    const std::string log = (dir() / "prepare.log").string();
    if (runLogged(a, log) != 0) throw std::runtime_error("solving the drives' offsets failed:\n" + tail(log));
  }

  nlohmann::json plan() const {
    std::ifstream in(dir() / "plan.json");
    const nlohmann::json p = nlohmann::json::parse(in, nullptr, false);
    if (p.is_discarded() || !p.contains("shards")) {
      throw std::runtime_error("no sharded fusion is prepared in " + dir().string() + " (its first step, --fuse-step prepare, has not run)");
    }
    return p;
  }

  // Shard k's command (into shard-K.partial) and its log.
  std::vector<std::string> shardArgs(const nlohmann::json& plan, int k) const {
    auto a = base(plan);
    a.insert(a.end(), {"--shard", std::to_string(k) + "/" + std::to_string(plan.at("shards").get<int>()), "--out", partial(k).string()});
    return a;
  }
  fs::path partial(int k) const { return dir() / ("shard-" + std::to_string(k) + ".partial"); }
  fs::path whole(int k) const { return dir() / ("shard-" + std::to_string(k)); }
  std::string log(int k) const { return (dir() / ("shard-" + std::to_string(k) + ".log")).string(); }
  // After shard k's command: whole (renamed into place), or the error.
  void finishShard(int k, int exit_code) const {
    if (exit_code != 0) {
      fs::remove_all(partial(k));
      throw std::runtime_error("shard " + std::to_string(k) + " failed (exit " + std::to_string(exit_code) + "):\n" + tail(log(k)));
    }
    fs::remove_all(whole(k));
    fs::rename(partial(k), whole(k));
  }
  void runShard(int k) const {
    const auto p = plan();
    if (k < 0 || k >= p.at("shards").get<int>()) {
      throw std::runtime_error("no shard " + std::to_string(k) + ": the fusion is prepared in " + std::to_string(p.at("shards").get<int>()) + " shards");
    }
    fs::remove_all(partial(k));
    finishShard(k, runLogged(shardArgs(p, k), log(k)));
  }

  // Every shard into S/map (through map.partial); S/fusion removed after.
  void assemble() const {
    const auto p = plan();
    auto a = base(p);
    for (int k = 0; k < p.at("shards").get<int>(); ++k) {
      if (!fs::exists(whole(k))) throw std::runtime_error("shard " + std::to_string(k) + " has not finished (" + whole(k).string() + "): the map is as it was");
      a.insert(a.end(), {"--assemble", whole(k).string()});
    }
    const fs::path map_dir = store_ / "map", partial_map = store_ / "map.partial", old = store_ / "map.old";
    fs::remove_all(partial_map);
    a.insert(a.end(), {"--out", partial_map.string()});
    const std::string log = (dir() / "assemble.log").string();
    if (runLogged(a, log) != 0) {
      fs::remove_all(partial_map);
      throw std::runtime_error("the assembly failed (the map of the store is as it was):\n" + tail(log));
    }
    fs::remove_all(old);
    if (fs::exists(map_dir)) fs::rename(map_dir, old);
    fs::rename(partial_map, map_dir);
    fs::remove_all(old);
    fs::remove_all(dir());
  }

 private:
  // lanemap-offline over the plan's projections, as the plan says to fuse them.
  std::vector<std::string> base(const nlohmann::json& plan) const {
    std::vector<std::string> a{offline_.string(), "-q", "--osm", osm_};
    for (const auto& p : plan.at("projections")) a.insert(a.end(), {"--traversals", p.get<std::string>()});
    a.insert(a.end(), labels_.begin(), labels_.end());
    if (plan.at("no_align").get<bool>()) a.push_back("--no-align");
    if (plan.value("align_rotation", false)) a.push_back("--align-rotation");  // (a plan of an older version has none)
    if (plan.at("offsets").get<bool>() && fs::exists(dir() / "offsets.json")) {
      a.insert(a.end(), {"--offsets-in", (dir() / "offsets.json").string()});
    }
    return a;
  }
  fs::path store_, offline_;
  std::string osm_;
  std::vector<std::string> labels_;
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"lanemap-city: many drives into one map store, on every core or on a Slurm cluster. Each new drive is\n"
               "projected once (lanemap-offline --project-only, N at once), then every drive of the store is fused\n"
               "into one map (lanemap-offline --traversals, the store's order), after solving each drive's own pose\n"
               "offset over the roads drives share (--drive-offsets; with --no-drive-offsets: the map --log A --log B\n"
               "... makes). --shards N fuses in N shards of roads (here or as Slurm array tasks), then assembles the\n"
               "map: the same map."};
  app.add_option("--store", o.store, "the map store (a folder, created): projections/, map/ (map.osm, map.geojson, ...)")->required();
  app.add_option("--osm", o.osm, "road-level OSM file of the city (.osm or .osm.pbf)")->required()->check(CLI::ExistingFile);
  app.add_option("drives", o.drives, "drive logs (drive.lcmlog, or a folder holding one), added to the store in this order");
  app.add_option("-j,--jobs", o.jobs, "drives projected at once (default: every core)")->check(lanemap::cli::kNonNegative);
  auto* oracle = app.add_flag("--oracle", o.oracle, "map on the simulator's truth labels (as lanemap-offline)");
  app.add_option("--semantic-channel", o.semantic_channel, "map on the labels of this channel of the logs")->excludes(oracle);
  app.add_option("--model", o.model, "ONNX model, instead of config/segmenter.yaml's");
  app.add_flag("--no-lidar", o.no_lidar, "project on the flat plane only");
  auto* no_align = app.add_flag("--no-align", o.no_align,
                                "fuse later drives unaligned, each drive's offset not solved either (to see what alignment removes)");
  app.add_flag("--align-rotation", o.align_rotation,
               "align by a shift and a small rotation, not a shift only (lanemap-offline --align-rotation)")
      ->excludes(no_align);
  auto* no_offsets = app.add_flag("--no-drive-offsets", o.no_drive_offsets,
                                  "fuse without solving each drive's own pose offset first: the map lanemap-offline --log A --log B ...\n"
                                  "makes, byte for byte");
  app.add_flag("--drive-offsets", o.drive_offsets,
               "solve each drive's own pose offset over the roads drives share before fusing (lanemap-offline\n"
               "--drive-offsets; the default, unless --no-align)")
      ->excludes(no_align)
      ->excludes(no_offsets);
  app.add_option("--shards", o.shards,
                 "fuse in N shards of roads (each shard's roads aligned, fused and explored apart, N at a time here or as\n"
                 "a Slurm array), then assemble the map: the same map as one process, whatever N")
      ->check(CLI::PositiveNumber);
  app.add_option("--fuse-step", o.fuse_step,
                 "run one step of a sharded fusion of the store's drives and stop (what --slurm's jobs run): prepare\n"
                 "(needs --shards), shard (--shard-index, else SLURM_ARRAY_TASK_ID), assemble")
      ->check(CLI::IsMember({"prepare", "shard", "assemble"}));
  app.add_option("--shard-index", o.shard_index, "--fuse-step shard: the shard to fuse (0 .. N-1)")->check(lanemap::cli::kNonNegative);
  auto* slurm = app.add_flag("--slurm", o.slurm, "write the jobs for Slurm (S/slurm/*.sbatch) and submit them with sbatch");
  app.add_flag("--slurm-dry-run", o.slurm_dry_run, "with --slurm: write the job scripts, do not submit")->needs(slurm);
  CLI11_PARSE(app, argc, argv);

  try {
    const auto t0 = Clock::now();
    const fs::path store = fs::absolute(o.store);
    fs::create_directories(store / "projections");
    const fs::path offline = lanemap::executableDir() / "lanemap-offline";
    const fs::path self = lanemap::executableDir() / "lanemap-city";
    const std::string osm = fs::absolute(o.osm).string();
    if (!o.model.empty() && fs::exists(o.model)) o.model = fs::absolute(o.model).string();  // jobs may run elsewhere
    const auto labels = labelArgs(o);
    // Each drive's own offset, solved over the roads drives share (core/bev/drive_offsets.h): on
    // unless asked not to, or unless the drives are fused unaligned.
    const bool offsets = !o.no_drive_offsets && !o.no_align;
    ShardedFusion sharded(store, offline, osm, labels);
    if (!o.fuse_step.empty()) {  // one step of a sharded fusion (a Slurm job's)
      if (!o.drives.empty()) throw std::runtime_error("--fuse-step fuses the store's drives: give no drive logs");
      if (o.fuse_step == "shard") {  // shards run at once: no lock (each writes its own folder)
        int k = o.shard_index;
        if (k < 0 && std::getenv("SLURM_ARRAY_TASK_ID")) k = std::atoi(std::getenv("SLURM_ARRAY_TASK_ID"));
        if (k < 0) throw std::runtime_error("--fuse-step shard: which shard? give --shard-index (or run it as a Slurm array task)");
        sharded.runShard(k);
        std::printf("lanemap-city: shard %d fused into %s\n", k, sharded.whole(k).c_str());
        return 0;
      }
      StoreLock lock(store);
      if (o.fuse_step == "prepare") {
        if (o.shards < 1) throw std::runtime_error("--fuse-step prepare: give --shards N");
        const auto all = projections(store);
        if (all.empty()) throw std::runtime_error("the store has no projected drive to fuse");
        sharded.prepare(all, o.shards, offsets, o.no_align, o.align_rotation);
        std::printf("lanemap-city: a fusion of %zu drives in %d shards prepared in %s\n", all.size(), o.shards, sharded.dir().c_str());
      } else {
        sharded.assemble();
        std::printf("lanemap-city: the shards assembled into %s\n", (store / "map").c_str());
      }
      return 0;
    }
    StoreLock lock(store);

    // The drives not in the store yet (by absolute path and size), each with its new slot.
    std::vector<fs::path> have = projections(store);
    std::map<std::pair<std::string, int64_t>, fs::path> known;
    for (const auto& p : have) {
      const auto m = manifest(p);
      if (m.contains("log")) known[{m["log"].get<std::string>(), m["log_read"].value("bytes", int64_t{0})}] = p;
    }
    std::vector<std::pair<std::string, fs::path>> todo;  // log, its projection folder
    const size_t first_slot = nextSlot(store);
    for (const auto& d : o.drives) {
      const fs::path log = fs::absolute(fs::is_directory(d) ? fs::path(d) / "drive.lcmlog" : fs::path(d));
      if (!fs::is_regular_file(log)) throw std::runtime_error("no such drive log: " + log.string());
      const auto key = std::make_pair(log.string(), static_cast<int64_t>(fs::file_size(log)));
      if (known.count(key)) {
        std::printf("lanemap-city: %s is in the store already (%s)\n", log.c_str(), known[key].filename().c_str());
        continue;
      }
      known[key] = store / "projections" / slot(first_slot + todo.size());
      todo.emplace_back(log.string(), known[key]);
    }
    if (have.empty() && todo.empty()) throw std::runtime_error("no drive: give drive logs (the store has none yet)");
    auto projectArgs = [&](const std::string& log, const std::string& folder) {
      std::vector<std::string> a{offline.string(), "-q", "--osm", osm, "--log", log, "--project-only", folder};
      a.insert(a.end(), labels.begin(), labels.end());
      return a;
    };
    auto fuseArgs = [&](const std::vector<fs::path>& all, const std::string& out) {
      std::vector<std::string> a{offline.string(), "-q", "--osm", osm, "--out", out};
      for (const auto& p : all) a.insert(a.end(), {"--traversals", p.string()});
      a.insert(a.end(), labels.begin(), labels.end());
      if (o.no_align) a.push_back("--no-align");
      if (o.align_rotation) a.push_back("--align-rotation");
      if (offsets) a.push_back("--drive-offsets");
      return a;
    };

    if (o.slurm) {
      // One array task per new drive (project into NNNN.partial, rename when whole), then the
      // fusion, which waits for the whole array to succeed (afterok).
      const fs::path dir = store / "slurm";
      fs::create_directories(dir);
      std::ofstream p(dir / "project.sbatch");
      p << "#!/bin/bash\n#SBATCH --job-name=lanemap-project\n#SBATCH --output=" << (dir / "project-%a.log").string() << "\n"
        << "#SBATCH --cpus-per-task=2\n";
      if (!todo.empty()) p << "#SBATCH --array=0-" << todo.size() - 1 << "\n";
      p << "set -euo pipefail\ncase \"$SLURM_ARRAY_TASK_ID\" in\n";
      for (size_t i = 0; i < todo.size(); ++i) {
        const std::string folder = todo[i].second.string();
        fs::create_directories(folder + ".partial");  // holds the slot until the task has run
        p << "  " << i << ") rm -rf " << quote(folder + ".partial") << " && " << join(projectArgs(todo[i].first, folder + ".partial"))
          << " && mv " << quote(folder + ".partial") << " " << quote(folder) << " ;;\n";
      }
      p << "  *) echo \"no drive for task $SLURM_ARRAY_TASK_ID\" >&2; exit 2 ;;\nesac\n";
      p.close();
      // The fusion: one job (fuse.sbatch), or with --shards N a chain: fuse-prepare.sbatch (the
      // plan and the drives' offsets), fuse-shards.sbatch (an array, one task per shard), then
      // fuse-assemble.sbatch, each after the one before has succeeded.
      const std::string city = join({self.string(), "--store", store.string(), "--osm", osm}) + (labels.empty() ? "" : " " + join(labels)) +
                               (o.no_align ? " --no-align" : "") + (o.align_rotation ? " --align-rotation" : "") +
                               (o.no_drive_offsets ? " --no-drive-offsets" : "");
      auto script = [&](const std::string& name, const std::string& array, const std::string& command) {
        std::ofstream f(dir / (name + ".sbatch"));
        f << "#!/bin/bash\n#SBATCH --job-name=lanemap-" << name << "\n#SBATCH --output="
          << (dir / (name + (array.empty() ? ".log" : "-%a.log"))).string() << "\n#SBATCH --cpus-per-task=2\n"
          << (array.empty() ? "" : "#SBATCH --array=" + array + "\n") << "set -euo pipefail\n" << command << "\n";
      };
      std::vector<std::string> fusion_jobs;
      if (o.shards > 0) {
        script("fuse-prepare", "", city + " --shards " + std::to_string(o.shards) + " --fuse-step prepare");
        script("fuse-shards", "0-" + std::to_string(o.shards - 1), city + " --fuse-step shard");
        script("fuse-assemble", "", city + " --fuse-step assemble");
        fusion_jobs = {"fuse-prepare", "fuse-shards", "fuse-assemble"};
      } else {
        script("fuse", "", city);
        fusion_jobs = {"fuse"};
      }
      std::printf("lanemap-city: wrote %s (%zu drive%s)", (dir / "project.sbatch").c_str(), todo.size(), todo.size() == 1 ? "" : "s");
      for (const auto& j : fusion_jobs) std::printf(" and %s", (dir / (j + ".sbatch")).c_str());
      std::printf("\n");
      if (o.slurm_dry_run) return 0;
      std::string dependency;
      if (!todo.empty()) {
        FILE* pipe = popen(("sbatch --parsable " + quote((dir / "project.sbatch").string())).c_str(), "r");
        char buf[128] = {0};
        const bool got = pipe && std::fgets(buf, sizeof(buf), pipe);
        const int rc = pipe ? pclose(pipe) : -1;
        if (!got || rc != 0) throw std::runtime_error("sbatch could not submit " + (dir / "project.sbatch").string() + " (is Slurm installed and running?)");
        std::string id = buf;
        id = id.substr(0, id.find_first_of(";\n"));
        dependency = "--dependency=afterok:" + id + " ";
        std::printf("lanemap-city: projection array job %s\n", id.c_str());
      }
      for (const auto& j : fusion_jobs) {
        const std::string path = (dir / (j + ".sbatch")).string();
        FILE* pipe = popen(("sbatch --parsable " + dependency + quote(path)).c_str(), "r");
        char buf[128] = {0};
        const bool got = pipe && std::fgets(buf, sizeof(buf), pipe);
        const int rc = pipe ? pclose(pipe) : -1;
        if (!got || rc != 0) throw std::runtime_error("sbatch could not submit " + path);
        std::string id = buf;
        id = id.substr(0, id.find_first_of(";\n"));
        dependency = "--dependency=afterok:" + id + " ";
        std::printf("lanemap-city: %s job %s\n", j.c_str(), id.c_str());
      }
      return 0;
    }

    // 1. Projection, `jobs` drives at once.
    const int jobs = o.jobs > 0 ? o.jobs : std::max(1u, std::thread::hardware_concurrency());
    std::vector<double> seconds(todo.size(), 0.0);
    int failed = 0;
    const auto p0 = Clock::now();
    runJobs(todo.size(), jobs, [&](size_t i) {
      const std::string partial = todo[i].second.string() + ".partial";
      fs::remove_all(partial);
      fs::create_directories(partial);
      const pid_t pid = lanemap::spawnLogged(projectArgs(todo[i].first, partial), partial + ".log");
      if (pid < 0) throw std::runtime_error("cannot start " + offline.string());
      return pid;
    }, [&](size_t i, int exit_code, double s) {
      seconds[i] = s;
      const std::string partial = todo[i].second.string() + ".partial";
      if (exit_code == 0) {
        fs::rename(partial + ".log", fs::path(partial) / "project.log");
        fs::rename(partial, todo[i].second);
        std::printf("lanemap-city: projected %s (%.1f s) -> %s\n", todo[i].first.c_str(), seconds[i], todo[i].second.filename().c_str());
      } else {
        ++failed;
        std::fprintf(stderr, "lanemap-city: %s could not be projected (exit %d), not added (%s):\n%s\n", todo[i].first.c_str(),
                     exit_code, (partial + ".log").c_str(), tail(partial + ".log").c_str());
        fs::remove_all(partial);
      }
      std::fflush(stdout);
    });
    const double projection_wall = std::chrono::duration<double>(Clock::now() - p0).count();
    double projection_sum = 0.0;
    for (double s : seconds) projection_sum += s;
    if (!todo.empty()) {
      std::printf("lanemap-city: %zu drive%s projected in %.1f s wall on %d job%s (the drives' own times add up to %.1f s)\n",
                  todo.size() - failed, todo.size() - failed == 1 ? "" : "s", projection_wall, jobs, jobs == 1 ? "" : "s", projection_sum);
    }

    // 2. Fusion of every drive in the store, into map.partial, swapped in when whole.
    const std::vector<fs::path> all = projections(store);
    if (all.empty()) throw std::runtime_error("no drive of the store could be projected");
    const fs::path map_dir = store / "map", partial = store / "map.partial", old = store / "map.old";
    fs::remove_all(partial);
    const auto f0 = Clock::now();
    if (o.shards > 0) {  // prepare, the shards `jobs` at a time, assemble
      sharded.prepare(all, o.shards, offsets, o.no_align, o.align_rotation);
      const auto plan = sharded.plan();
      std::vector<double> shard_s(o.shards, 0.0);
      std::string first_error;
      runJobs(static_cast<size_t>(o.shards), jobs, [&](size_t k) {
        fs::remove_all(sharded.partial(static_cast<int>(k)));
        const pid_t pid = lanemap::spawnLogged(sharded.shardArgs(plan, static_cast<int>(k)), sharded.log(static_cast<int>(k)));
        if (pid < 0) throw std::runtime_error("cannot start " + offline.string());
        return pid;
      }, [&](size_t k, int exit_code, double s) {
        shard_s[k] = s;
        try {
          sharded.finishShard(static_cast<int>(k), exit_code);
        } catch (const std::exception& e) {
          if (first_error.empty()) first_error = e.what();
        }
      });
      if (!first_error.empty()) throw std::runtime_error(first_error + "\n(the map of the store is as it was)");
      double sum = 0.0;
      for (double v : shard_s) sum += v;
      const double shards_wall = std::chrono::duration<double>(Clock::now() - f0).count();
      sharded.assemble();
      std::printf("lanemap-city: %zu drive%s fused in %d shards on %d job%s (%.1f s wall with the offsets solved first, the "
                  "shards' own times add up to %.1f s), assembled in %.1f s into %s; %.1f s in all\n",
                  all.size(), all.size() == 1 ? "" : "s", o.shards, jobs, jobs == 1 ? "" : "s", shards_wall, sum,
                  std::chrono::duration<double>(Clock::now() - f0).count() - shards_wall, map_dir.c_str(),
                  std::chrono::duration<double>(Clock::now() - t0).count());
      return failed > 0 ? 1 : 0;
    }
    const pid_t pid = lanemap::spawnLogged(fuseArgs(all, partial.string()), (store / "fuse.log").string());
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) < 0 || lanemap::exitCode(status) != 0) {
      fs::remove_all(partial);
      throw std::runtime_error("the fusion failed (the map of the store is as it was):\n" + tail((store / "fuse.log").string()));
    }
    fs::remove_all(old);
    if (fs::exists(map_dir)) fs::rename(map_dir, old);
    fs::rename(partial, map_dir);
    fs::remove_all(old);
    std::printf("lanemap-city: %zu drive%s fused in %.1f s into %s (map.osm, map.geojson, map.png, summary.json); %.1f s in all\n",
                all.size(), all.size() == 1 ? "" : "s", std::chrono::duration<double>(Clock::now() - f0).count(), map_dir.c_str(),
                std::chrono::duration<double>(Clock::now() - t0).count());
    return failed > 0 ? 1 : 0;
  } catch (const std::exception& e) {
    std::cerr << "lanemap-city: " << e.what() << "\n";
    return 2;
  }
}
