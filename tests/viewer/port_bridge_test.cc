// lanemap-port-bridge (tools/port_bridge.cc): a page served on 127.0.0.1 inside another private
// network namespace is reachable through the bridge on this namespace's loopback, and only there.
// The whole test runs inside a private namespace of its own; the server runs in a second one nested
// in it (what `make demo` does with the live graph's viewer).
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"
#include "tests/viewer/http_client.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace {

namespace fs = std::filesystem;
namespace lt = lanemap::testing;

constexpr uint16_t kInnerPort = 18765, kBridgePort = 18766;

template <typename F>
bool waitFor(F&& f, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    if (f()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return f();
}

TEST(PortBridge, ForwardsLoopbackIntoAnotherNamespaceAndEndsWithIt) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  lt::TempDir dir("port-bridge");
  const std::string token = "lanes-" + std::to_string(::getpid());
  { std::ofstream(dir.path() / "token.txt") << token; }
  // A web server on 127.0.0.1 of a namespace of its own.
  lt::ChildProcess server({"/usr/bin/unshare", "-rn", "sh", "-c",
                           "ip link set lo up && exec python3 -m http.server --bind 127.0.0.1 " + std::to_string(kInnerPort) +
                               " --directory " + dir.path().string()});
  ASSERT_TRUE(server.started());
  const std::string ready = (dir.path() / "bridge.url").string();
  lt::ChildProcess bridge({lt::binPath("lanemap-port-bridge"), "--pid", std::to_string(server.pid()), "--port",
                           std::to_string(kInnerPort), "--listen-port", std::to_string(kBridgePort), "--ready-file", ready});
  ASSERT_TRUE(bridge.started());
  ASSERT_TRUE(waitFor([&] { return fs::exists(ready); }, 15)) << "the bridge never joined the server's namespace";
  std::string url;
  std::getline(std::ifstream(ready), url);
  EXPECT_EQ(url, "http://127.0.0.1:" + std::to_string(kBridgePort) + "/");

  // Through the bridge: the file the server serves (python needs a moment to listen).
  std::string response;
  ASSERT_TRUE(waitFor([&] { return lt::statusCode(response = lt::httpCall(kBridgePort, "GET", "/token.txt", "", 2000)) == 200; }, 15))
      << response;
  EXPECT_EQ(lt::responseBody(response), token);
  EXPECT_EQ(lt::statusCode(lt::httpCall(kBridgePort, "GET", "/no-such-file", "", 2000)), 404);
  // Several at once: each connection gets its own answer.
  const int a = lt::connectLoopback(kBridgePort), b = lt::connectLoopback(kBridgePort);
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 0);
  for (int fd : {b, a}) ASSERT_TRUE(lt::sendAll(fd, "GET /token.txt HTTP/1.0\r\n\r\n"));
  for (int fd : {a, b}) {
    const std::string r = lt::readUntil(fd, 5000);
    EXPECT_EQ(lt::statusCode(r), 200) << r;
    EXPECT_NE(r.find(token), std::string::npos);
    ::close(fd);
  }
  // The server's port is not open in this namespace: only the bridge reaches it.
  EXPECT_EQ(lt::connectLoopback(kInnerPort), -1);

  // The bridge ends when the namespace's process does.
  server.stop();
  EXPECT_EQ(bridge.waitExit(std::chrono::seconds(5)), 0);
  EXPECT_EQ(lt::connectLoopback(kBridgePort), -1);
}

TEST(PortBridge, RefusesAProcessInItsOwnNamespaceOrNoProcess) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  // This test's own process shares the bridge's namespace: nothing to bridge.
  lt::ChildProcess same({lt::binPath("lanemap-port-bridge"), "--pid", std::to_string(::getpid()), "--port", "18767", "--wait", "0.3"});
  ASSERT_TRUE(same.started());
  EXPECT_EQ(same.waitExit(std::chrono::seconds(5)), 1);
  lt::ChildProcess none({lt::binPath("lanemap-port-bridge"), "--pid", "999999999", "--port", "18768", "--wait", "0.3"});
  ASSERT_TRUE(none.started());
  EXPECT_EQ(none.waitExit(std::chrono::seconds(5)), 1);
}

}  // namespace
