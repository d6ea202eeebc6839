// lanemap-sim end to end: a short drive over the real West Oakland street network. Checks the
// files, the channels and their rates, determinism, and the simulator's geometry: truth labels
// where the true lane projects into the image, LIDAR ground returns on the true surface.
#include "core/camera/camera_model.h"
#include "core/config/map_config.h"
#include "core/io/lanelet2.h"
#include "core/lidar/velodyne.h"
#include "core/osm/osm_data.h"
#include "core/sim/drive.h"
#include "core/sim/lidar_scanner.h"
#include "core/sim/simulator.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/pose_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/process.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

namespace {

using namespace lanemap;
using namespace lanemap::testing;
namespace fs = std::filesystem;

constexpr double kDuration = 12.0;
constexpr uint64_t kSeed = 7;

// The drive of this file, simulated once; and the same world rebuilt in-process, which the
// simulator must reproduce exactly for the seed.
struct Drive {
  std::string dir;
  osm::OsmData osm;
  std::unique_ptr<skeleton::Skeleton> sk;
  std::unique_ptr<sim::SimWorld> world;
  sim::LanePlan plan;
  std::unique_ptr<sim::Trajectory> trajectory;
  sim::DriveOptions drive;
  std::unique_ptr<camera::CameraModel> camera;
  sim::LidarScannerOptions lidar;
  std::string out() const { return dir; }
};

Drive* g_drive = nullptr;

class SimDrive : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    g_drive = new Drive;
    Drive& d = *g_drive;
    d.dir = sharedSimDrive("osm/west-oakland.osm", kDuration, kSeed);
    d.osm = osm::readOsm(dataPath("osm/west-oakland.osm"));
    d.sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(d.osm));
    auto wopt = sim::WorldOptions::fromYaml(loadYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/sim_world.yaml"));
    wopt.seed = kSeed;
    d.world = sim::buildWorld(*d.sk, wopt, d.osm.restrictions);  // as lanemap-sim builds it
    d.drive = sim::DriveOptions::fromYaml(loadYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/sim_drive.yaml")["drive"]);
    d.drive.seed = kSeed;
    d.drive.duration_s = kDuration;
    d.plan = sim::planDrive(*d.sk, d.world->truth(), d.drive);
    d.trajectory = std::make_unique<sim::Trajectory>(d.world->truth(), *d.world, d.plan, d.drive);
    const YAML::Node vehicle = loadYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/vehicle.yaml");
    d.camera = std::make_unique<camera::CameraModel>(camera::CameraModel::fromYaml(vehicle["camera"]));
    d.lidar = sim::LidarScannerOptions::fromYaml(vehicle["lidar"]);
  }
  static void TearDownTestSuite() {
    delete g_drive;
    g_drive = nullptr;
  }
};

struct LogChannel {
  std::vector<std::vector<uint8_t>> messages;
  std::vector<int64_t> timestamps;
};

std::map<std::string, LogChannel> readLog(const std::string& path, bool* monotonic) {
  std::map<std::string, LogChannel> out;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  int64_t last = 0;
  *monotonic = true;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->timestamp < last) *monotonic = false;
    last = ev->timestamp;
    auto& c = out[ev->channel];
    const auto* p = static_cast<const uint8_t*>(ev->data);
    c.messages.emplace_back(p, p + ev->datalen);
    c.timestamps.push_back(ev->timestamp);
  }
  return out;
}

template <typename T>
T decode(const std::vector<uint8_t>& buf) {
  T msg;
  EXPECT_GT(msg.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  return msg;
}

TEST_F(SimDrive, WritesEveryOutputFile) {
  for (const char* f : {"drive.lcmlog", "groundtruth.osm", "groundtruth.png", "roads.osm", "trajectory.csv", "scenario.json"}) {
    EXPECT_TRUE(fs::exists(fs::path(g_drive->out()) / f)) << f;
  }
  std::ifstream js(fs::path(g_drive->out()) / "scenario.json");
  nlohmann::json scenario;
  js >> scenario;
  EXPECT_EQ(scenario["seed"].get<uint64_t>(), kSeed);
  EXPECT_EQ(scenario["planned_route"].get<std::vector<int64_t>>(), g_drive->plan.roads);
  // The driven route is a prefix of the plan; each road is entered when the true motion is on it,
  // and every road but possibly the last is left before the drive ends.
  const auto& route = scenario["route"];
  ASSERT_GE(route.size(), 1u);
  ASSERT_LE(route.size(), g_drive->plan.roads.size());
  const int64_t t0 = scenario["start_utime"].get<int64_t>();
  for (size_t i = 0; i < route.size(); ++i) {
    EXPECT_EQ(route[i]["road_id"].get<int64_t>(), g_drive->plan.roads[i]) << i;
    const double t_in = (route[i]["entered_utime"].get<int64_t>() - t0) * 1e-6;
    EXPECT_EQ(g_drive->trajectory->at(t_in).road_id, route[i]["road_id"].get<int64_t>()) << i;
    if (i + 1 < route.size()) {
      ASSERT_FALSE(route[i]["left_utime"].is_null()) << i;
      const double t_out = (route[i]["left_utime"].get<int64_t>() - t0) * 1e-6;
      EXPECT_GT(t_out, t_in);
      EXPECT_NE(g_drive->trajectory->at(t_out).road_id, route[i]["road_id"].get<int64_t>()) << i;
    }
  }
  EXPECT_NEAR(scenario["duration_s"].get<double>(), g_drive->trajectory->duration(), 1e-6);
}

TEST_F(SimDrive, LogHasEveryChannelAtItsRateInTimeOrder) {
  bool monotonic = false;
  const auto log = readLog(g_drive->out() + "/drive.lcmlog", &monotonic);
  EXPECT_TRUE(monotonic) << "log timestamps go backwards";
  const double T = g_drive->trajectory->duration();
  ASSERT_GT(T, 5.0);
  // Rates from the registry; counts over the drive within one period.
  for (const char* ch : {channels::kPose, channels::kCameraFront, channels::kSemanticFrontTruth, channels::kLidarPackets}) {
    ASSERT_TRUE(log.count(ch)) << ch;
    const double rate = channels::find(ch)->rate_hz;
    EXPECT_NEAR(static_cast<double>(log.at(ch).messages.size()), T * rate, 1.5) << ch;
    const auto& ts = log.at(ch).timestamps;
    const double measured = (ts.size() - 1) / ((ts.back() - ts.front()) * 1e-6);
    EXPECT_NEAR(measured, rate, 0.02 * rate) << ch;
  }
  // Camera frames and truth labels pair up by utime and seq.
  const auto& cams = log.at(channels::kCameraFront).messages;
  const auto& labs = log.at(channels::kSemanticFrontTruth).messages;
  ASSERT_EQ(cams.size(), labs.size());
  for (size_t i = 0; i < cams.size(); ++i) {
    const auto img = decode<image_t>(cams[i]);
    const auto lab = decode<label_image_t>(labs[i]);
    EXPECT_EQ(img.utime, lab.utime);
    EXPECT_EQ(img.seq, static_cast<int64_t>(i));
    EXPECT_EQ(img.pixelformat, +image_t::PIXEL_FORMAT_JPEG);
    EXPECT_EQ(img.width, g_drive->camera->width());
    EXPECT_EQ(lab.encoding, +label_image_t::ENCODING_PNG);
  }
  // A VLP-16 at 600 rpm sends 754 packets/s: 75 or 76 per sweep.
  for (const auto& buf : log.at(channels::kLidarPackets).messages) {
    const auto pk = decode<lidar_packets_t>(buf);
    EXPECT_GE(pk.num_packets, 75);
    EXPECT_LE(pk.num_packets, 76);
    EXPECT_EQ(pk.packet_size, lidar::kDataPacketSize);
  }
}

TEST_F(SimDrive, PosesFollowTheTrueTrajectoryWithinTheNoise) {
  bool monotonic = false;
  const auto log = readLog(g_drive->out() + "/drive.lcmlog", &monotonic);
  const auto& poses = log.at(channels::kPose).messages;
  const int64_t start = decode<pose_t>(poses.front()).utime;
  double max_err = 0.0;
  for (size_t i = 0; i < poses.size(); i += 10) {
    const auto p = decode<pose_t>(poses[i]);
    const Eigen::Vector3d enu = g_drive->sk->frame().toEnu(p.latitude, p.longitude, p.altitude);
    const auto st = g_drive->trajectory->at((p.utime - start) * 1e-6);
    max_err = std::max(max_err, (enu - st.vehicle_to_enu.translation()).head<2>().norm());
  }
  // Default noise: 3 cm white + 10 cm (1 sigma) wandering bias: 5 sigma bound.
  EXPECT_LT(max_err, 0.6);
  EXPECT_GT(max_err, 0.001) << "poses carry no noise at all";
}

TEST_F(SimDrive, TruthLabelsAgreeWithWhereTheEgoLaneProjects) {
  bool monotonic = false;
  const auto log = readLog(g_drive->out() + "/drive.lcmlog", &monotonic);
  const auto& labs = log.at(channels::kSemanticFrontTruth).messages;
  const int64_t start = decode<label_image_t>(labs.front()).utime;
  int checked = 0, agree = 0;
  for (const auto& buf : labs) {
    const auto lab = decode<label_image_t>(buf);
    const cv::Mat labels = cv::imdecode(lab.data, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(labels.type(), CV_8UC1);
    const auto st = g_drive->trajectory->at((lab.utime - start) * 1e-6);
    if (st.road_id < 0) continue;  // inside an intersection: no ego lane
    const map::Lanelet* ego = g_drive->world->truth().lanelet(st.lanelet);
    ASSERT_NE(ego, nullptr);
    const Eigen::Isometry3d enu_to_vehicle = st.vehicle_to_enu.inverse();
    for (const auto& c : ego->centre) {
      Eigen::Vector3d p(c.x(), c.y(), g_drive->world->height(c.x(), c.y()));
      const Eigen::Vector3d v = enu_to_vehicle * p;
      if (v.x() < 8.0 || v.x() > 25.0) continue;  // ahead, in the camera's near field
      const auto px = g_drive->camera->projectVehicle(v);
      if (!px || !g_drive->camera->inImage(*px)) continue;
      const int u = static_cast<int>(std::lround(px->x())), w = static_cast<int>(std::lround(px->y()));
      ++checked;
      const int label = labels.at<uint8_t>(w, u);
      // The centre of the ego lane is ego-lane asphalt, unless a car stands on it or paint (a
      // stop line, a crosswalk) crosses it.
      if (label == static_cast<int>(sim::LabelClass::kLaneEgo) || label == static_cast<int>(sim::LabelClass::kStopLine) ||
          label == static_cast<int>(sim::LabelClass::kCrosswalk)) {
        ++agree;
      }
    }
  }
  ASSERT_GT(checked, 20);
  EXPECT_GE(agree, 0.9 * checked) << agree << " of " << checked;
}

TEST_F(SimDrive, LidarGroundReturnsLieOnTheTrueSurface) {
  bool monotonic = false;
  const auto log = readLog(g_drive->out() + "/drive.lcmlog", &monotonic);
  const auto& sweeps = log.at(channels::kLidarPackets).messages;
  const int64_t start = decode<pose_t>(log.at(channels::kPose).messages.front()).utime;
  std::vector<double> residuals;
  for (size_t k = 0; k < sweeps.size(); k += 5) {
    const auto msg = decode<lidar_packets_t>(sweeps[k]);
    for (int i = 0; i < msg.num_packets; ++i) {
      std::vector<lidar::LidarPoint> pts;
      ASSERT_EQ(lidar::decodePacket(msg.data[i].data(), msg.data[i].size(), std::nullopt, pts), lidar::DecodeStatus::kOk);
      for (const auto& p : pts) {
        // Lowest lasers only, and near: these see the road surface unless a car is in the way.
        if (p.ring > 2) continue;
        const double t = (msg.packet_utime[i] - start) * 1e-6 + p.time_offset_s;
        const Eigen::Isometry3d T = g_drive->trajectory->at(t).vehicle_to_enu * g_drive->lidar.mount;
        const Eigen::Vector3d q = T * Eigen::Vector3d(p.x, p.y, p.z);
        residuals.push_back(q.z() - g_drive->world->height(q.x(), q.y()));
      }
    }
  }
  ASSERT_GT(residuals.size(), 1000u);
  const size_t on_ground = static_cast<size_t>(std::count_if(residuals.begin(), residuals.end(),
                                                              [](double r) { return std::abs(r) < 0.08; }));
  // Range noise is 2 cm; most low-laser returns hit the ground, the rest parked cars and buildings.
  EXPECT_GT(on_ground, 0.8 * residuals.size()) << on_ground << " of " << residuals.size();
  std::nth_element(residuals.begin(), residuals.begin() + residuals.size() / 2, residuals.end());
  EXPECT_LT(std::abs(residuals[residuals.size() / 2]), 0.02);
}

TEST_F(SimDrive, GroundTruthMapReadsBackWithEveryLanelet) {
  const auto& truth = g_drive->world->truth();
  const auto back = io::readLanelet2(g_drive->out() + "/groundtruth.osm", truth.origin_lat, truth.origin_lon);
  EXPECT_EQ(back.lanelets.size(), truth.lanelets.size());
  // The file's geometry is the truth simplified by 1 cm, with points closer than 5 cm merged into
  // one node (Lanelet2's points_too_close; also across lines, e.g. the nearly common start of two
  // intersection lanelets' bounds): every truth point of every line lies within 1.2 cm + 5 cm of
  // the line read back (measured: 3.6 cm at most on this drive, line 405).
  size_t truth_points = 0, file_points = 0;
  for (const auto& t : truth.lines) {
    const auto* b = back.line(t.id);
    ASSERT_NE(b, nullptr) << "line " << t.id;
    truth_points += t.points.size();
    file_points += b->points.size();
    for (const auto& p : t.points) {
      double best = 1e300;
      for (size_t i = 0; i + 1 < b->points.size(); ++i) {
        const Eigen::Vector3d ab = b->points[i + 1] - b->points[i];
        const double u = ab.squaredNorm() > 0 ? std::clamp((p - b->points[i]).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
        best = std::min(best, (p - (b->points[i] + u * ab)).head<2>().norm());
      }
      ASSERT_LT(best, 0.062) << "line " << t.id;
    }
  }
  EXPECT_LT(file_points * 2, truth_points) << "simplification should at least halve the nodes";
  size_t road = 0;
  for (const auto& l : back.lanelets) road += l.kind == map::LaneletKind::kRoad;
  EXPECT_GT(road, 0u);
  // roads.osm is the road-level map: the same drivable ways, without lane tags.
  const auto roads = osm::readOsm(g_drive->out() + "/roads.osm");
  EXPECT_EQ(roads.ways.size(), g_drive->osm.ways.size());
  for (const auto& w : roads.ways) {
    EXPECT_EQ(w.tags.count("lanes"), 0u) << w.id;
    EXPECT_EQ(w.tags.count("turn:lanes"), 0u) << w.id;
  }
}

// The shared drive ran with the default --threads (the cores); the same drive on one thread must be
// the same files, byte for byte.
TEST_F(SimDrive, IsDeterministicForASeedWhateverTheThreads) {
  TempDir again("simtool-again");
  const auto r = runCommand(binPath("lanemap-sim") + " -q --osm " + dataPath("osm/west-oakland.osm") +
                            " --out " + again.str("drive") + " --duration " + std::to_string(kDuration) +
                            " --seed " + std::to_string(kSeed) + " --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"drive.lcmlog", "groundtruth.osm", "trajectory.csv", "scenario.json", "roads.osm"}) {
    const auto a = runCommand("cmp " + g_drive->out() + "/" + f + " " + again.str("drive") + "/" + f);
    EXPECT_EQ(a.exit_code, 0) << f << ": " << a.output;
  }
}

// Every measurement a Simulator emits, as bytes, in the order the sink got them.
class RecordingSink : public sim::SensorSink {
 public:
  std::vector<std::string> events;
  int poses = 0, frames = 0, sweeps = 0;
  void onPose(const sim::PoseMeasurement& m) override {
    std::ostringstream s;
    s.precision(17);
    s << "pose " << m.utime << ' ' << m.wgs84.lat << ' ' << m.wgs84.lon << ' ' << m.wgs84.alt << ' '
      << m.orientation.coeffs().transpose() << ' ' << m.velocity_enu.transpose();
    events.push_back(s.str());
    ++poses;
  }
  void onCamera(const sim::CameraMeasurement& m) override {
    events.push_back("camera " + std::to_string(m.utime) + " " + std::to_string(m.seq) + " " +
                     std::string(m.jpeg.begin(), m.jpeg.end()) + "|" + std::string(m.labels_png.begin(), m.labels_png.end()));
    ++frames;
  }
  void onLidar(const sim::LidarMeasurement& m) override {
    std::string e = "lidar " + std::to_string(m.utime) + " " + std::to_string(m.publish_utime);
    for (const auto& p : m.packets) e.append(reinterpret_cast<const char*>(p.data()), p.size());
    for (const int64_t u : m.packet_utime) e += " " + std::to_string(u);
    events.push_back(e);
    ++sweeps;
  }
};

// Frames and sweeps rendered on a pool of workers (ahead of the one emitted) reach the sink in time
// order and are the same bytes as on the calling thread alone.
TEST_F(SimDrive, SimulatorEmitsTheSameBytesInTheSameOrderOnOneThreadAndOnFour) {
  sim::DriveOptions drive = g_drive->drive;
  drive.duration_s = 1.0;
  const sim::Trajectory trajectory(g_drive->world->truth(), *g_drive->world, g_drive->plan, drive);
  sim::SimulatorOptions options;
  options.seed = kSeed;
  RecordingSink one, four;
  options.threads = 1;
  sim::Simulator(*g_drive->world, trajectory, g_drive->sk->frame(), *g_drive->camera, sim::RenderOptions(),
                 g_drive->lidar, options)
      .run(one);
  options.threads = 4;
  sim::Simulator(*g_drive->world, trajectory, g_drive->sk->frame(), *g_drive->camera, sim::RenderOptions(),
                 g_drive->lidar, options)
      .run(four);
  // 1 s at 100 Hz poses, 10 Hz camera (t = 0 included), 10 Hz sweeps (emitted at their end).
  EXPECT_EQ(one.poses, 101);
  EXPECT_EQ(one.frames, 11);
  EXPECT_EQ(one.sweeps, 10);
  EXPECT_EQ(four.poses, one.poses);
  EXPECT_EQ(four.frames, one.frames);
  EXPECT_EQ(four.sweeps, one.sweeps);
  ASSERT_EQ(one.events.size(), four.events.size());
  int differing = 0;
  for (size_t i = 0; i < one.events.size(); ++i) {
    if (one.events[i] != four.events[i]) {
      ADD_FAILURE() << "event " << i << " differs: " << one.events[i].substr(0, 40) << " vs "
                    << four.events[i].substr(0, 40);
      if (++differing > 5) break;
    }
  }
  // Real renders: the first and last frames are different pictures of some size.
  std::vector<std::string> frames;
  for (const auto& e : one.events)
    if (e.rfind("camera ", 0) == 0) frames.push_back(e);
  ASSERT_GE(frames.size(), 2u);
  EXPECT_NE(frames.front(), frames.back());
  EXPECT_GT(frames.front().size(), 20000u);
}

// The truth of a network with OSM turn restrictions (Kingsway: dual carriageways meeting) has no
// lanelet for a forbidden turn: lanemap-sim builds its world with the file's restrictions, as the
// same world rebuilt in-process with them, and fewer intersection lanelets than without them.
TEST(SimTool, TruthLeavesOutTheTurnsTheOsmRestrictionsForbid) {
  TempDir dir("simrestr");
  const std::string osm_path = dataPath("osm/dev/kingsway_junction.osm");
  const auto r = runCommand(binPath("lanemap-sim") + " -q --no-lidar --osm " + osm_path + " --out " + dir.str("out") +
                            " --duration 1 --seed 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto scenario = nlohmann::json::parse(std::ifstream(dir.str("out") + "/scenario.json"));
  const osm::OsmData data = osm::readOsm(osm_path);
  ASSERT_FALSE(data.restrictions.empty());
  const skeleton::Skeleton sk = skeleton::Skeleton::build(
      data, config::MapConfig::fromYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/map.yaml").skeleton);
  auto wopt = sim::WorldOptions::fromYaml(loadYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/sim_world.yaml"));
  wopt.seed = 1;
  const auto with = sim::buildWorld(sk, wopt, data.restrictions);
  const auto without = sim::buildWorld(sk, wopt);
  EXPECT_GT(with->stats().turns_restricted, 0u);
  EXPECT_EQ(scenario.at("turns_restricted").get<size_t>(), with->stats().turns_restricted);
  EXPECT_EQ(without->stats().turns_restricted, 0u);
  const auto intersectionLanelets = [](const map::LaneMap& m) {
    return std::count_if(m.lanelets.begin(), m.lanelets.end(),
                         [](const map::Lanelet& l) { return l.kind == map::LaneletKind::kIntersection; });
  };
  const auto written = io::readLanelet2(dir.str("out") + "/groundtruth.osm", with->truth().origin_lat,
                                        with->truth().origin_lon);
  EXPECT_EQ(intersectionLanelets(written), intersectionLanelets(with->truth()));
  EXPECT_LT(intersectionLanelets(with->truth()), intersectionLanelets(without->truth()));
}

// Bad input: a clear message, a non-zero exit, and nothing left behind.
void expectCleanFailure(const std::string& args, const std::string& message_part) {
  TempDir dir("simbad");
  const auto r = runCommand(binPath("lanemap-sim") + " -q --out " + dir.str("out") + " " + args);
  EXPECT_NE(r.exit_code, 0) << args;
  EXPECT_NE(r.output.find(message_part), std::string::npos) << "for '" << args << "' got: " << r.output;
  EXPECT_FALSE(fs::exists(dir.str("out"))) << "partial output left for " << args;
  for (const auto& e : fs::directory_iterator(dir.path())) ADD_FAILURE() << "left behind: " << e.path();
}

TEST(SimToolBadInput, MissingOsmFile) { expectCleanFailure("--osm /nonexistent/roads.osm", "/nonexistent/roads.osm"); }

TEST(SimToolBadInput, MalformedOsmFile) {
  TempDir dir("simbad-src");
  std::ofstream(dir.str("bad.osm")) << "<?xml version='1.0'?><osm version='0.6'><node id='1' lat='1' lon=";
  expectCleanFailure("--osm " + dir.str("bad.osm"), "bad.osm");
}

TEST(SimToolBadInput, OsmWithoutDrivableWays) {
  TempDir dir("simbad-src");
  std::ofstream(dir.str("paths.osm"))
      << "<?xml version='1.0'?>\n<osm version='0.6'>\n"
         "<node id='1' lat='37.80' lon='-122.30'/><node id='2' lat='37.81' lon='-122.30'/>\n"
         "<way id='10'><nd ref='1'/><nd ref='2'/><tag k='highway' v='footway'/></way>\n</osm>\n";
  expectCleanFailure("--osm " + dir.str("paths.osm"), "drivable");
}

TEST(SimToolBadInput, ImpossibleRoute) {
  expectCleanFailure("--osm " + dataPath("osm/west-oakland.osm") + " --route 1,2", "route");
  expectCleanFailure("--osm " + dataPath("osm/west-oakland.osm") + " --route abc", "route");
}

// A number out of its range is named with what it must be (CLI11's own check printed its upper
// bound, DBL_MAX, as 309 digits).
TEST(SimToolBadInput, ANumberOutOfRangeSaysWhatItMustBe) {
  expectCleanFailure("--osm " + dataPath("osm/west-oakland.osm") + " --duration -1", "--duration: must be greater than 0, not -1");
  expectCleanFailure("--osm " + dataPath("osm/west-oakland.osm") + " --duration 0", "--duration: must be greater than 0, not 0");
  expectCleanFailure("--osm " + dataPath("osm/west-oakland.osm") + " --duration soon", "--duration: a number is needed, not 'soon'");
  const auto r = runCommand(binPath("lanemap-sim") + " --osm " + dataPath("osm/west-oakland.osm") + " --out /nonexistent/x --duration -1");
  EXPECT_LT(r.output.size(), 200u) << r.output;
}

TEST(SimToolBadInput, NonEmptyOutputFolderIsNotOverwritten) {
  TempDir dir("simbad-out");
  std::ofstream(dir.str("keep.txt")) << "mine";
  const auto r = runCommand(binPath("lanemap-sim") + " -q --osm " + dataPath("osm/west-oakland.osm") +
                            " --out " + dir.str());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("not empty"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir.str("keep.txt")));
}

}  // namespace
