// Process replay (issue 19, openpilot's manner): every case of tests/replay/cases.yaml (the road
// tracker, the BEV builder, the lane mapper, the segmenter on the shipped model, the viewer, each
// over its recorded input; the NMEA and VLP-16 drivers over the files they read) publishes what
// its reference says; a reference changed by more than the
// tolerance fails, naming the message and the field, and passes within a case's own tolerance; the comparison itself (processes/framework/message_json.h) tells a number within the
// tolerance from one beyond it, a missing field, a new one and a missing message.
#include "processes/framework/message_json.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace lt = lanemap::testing;
using lanemap::testing::readFile;

const std::string kSource = LANEMAP_SOURCE_DIR;
const std::string kReplay = std::string(LANEMAP_BIN_DIR) + "/lanemap-replay";

struct ReplayRun {
  int rc = -1;
  std::string out;
};

ReplayRun run(const std::string& args) {
  const auto r = lt::runCommand(kReplay + " " + args);
  return {r.exit_code, r.output};
}

TEST(ProcessReplay, EveryProcessPublishesWhatItsReferenceSays) {
  const ReplayRun r = run("");
  EXPECT_EQ(r.rc, 0) << r.out;
  for (const char* line : {"road_tracker: 3 messages, as the reference", "bev_builder: 2 messages, as the reference",
                           "lane_mapper: 2 messages, as the reference", "segmenter: 7 messages, as the reference",
                           // the page's state, the roads driven or mapped, the lanes' GeoJSON
                           "viewer: 3 messages, as the reference",
                           // 31 epochs, one without a fix; 12 whole rotations of 1000 packets, packets and points
                           "pose_nmea: 30 messages, as the reference", "lidar_vlp16: 24 messages, as the reference",
                           "7 case(s) run, 0 differ"}) {
    EXPECT_NE(r.out.find(line), std::string::npos) << line << "\n" << r.out;
  }
}

TEST(ProcessReplay, AReferenceChangedBeyondTheToleranceFailsNamingTheField) {
  lt::TempDir tmp("replay");
  // The road tracker's reference with the first event's distance moved by 1 mm.
  std::string ref = readFile(kSource + "/tests/replay/road_tracker.reference.jsonl");
  const size_t eol = ref.find('\n');
  ASSERT_NE(eol, std::string::npos);
  auto first = nlohmann::json::parse(ref.substr(0, eol));
  const double d = first["msg"]["distance_m"].get<double>();
  first["msg"]["distance_m"] = d + 1e-3;
  std::ofstream(tmp.str("road_tracker.reference.jsonl")) << first.dump() << "\n" << ref.substr(eol + 1);
  std::ofstream(tmp.str("cases.yaml")) << "cases:\n"
                                       << "  - name: road_tracker\n"
                                       << "    command: [lanemap-road-tracker, --config, config/road_tracker.yaml, --osm, tests/replay/roads.osm]\n"
                                       << "    input: tests/replay/road_tracker.input.lcmlog\n"
                                       << "    reference: " << tmp.str("road_tracker.reference.jsonl") << "\n";
  const ReplayRun r = run("--cases " + tmp.str("cases.yaml"));
  EXPECT_EQ(r.rc, 1) << r.out;
  EXPECT_NE(r.out.find("line 1 (ROAD_EVENT).msg.distance_m"), std::string::npos) << r.out;
  // --update writes what was published back: the reference is the original again.
  const ReplayRun u = run("--cases " + tmp.str("cases.yaml") + " --update");
  EXPECT_EQ(u.rc, 0) << u.out;
  EXPECT_EQ(readFile(tmp.str("road_tracker.reference.jsonl")), ref);
  EXPECT_EQ(run("--cases " + tmp.str("cases.yaml")).rc, 0);
  // A case's own tolerance (abs_tolerance: 0.01 m) lets the 1 mm through.
  std::ofstream(tmp.str("road_tracker.reference.jsonl")) << first.dump() << "\n" << ref.substr(eol + 1);
  std::ofstream(tmp.str("cases.yaml"), std::ios::app) << "    abs_tolerance: 0.01\n";
  const ReplayRun loose = run("--cases " + tmp.str("cases.yaml"));
  EXPECT_EQ(loose.rc, 0) << loose.out;
}

// A driver's case (no input log: it reads its own file) and the viewer's (several input logs
// merged, its state written to a file) fail on a changed reference too, naming the field.
TEST(ProcessReplay, ADriversRecordingAndTheViewersStateFailWhenTheyDifferFromTheirReference) {
  lt::TempDir tmp("replay");
  std::string pose_ref = readFile(kSource + "/tests/replay/pose_nmea.reference.jsonl");
  auto first = nlohmann::json::parse(pose_ref.substr(0, pose_ref.find('\n')));
  first["msg"]["latitude"] = first["msg"]["latitude"].get<double>() + 1e-5;  // 1.1 m north
  std::ofstream(tmp.str("pose.jsonl")) << first.dump() << "\n" << pose_ref.substr(pose_ref.find('\n') + 1);
  std::ofstream(tmp.str("cases.yaml"))
      << "cases:\n"
      << "  - name: pose_nmea\n"
      << "    command: [lanemap-pose-nmea, --config, config/pose_nmea.yaml, --file, tests/replay/pose_nmea.input.nmea]\n"
      << "    reference: " << tmp.str("pose.jsonl") << "\n"
      // The viewer over the poses and the road tracker's own recorded events: the car, its trail,
      // the roads driven; no lanes.
      << "  - name: road_tracker\n"
      << "    command: [lanemap-road-tracker, --config, config/road_tracker.yaml, --osm, tests/replay/roads.osm]\n"
      << "    input: tests/replay/road_tracker.input.lcmlog\n"
      << "    reference: tests/replay/road_tracker.reference.jsonl\n"
      << "  - name: viewer\n"
      << "    command: [lanemap-viewer, --config, config/viewer.yaml, --osm, tests/replay/roads.osm, --port, '0',\n"
      << "              --state-out, '${work}/state.jsonl']\n"
      << "    input: [tests/replay/road_tracker.input.lcmlog, '${work}/road_tracker.out.lcmlog']\n"
      << "    output_file: '${work}/state.jsonl'\n"
      << "    reference: " << tmp.str("viewer.jsonl") << "\n";
  const ReplayRun r = run("--cases " + tmp.str("cases.yaml"));
  EXPECT_EQ(r.rc, 1) << r.out;
  EXPECT_NE(r.out.find("line 1 (POSE).msg.latitude"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("viewer: 3 messages, not as the reference"), std::string::npos) << r.out;  // none yet
  ASSERT_EQ(run("--cases " + tmp.str("cases.yaml") + " --update").rc, 0);
  const std::string state = readFile(tmp.str("viewer.jsonl"));
  const auto s = nlohmann::json::parse(state.substr(0, state.find('\n')))["state"];
  // 451 poses of the 18 s drive at 25 Hz; the road it entered and the one it closed driven, none mapped.
  EXPECT_EQ(s["car"]["poses"], 451);
  EXPECT_EQ(s["closed_roads"], nlohmann::json::array({4}));
  EXPECT_EQ(s["coverage"]["mapped"], 0);
  EXPECT_EQ(s["coverage"]["driven"], 2);
  EXPECT_EQ(s["map"]["road_lanes"], 0);
  EXPECT_EQ(run("--cases " + tmp.str("cases.yaml")).rc, 0);
  // One more road driven in the reference than the viewer saw: named.
  auto changed = nlohmann::json::parse(state.substr(0, state.find('\n')));
  changed["state"]["coverage"]["driven"] = 3;
  std::ofstream(tmp.str("viewer.jsonl")) << changed.dump() << "\n" << state.substr(state.find('\n') + 1);
  const ReplayRun v = run("--cases " + tmp.str("cases.yaml"));
  EXPECT_EQ(v.rc, 1) << v.out;
  EXPECT_NE(v.out.find("line 1 (state).state.coverage.driven: 3 -> 2"), std::string::npos) << v.out;
}

TEST(MessageJson, NumbersWithinTheToleranceAgreeEverythingElseExactly) {
  const std::string ref = R"({"channel":"ROAD_EVENT","msg":{"d":1.0,"s":"a","v":[1,2]}})" "\n"
                          R"({"channel":"BEV_ROAD","msg":{"n":3}})" "\n";
  EXPECT_TRUE(lanemap::compareJsonLines(ref, ref).empty());
  const std::string close = R"({"channel":"ROAD_EVENT","msg":{"d":1.0000005,"s":"a","v":[1,2]}})" "\n"
                            R"({"channel":"BEV_ROAD","msg":{"n":3}})" "\n";
  EXPECT_TRUE(lanemap::compareJsonLines(ref, close).empty());
  const std::string far = R"({"channel":"ROAD_EVENT","msg":{"d":1.00001,"s":"b","v":[1,2,3]}})" "\n"
                          R"({"channel":"BEV_ROAD","msg":{"m":3}})" "\n";
  const auto diffs = lanemap::compareJsonLines(ref, far);
  ASSERT_EQ(diffs.size(), 5u);
  EXPECT_EQ(diffs[0].rfind("line 1 (ROAD_EVENT).msg.d: 1.0 -> 1.00001", 0), 0u) << diffs[0];
  EXPECT_EQ(diffs[1].rfind("line 1 (ROAD_EVENT).msg.s:", 0), 0u) << diffs[1];
  EXPECT_EQ(diffs[2], "line 1 (ROAD_EVENT).msg.v: 2 items -> 3");
  EXPECT_EQ(diffs[3], "line 2 (BEV_ROAD).msg.n: missing");
  EXPECT_EQ(diffs[4], "line 2 (BEV_ROAD).msg.m: new, 3");
  const auto shorter = lanemap::compareJsonLines(ref, ref.substr(0, ref.find('\n') + 1));
  ASSERT_EQ(shorter.size(), 1u);
  EXPECT_EQ(shorter[0].rfind("2 messages in the reference, 1 published; the first missing:", 0), 0u) << shorter[0];
}

}  // namespace
