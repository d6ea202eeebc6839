// tools/lcm-spy, the working replacement of Debian's broken lcm-spy launcher: it is executable,
// builds a class path on which java loads lcm.spy.Spy and lanemap's message classes, starts Spy
// (--help needs no display), and says clearly what is missing (java, a jar).
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace {

using lanemap::testing::runCommand;

const std::string kScript = std::string(LANEMAP_DATA_DIR) + "/../tools/lcm-spy";
const std::string kBuildDir = std::string(LANEMAP_BIN_DIR) + "/..";
const std::string kEnv = "LANEMAP_BUILD_DIR='" + kBuildDir + "' ";

bool haveJava() { return runCommand("command -v java").exit_code == 0; }

class LcmSpy : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!haveJava()) GTEST_SKIP() << "no java on PATH: lcm-spy cannot run here";
    const auto jar = std::filesystem::path(kBuildDir) / "share/java/lanemap_lcmtypes.jar";
    if (!std::filesystem::exists(jar)) {
      // The build makes it whenever a JDK is present (cmake/LcmTypes.cmake).
      ASSERT_NE(runCommand("command -v javac").exit_code, 0)
          << jar << " missing although javac exists: build target lanemap_lcmtypes_java";
      GTEST_SKIP() << "no JDK: the lanemap types jar is not built";
    }
  }
};

TEST_F(LcmSpy, ScriptIsExecutable) { EXPECT_EQ(access(kScript.c_str(), X_OK), 0) << kScript; }

TEST_F(LcmSpy, ClassPathHoldsTheThreeJars) {
  const auto r = runCommand(kEnv + kScript + " --lanemap-classpath");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("/usr/share/java/lcm.jar:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("jchart2d.jar:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("share/java/lanemap_lcmtypes.jar"), std::string::npos) << r.output;
}

TEST_F(LcmSpy, JavaLoadsSpyAndLanemapTypes) {
  const auto r = runCommand(kEnv + kScript + " --lanemap-check");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* cls :
       {"lcm.spy.Spy", "lanemap.pose_t", "lanemap.lidar_packets_t", "lanemap.status_t"}) {
    EXPECT_NE(r.output.find(std::string("ok ") + cls), std::string::npos) << r.output;
  }
}

TEST_F(LcmSpy, SpyStartsAndPrintsItsUsage) {
  // Debian's launcher dies here ("Unrecognized option: -Xincgc"); Spy's --help needs no display.
  const auto r = runCommand(kEnv + "timeout 60 " + kScript + " --help");
  EXPECT_NE(r.output.find("usage: lcm-spy"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--lcm-url"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Unrecognized option"), std::string::npos) << r.output;
}

TEST_F(LcmSpy, MissingPiecesGiveClearMessages) {
  auto r = runCommand("LANEMAP_TYPES_JAR=/nonexistent/types.jar " + kScript);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("lanemap message types jar not found: /nonexistent/types.jar"),
            std::string::npos)
      << r.output;
  r = runCommand(kEnv + "JCHART2D_JAR=/nonexistent/jchart2d.jar " + kScript);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("jchart2d not found: /nonexistent/jchart2d.jar"), std::string::npos)
      << r.output;
  // A class path that resolves to the wrong jar is caught by the check.
  r = runCommand(kEnv + "LCM_JAR=/usr/share/java/jchart2d.jar " + kScript + " --lanemap-check");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("java cannot load lcm.spy.Spy"), std::string::npos) << r.output;
  r = runCommand(kEnv + "PATH=/nonexistent /bin/sh " + kScript);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("java not found on PATH"), std::string::npos) << r.output;
}

}  // namespace
