// Runs a test inside a private network namespace so that LCM's udpm:// multicast never reaches
// the host's network (lanemap's network rule). The test re-executes its own binary under
// `unshare -rn` (unprivileged: a user namespace maps us to root inside), brings `lo` up and routes
// 224.0.0.0/4 to it, and runs only the current test there.
//
//   TEST(Udpm, Something) {
//     if (!lanemap::testing::inPrivateNetns()) { ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0); return; }
//     ... udpm code ...
//   }
#pragma once

#include <gtest/gtest.h>
#include <net/if.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace lanemap::testing {

// True only when the wrapper said so AND the namespace has no interface but `lo`.
inline bool inPrivateNetns() {
  const char* flag = std::getenv("LANEMAP_PRIVATE_NETNS");
  if (!flag || std::string(flag) != "1") return false;
  struct if_nameindex* ifs = if_nameindex();
  if (!ifs) return false;
  bool only_lo = true;
  for (auto* i = ifs; i->if_index != 0 || i->if_name != nullptr; ++i) {
    if (std::string(i->if_name) != "lo") only_lo = false;
  }
  if_freenameindex(ifs);
  return only_lo;
}

// The shell prologue that makes a fresh namespace usable for LCM multicast.
inline const char* kNetnsPrologue = "ip link set lo up && ip route add 224.0.0.0/4 dev lo";

// Re-runs the current test in a new private network namespace; returns its exit status.
inline int rerunInPrivateNetns() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string filter = std::string(info->test_suite_name()) + "." + info->name();
  char exe[4096] = {0};
  if (readlink("/proc/self/exe", exe, sizeof(exe) - 1) <= 0) return -1;
  const std::string cmd = std::string("unshare -rn sh -c '") + kNetnsPrologue +
                          " && LANEMAP_PRIVATE_NETNS=1 exec \"$0\" --gtest_filter=\"$1\"' '" +
                          exe + "' '" + filter + "'";
  const int rc = std::system(cmd.c_str());
  return rc == -1 ? -1 : WEXITSTATUS(rc);
}

// A multicast URL for tests inside the namespace: ttl=0, a receive buffer large enough for images.
inline std::string testUdpmUrl(int port = 7667) {
  return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0&recv_buf_size=8388608";
}

}  // namespace lanemap::testing
