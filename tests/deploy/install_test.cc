// The installation (issue 19): `cmake --install` into a temporary prefix, then the demo's first
// steps run from there with the source tree (and the build folder inside it) out of reach: a mount
// namespace lays an empty tmpfs over the source folder. The installed programs must find their
// configs, the shipped model and the bundled OSM under <prefix>/share/lanemap, and give the same
// bytes as the build tree's programs.
#include "tests/common/lcm_log.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
namespace lt = lanemap::testing;
using lanemap::testing::readFile;

namespace {

std::string quoted(const std::string& s) { return "'" + s + "'"; }

// `script` run by sh in a user + mount namespace where LANEMAP_SOURCE_DIR is an empty folder and
// the current folder is `cwd`; LANEMAP_DATA_DIR is unset so the binaries look for themselves.
lt::CommandResult runWithoutSources(const std::string& cwd, const std::string& script) {
  const std::string inner = "mount -t tmpfs none " + quoted(LANEMAP_SOURCE_DIR) + " && cd " + quoted(cwd) + " && " + script;
  return lt::runCommand("env -u LANEMAP_DATA_DIR unshare -rm sh -c " + quoted(inner));
}

}  // namespace

TEST(Install, TheInstalledProgramsRunTheDemoStepsWithoutTheSourceTree) {
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", 8.0, 5);
  ASSERT_FALSE(drive.empty());
  lt::TempDir tmp("install");
  const fs::path prefix = tmp.path() / "prefix";
  const fs::path build = fs::path(LANEMAP_BIN_DIR).parent_path();
  ASSERT_FALSE(fs::path(tmp.str()).string().rfind(LANEMAP_SOURCE_DIR, 0) == 0) << "the temporary folder is inside the sources";

  const auto inst = lt::runCommand("cmake --install " + quoted(build.string()) + " --prefix " + quoted(prefix.string()));
  ASSERT_EQ(inst.exit_code, 0) << inst.output;
  for (const char* f : {"bin/lanemap-sim", "bin/lanemap-offline", "bin/lanemap-eval", "bin/lanemap-segmenter",
                        "bin/lanemap-launch", "bin/lanemap-viewer", "share/lanemap/config/segmenter.yaml",
                        "share/lanemap/config/launch/demo.yaml", "share/lanemap/models/lanesegnet.onnx",
                        "share/lanemap/data/osm/west-oakland.osm", "share/lanemap/viewer/index.html"}) {
    EXPECT_TRUE(fs::exists(prefix / f)) << f;
  }
  EXPECT_FALSE(fs::exists(prefix / "bin/lanemap-bench-bev")) << "benchmarks read the source tree: not installed";

  // The build tree's map of the shared drive, for the byte comparison.
  const auto ref = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --log " + drive +
                                  "/drive.lcmlog --osm " + drive + "/roads.osm --out " + tmp.str("ref-map"));
  ASSERT_EQ(ref.exit_code, 0) << ref.output;
  fs::copy(drive, tmp.path() / "ref-drive", fs::copy_options::recursive);

  const std::string bin = (prefix / "bin").string() + "/";
  const std::string work = tmp.str("work");
  fs::create_directories(work);
  // 1. simulate the same drive (the OSM is the bundled one, named as the configs name it: relative);
  // 2. map it on the truth labels; 3. score it; 4. the shipped model on its camera frames;
  // 5. the demo's launch file resolves its programs to the installed ones.
  const auto r = runWithoutSources(
      work, "test ! -e " + quoted(std::string(LANEMAP_SOURCE_DIR) + "/config") + " && " +
                bin + "lanemap-sim -q --osm data/osm/west-oakland.osm --out drive --duration 8 --seed 5 && " +
                bin + "lanemap-offline -q --oracle --no-lidar --log drive/drive.lcmlog --osm drive/roads.osm --out map && " +
                bin + "lanemap-eval -q --truth drive/groundtruth.osm --map map/map.osm --driven drive/scenario.json --json eval.json && " +
                bin + "lanemap-segmenter --config config/segmenter.yaml --lcm-url memq:// --log-in drive/drive.lcmlog --log-out seg.lcmlog && " +
                bin + "lanemap-launch config/launch/demo.yaml --all-hosts --set drive=drive --dry-run > launch.txt");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // The installed simulator and mapper give the build tree's bytes.
  for (const char* f : {"drive.lcmlog", "groundtruth.osm", "roads.osm"}) {  // scenario.json names paths
    EXPECT_EQ(readFile(fs::path(work) / "drive" / f), readFile(tmp.path() / "ref-drive" / f)) << f << " differs";
  }
  const std::string map = readFile(fs::path(work) / "map/map.osm");
  EXPECT_GT(map.size(), 1000u);
  EXPECT_EQ(map, readFile(tmp.path() / "ref-map/map.osm")) << "the installed lanemap-offline made another map";
  EXPECT_NE(readFile(fs::path(work) / "eval.json").find("\"lanes\""), std::string::npos);

  // The shipped model labelled every camera frame of the drive.
  const auto in = lt::readLcmLog(fs::path(work) / "drive/drive.lcmlog");
  const auto out = lt::readLcmLog(fs::path(work) / "seg.lcmlog");
  const std::size_t frames = lt::countChannel(in, "CAMERA_FRONT");
  EXPECT_GT(frames, 20u);
  EXPECT_EQ(lt::countChannel(out, "SEMANTIC_FRONT"), frames);

  // Every lanemap program of the launch file runs from the installation.
  const std::string launch = readFile(fs::path(work) / "launch.txt");
  EXPECT_NE(launch.find(bin + "lanemap-segmenter"), std::string::npos) << launch;
  EXPECT_NE(launch.find(bin + "lanemap-lane-mapper"), std::string::npos) << launch;
  EXPECT_EQ(launch.find(LANEMAP_SOURCE_DIR), std::string::npos) << launch;
}

TEST(Install, ADataDirWithoutConfigIsAClearError) {
  const auto r = lt::runCommand("LANEMAP_DATA_DIR=/nonexistent " + lt::binPath("lanemap-offline") + " --log x --osm y --out z");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("LANEMAP_DATA_DIR=/nonexistent has no config/ folder"), std::string::npos) << r.output;
}

TEST(Install, TheDebianPackageHoldsTheProgramsTheShippedFilesAndItsDependencies) {
  lt::TempDir tmp("cpack");
  const fs::path build = fs::path(LANEMAP_BIN_DIR).parent_path();
  const auto r = lt::runCommand("cpack -G DEB -B " + quoted(tmp.str()) + " --config " + quoted((build / "CPackConfig.cmake").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  fs::path deb;
  for (const auto& e : fs::directory_iterator(tmp.path())) {
    if (e.path().extension() == ".deb") deb = e.path();
  }
  ASSERT_FALSE(deb.empty()) << r.output;
  const auto contents = lt::runCommand("dpkg-deb -c " + quoted(deb.string()));
  ASSERT_EQ(contents.exit_code, 0) << contents.output;
  for (const char* f : {"./usr/bin/lanemap-offline", "./usr/bin/lanemap-bev-builder", "./usr/bin/lanemap-launch",
                        "./usr/share/lanemap/config/map.yaml", "./usr/share/lanemap/models/lanesegnet.onnx",
                        "./usr/share/lanemap/data/osm/west-oakland.osm", "./usr/share/lanemap/viewer/index.html"}) {
    EXPECT_NE(contents.output.find(f), std::string::npos) << f;
  }
  EXPECT_EQ(contents.output.find("lanemap-bench-"), std::string::npos);
  // Its dependencies are Debian's packages of the libraries the programs link, and LCM's tools.
  const auto depends = lt::runCommand("dpkg-deb -f " + quoted(deb.string()) + " Depends");
  ASSERT_EQ(depends.exit_code, 0) << depends.output;
  for (const char* p : {"liblcm-bin", "liblcm1", "libopencv-dnn", "libpcl-common", "libyaml-cpp", "libgeographiclib"}) {
    EXPECT_NE(depends.output.find(p), std::string::npos) << p << " not in: " << depends.output;
  }
}
