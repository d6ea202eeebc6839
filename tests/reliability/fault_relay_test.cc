// lanemap-fault-relay (tools/fault_relay.cc) between two udpm buses inside a private network
// namespace: numbered messages on two channels go in; what comes out is compared with the relay's
// STATUS counts (exactly) and with the configured rates (statistically: 4 sigma), reordering must
// really reorder, a delay must really delay, and the same seed must give the same decisions.
#include "lanemap/status_t.hpp"
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/status.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
const std::string kRelay = std::string(LANEMAP_BIN_DIR) + "/lanemap-fault-relay";

struct Payload {
  int64_t seq;
  int64_t sent_ns;  // steady clock of this process
};

struct Out {
  std::map<std::string, std::vector<int64_t>> seqs;  // per channel, in arrival order
  double min_latency_ms_b = 1e9;
  std::vector<lanemap::status_t> status;
  void onRaw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (rbuf->data_size != sizeof(Payload)) return;
    Payload p;
    std::memcpy(&p, rbuf->data, sizeof p);
    seqs[channel].push_back(p.seq);
    if (channel == "B") {
      const double ms = (Clock::now().time_since_epoch().count() - p.sent_ns) * 1e-6;
      min_latency_ms_b = std::min(min_latency_ms_b, ms);
    }
  }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const lanemap::status_t* m) {
    if (m->process == "fault_relay") status.push_back(*m);
  }
};

// A counter of the relay's STATUS; per-channel counters (dropped:A ...) exist from their first
// event, so a missing one is 0.
int64_t counter(const lanemap::status_t& s, const std::string& name) {
  return lanemap::testing::statusCounter(s, name, name.find(':') != std::string::npos ? 0 : -1);
}

struct RelayRun {
  Out out;
  lanemap::status_t last;  // the relay's final STATUS (state "stopped")
  std::set<int64_t> dropped_a, duplicated_a;
  int64_t inversions_a = 0;  // first arrivals of a seq lower than one already seen
};

// Sends na messages on A and nb on B through a relay started with `args`.
RelayRun runRelay(const std::vector<std::string>& args, int na, int nb) {
  const std::string in_url = lanemap::testing::testUdpmUrl(7691), out_url = lanemap::testing::testUdpmUrl(7692);
  std::vector<std::string> cmd{kRelay, "--from", in_url, "--lcm-url", out_url};
  cmd.insert(cmd.end(), args.begin(), args.end());
  RelayRun run;
  lcm::LCM in(in_url), out(out_url);
  EXPECT_TRUE(in.good() && out.good());
  out.subscribe("A|B", &Out::onRaw, &run.out)->setQueueCapacity(100000);
  out.subscribe("STATUS", &Out::onStatus, &run.out)->setQueueCapacity(1000);
  lanemap::testing::ChildProcess relay(cmd);
  EXPECT_TRUE(relay.started());
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  while (run.out.status.empty() && Clock::now() < deadline) out.handleTimeout(50);
  EXPECT_FALSE(run.out.status.empty()) << "no STATUS from lanemap-fault-relay";
  for (int i = 0; i < std::max(na, nb); ++i) {
    for (const char* ch : {"A", "B"}) {
      if (i >= (ch[0] == 'A' ? na : nb)) continue;
      const Payload p{i, static_cast<int64_t>(Clock::now().time_since_epoch().count())};
      in.publish(ch, &p, sizeof p);
    }
    if (i % 25 == 0) {
      while (out.handleTimeout(0) > 0) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  // Until the relay says it received everything (STATUS at 1 Hz), then stop it: it flushes what
  // it holds and publishes a last STATUS.
  const auto end = Clock::now() + std::chrono::seconds(10);
  while (Clock::now() < end && (run.out.status.empty() || counter(run.out.status.back(), "received") < na + nb)) {
    out.handleTimeout(50);
  }
  EXPECT_EQ(relay.stop(), 0);
  const auto drain = Clock::now() + std::chrono::seconds(3);
  while (Clock::now() < drain && (run.out.status.empty() || run.out.status.back().state != "stopped")) {
    out.handleTimeout(50);
  }
  while (out.handleTimeout(100) > 0) {
  }
  EXPECT_FALSE(run.out.status.empty());
  if (!run.out.status.empty()) run.last = run.out.status.back();
  EXPECT_EQ(run.last.state, "stopped");
  std::map<int64_t, int> seen;
  int64_t max_first = -1;
  for (int64_t s : run.out.seqs["A"]) {
    if (seen[s]++ == 0) {
      if (s < max_first) ++run.inversions_a;
      max_first = std::max(max_first, s);
    }
  }
  for (int i = 0; i < na; ++i) {
    if (!seen.count(i)) run.dropped_a.insert(i);
    if (seen.count(i) && seen[i] == 2) run.duplicated_a.insert(i);
  }
  return run;
}

// |x - n p| within 4 standard deviations of a binomial(n, p).
void expectRate(int64_t x, int64_t n, double p, const std::string& what) {
  const double sd = std::sqrt(n * p * (1 - p));
  EXPECT_NEAR(static_cast<double>(x), n * p, 4 * sd + 1) << what << ": " << x << " of " << n << ", p = " << p;
}

TEST(FaultRelay, CountsWhatItDidAndKeepsToTheRatesAndTheSeed) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const int na = 3000, nb = 1000;
  const std::vector<std::string> args{"--drop", "0.1", "--duplicate", "0.05", "--reorder", "0.1", "--seed", "7",
                                      "--rule", "B:drop=0.5"};
  const RelayRun r = runRelay(args, na, nb);
  const auto& s = r.last;
  ASSERT_EQ(counter(s, "received"), na + nb);  // the loopback bus itself lost nothing
  EXPECT_EQ(counter(s, "received:A"), na);
  EXPECT_EQ(counter(s, "received:B"), nb);
  // What came out is exactly what the relay counted.
  const auto& a = r.out.seqs.at("A");
  const auto& b = r.out.seqs.at("B");
  EXPECT_EQ(static_cast<int64_t>(a.size() + b.size()), counter(s, "published"));
  EXPECT_EQ(static_cast<int64_t>(r.dropped_a.size()), counter(s, "dropped:A"));
  EXPECT_EQ(static_cast<int64_t>(r.duplicated_a.size()), counter(s, "duplicated:A"));
  EXPECT_EQ(static_cast<int64_t>(a.size()), na - counter(s, "dropped:A") + counter(s, "duplicated:A"));
  EXPECT_EQ(static_cast<int64_t>(b.size()), nb - counter(s, "dropped:B") + counter(s, "duplicated:B"));
  EXPECT_EQ(counter(s, "dropped"), counter(s, "dropped:A") + counter(s, "dropped:B"));
  // The rates: A by the options, B by its rule (drop 0.5, nothing else).
  expectRate(counter(s, "dropped:A"), na, 0.1, "A dropped");
  expectRate(counter(s, "duplicated:A"), na - counter(s, "dropped:A"), 0.05, "A duplicated");
  expectRate(counter(s, "dropped:B"), nb, 0.5, "B dropped");
  EXPECT_EQ(counter(s, "duplicated:B"), 0);
  EXPECT_EQ(counter(s, "reordered:B"), 0);
  // Reordering reorders: every reordered message arrives after a later one (unless its hold
  // expired at the very end), and about 10 % of the kept messages that found nothing held.
  EXPECT_GT(r.inversions_a, 100);
  EXPECT_EQ(r.inversions_a, counter(s, "reordered:A"));
  EXPECT_LE(counter(s, "reorder_expired"), 1);
  for (size_t i = 1; i < b.size(); ++i) EXPECT_LT(b[i - 1], b[i]) << "B was not to be reordered";

  // The same seed: the same decisions. Another seed: others. And a delay on B delays it.
  const RelayRun again = runRelay(args, na, nb);
  EXPECT_EQ(again.dropped_a, r.dropped_a);
  EXPECT_EQ(again.duplicated_a, r.duplicated_a);
  EXPECT_EQ(counter(again.last, "dropped:B"), counter(s, "dropped:B"));
  const RelayRun other = runRelay({"--drop", "0.1", "--duplicate", "0.05", "--seed", "8", "--rule", "B:delay_ms=40"}, na, 200);
  EXPECT_NE(other.dropped_a, r.dropped_a);
  expectRate(static_cast<int64_t>(other.dropped_a.size()), na, 0.1, "A dropped, seed 8");
  const std::set<int64_t> both = [&] {
    std::set<int64_t> x;
    for (int64_t v : r.dropped_a)
      if (other.dropped_a.count(v)) x.insert(v);
    return x;
  }();
  EXPECT_LT(both.size(), r.dropped_a.size() / 2);  // independent draws overlap ~10 %
  EXPECT_EQ(other.out.seqs.at("B").size(), 200u);  // the rule replaces the options: no drop on B
  EXPECT_GE(other.out.min_latency_ms_b, 38.0);
  EXPECT_EQ(counter(other.last, "delayed"), 200);
}

TEST(FaultRelay, RefusesBadOptionsWithAClearMessage) {
  // memq:// buses: no traffic at all; the options are checked before anything is relayed.
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--drop", "1.5"}, {"--rule", "POSE"}, {"--rule", "POSE:drop=x"},
        {"--rule", "POSE:loss=0.1"}, {"--rule", "(:drop=0.1"}, {"--delay-ms", "5", "--jitter-ms", "10"}}) {
    std::vector<std::string> cmd{kRelay, "--from", "memq://", "--lcm-url", "memq://"};
    cmd.insert(cmd.end(), bad.begin(), bad.end());
    lanemap::testing::ChildProcess p(cmd);
    ASSERT_TRUE(p.started());
    EXPECT_EQ(p.waitExit(std::chrono::seconds(5)), 2) << bad[0] << " " << bad[1];
  }
}

}  // namespace
