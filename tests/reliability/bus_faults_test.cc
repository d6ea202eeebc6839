// core/sim/bus_faults.h: the lossy bus of lanemap-fault-relay, live and in its log mode. Decisions
// are per channel and seeded (a channel's drops do not depend on the other channels' traffic),
// the counters add up, a held message is overtaken by the next one of its channel or sent when
// its hold runs out, a delay is in the caller's clock. And the log mode of lanemap-fault-relay
// (--log-in/--log-out) writes what the bus let through, with the same decisions.
#include "core/sim/bus_faults.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

using lanemap::sim::BusFaults;
using lanemap::sim::LossyBus;
namespace lt = lanemap::testing;

std::vector<uint8_t> payload(int64_t seq) {
  std::vector<uint8_t> d(sizeof seq);
  std::memcpy(d.data(), &seq, sizeof seq);
  return d;
}
int64_t seqOf(const LossyBus::Message& m) {
  int64_t s = 0;
  std::memcpy(&s, m.data.data(), sizeof s);
  return s;
}

// Pushes n messages on each channel (interleaved as `order` says, one per 10 ms) and returns the
// seqs that came out per channel.
std::map<std::string, std::vector<int64_t>> run(LossyBus& bus, const std::vector<std::string>& order, int n) {
  std::map<std::string, std::vector<int64_t>> out;
  int64_t t = 0;
  for (int i = 0; i < n; ++i) {
    for (const auto& ch : order) {
      const auto p = payload(i);
      bus.push(ch, p.data(), p.size(), t);
      for (const auto& m : bus.takeDue(t)) out[m.channel].push_back(seqOf(m));
      t += 10000;
    }
  }
  for (const auto& m : bus.drain(t)) out[m.channel].push_back(seqOf(m));
  return out;
}

TEST(BusFaults, DropsAreSeededPerChannelAndCounted) {
  BusFaults f;
  f.drop = 0.1;
  LossyBus a(f, {}, 7, 100000), b(f, {}, 7, 100000), c(f, {}, 8, 100000);
  // b gets a third channel between A's messages: A's fate must not change.
  const auto ra = run(a, {"A", "B"}, 2000), rb = run(b, {"A", "X", "B"}, 2000), rc = run(c, {"A", "B"}, 2000);
  EXPECT_EQ(ra.at("A"), rb.at("A"));
  EXPECT_EQ(ra.at("B"), rb.at("B"));
  EXPECT_NE(ra.at("A"), rc.at("A")) << "another seed, other drops";
  for (const char* ch : {"A", "B"}) {
    const int64_t dropped = a.counters().at(std::string("dropped:") + ch);
    EXPECT_EQ(static_cast<int64_t>(ra.at(ch).size()), 2000 - dropped) << ch;
    EXPECT_NEAR(dropped, 200, 4 * std::sqrt(2000 * 0.1 * 0.9)) << ch;
    // Nothing but drops: the others come out once, in order.
    EXPECT_TRUE(std::is_sorted(ra.at(ch).begin(), ra.at(ch).end()));
    EXPECT_EQ(std::set<int64_t>(ra.at(ch).begin(), ra.at(ch).end()).size(), ra.at(ch).size());
  }
  EXPECT_EQ(a.counters().at("received"), 4000);
  EXPECT_EQ(a.counters().at("dropped"), a.counters().at("dropped:A") + a.counters().at("dropped:B"));
  EXPECT_EQ(a.counters().at("published"), 4000 - a.counters().at("dropped"));
}

TEST(BusFaults, RulesPickTheRatesOfAChannel) {
  BusFaults none;
  std::vector<lanemap::sim::BusFaultRule> rules{lanemap::sim::parseBusFaultRule("PO.*:drop=1"),
                                                lanemap::sim::parseBusFaultRule("POSE:drop=0")};
  LossyBus bus(none, rules, 1, 100000);
  const auto r = run(bus, {"POSE", "LABELS"}, 100);
  EXPECT_EQ(r.count("POSE"), 0u) << "the first matching rule wins";
  EXPECT_EQ(r.at("LABELS").size(), 100u);
  EXPECT_THROW(lanemap::sim::parseBusFaultRule("POSE:loss=0.1"), std::runtime_error);
  EXPECT_THROW(lanemap::sim::parseBusFaultRule("POSE:drop=2"), std::runtime_error);
}

TEST(BusFaults, HeldMessagesAreOvertakenOrSentWhenTheirHoldRunsOut) {
  BusFaults f;
  f.reorder = 1.0;  // every message is held, so each is overtaken by the next: pairs swap
  LossyBus bus(f, {}, 3, 50000);
  std::vector<int64_t> out;
  for (int i = 0; i < 6; ++i) {
    const auto p = payload(i);
    bus.push("A", p.data(), p.size(), i * 10000);
    for (const auto& m : bus.takeDue(i * 10000)) out.push_back(seqOf(m));
  }
  EXPECT_EQ(out, (std::vector<int64_t>{1, 0, 3, 2, 5, 4}));
  EXPECT_EQ(bus.counters().at("reordered"), 3);
  // One held message and nothing after it: sent once its hold (50 ms) ran out, not before.
  const auto p = payload(9);
  bus.push("A", p.data(), p.size(), 100000);
  EXPECT_TRUE(bus.takeDue(149999).empty());
  const auto late = bus.takeDue(150000);
  ASSERT_EQ(late.size(), 1u);
  EXPECT_EQ(seqOf(late[0]), 9);
  EXPECT_EQ(bus.counters().at("reorder_expired"), 1);
}

TEST(BusFaults, DelaysAndDuplicatesAreInTheCallersClock) {
  BusFaults f;
  f.delay_ms = 40;
  f.jitter_ms = 10;
  f.duplicate = 1.0;
  LossyBus bus(f, {}, 5, 100000);
  const auto p = payload(1);
  bus.push("A", p.data(), p.size(), 1000000);
  EXPECT_TRUE(bus.takeDue(1029999).empty()) << "due 30-50 ms later";
  const auto due = bus.nextDue();
  ASSERT_TRUE(due.has_value());
  EXPECT_GE(*due, 1030000);
  EXPECT_LE(*due, 1050000);
  const auto out = bus.takeDue(1050000);
  ASSERT_EQ(out.size(), 2u) << "sent twice";
  EXPECT_EQ(out[0].due_us, *due);
  EXPECT_EQ(bus.counters().at("duplicated:A"), 1);
  EXPECT_EQ(bus.counters().at("delayed"), 1);
}

// The log mode: a log of numbered messages on two channels through lanemap-fault-relay --log-in.
TEST(FaultRelayLogMode, WritesWhatTheBusLetsThroughWithTheSameDecisions) {
  lt::TempDir dir("relay-log");
  const std::string in = dir.str("in.lcmlog"), out = dir.str("out.lcmlog"), out2 = dir.str("out2.lcmlog");
  {
    lcm::LogFile log(in, "w");
    ASSERT_TRUE(log.good());
    for (int i = 0; i < 1000; ++i) {
      for (const char* ch : {"POSE", "LABELS"}) {
        auto p = payload(i);
        lcm::LogEvent ev{};
        ev.eventnum = 2 * i;
        ev.timestamp = 1000000 + i * 10000;
        ev.channel = ch;
        ev.datalen = static_cast<int32_t>(p.size());
        ev.data = p.data();
        ASSERT_EQ(log.writeEvent(&ev), 0);
      }
    }
  }
  const std::string relay = lt::binPath("lanemap-fault-relay");
  const auto r = lt::runCommand(relay + " --log-in " + in + " --log-out " + out + " --drop 0.1 --seed 7 --rule 'LABELS:drop=0.3'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(lt::runCommand(relay + " --log-in " + in + " --log-out " + out2 + " --drop 0.1 --seed 7 --rule 'LABELS:drop=0.3'").exit_code, 0);
  // What the core bus decides for the same messages.
  BusFaults f;
  f.drop = 0.1;
  LossyBus bus(f, {lanemap::sim::parseBusFaultRule("LABELS:drop=0.3")}, 7, 100000);
  const auto expected = run(bus, {"POSE", "LABELS"}, 1000);
  std::map<std::string, std::vector<int64_t>> got;
  std::vector<int64_t> stamps;
  lcm::LogFile log(out, "r");
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    int64_t s = 0;
    std::memcpy(&s, ev->data, sizeof s);
    got[ev->channel].push_back(s);
    stamps.push_back(ev->timestamp);
  }
  EXPECT_EQ(got, expected);
  EXPECT_TRUE(std::is_sorted(stamps.begin(), stamps.end()));
  EXPECT_NEAR(static_cast<double>(got["LABELS"].size()), 700, 4 * std::sqrt(1000 * 0.3 * 0.7));
  // It says what it dropped; the same seed gives the same file.
  EXPECT_NE(r.output.find("dropped:LABELS " + std::to_string(1000 - got["LABELS"].size())), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dropped:POSE " + std::to_string(1000 - got["POSE"].size())), std::string::npos) << r.output;
  EXPECT_EQ(lt::runCommand("cmp " + out + " " + out2).exit_code, 0);
  // Bad uses are clear errors.
  EXPECT_NE(lt::runCommand(relay + " --log-in " + in).exit_code, 0) << "--log-in needs --log-out";
  EXPECT_EQ(lt::runCommand(relay + " --log-in " + dir.str("none.lcmlog") + " --log-out " + out).exit_code, 2);
  EXPECT_EQ(lt::runCommand(relay + " --log-in " + in + " --log-out " + out + " --drop 1.5").exit_code, 2);
}

}  // namespace
