// lanemap-fault-relay: a lossy, unordered bus between two LCM URLs, for testing the graph against
// what a real network between two onboard machines does. Every message received on --from is
// republished on --lcm-url (the output bus, where this tool's STATUS goes too) unless it is
// dropped; it may be duplicated, reordered (held back and sent after the next message of its
// channel) and delayed. Rates are per channel: --rule 'REGEX:drop=0.1,duplicate=0.02' for the
// channels whose name matches REGEX (first matching rule wins), the --drop/--duplicate/...
// options for the others. Decisions are seeded (--seed) and drawn from one random stream per
// channel, so a channel's fate does not depend on the traffic of the others: the same seed and the
// same messages give the same drops and duplicates.
//
//   lanemap-fault-relay --from 'udpm://239.255.76.67:7667?ttl=0' \
//       --lcm-url 'udpm://239.255.76.68:7668?ttl=0' --drop 0.1 --seed 7
//   lanemap-fault-relay --from URL_A --lcm-url URL_B --rule 'CAMERA_.*:drop=0.3' --rule 'POSE:reorder=0.05'
//
// STATUS counters (process fault_relay): received, published, dropped, duplicated, reordered,
// reorder_expired (held back but nothing came to overtake it within --hold-ms), delayed, and per channel received:<CH>, dropped:<CH>, duplicated:<CH>, reordered:<CH>.
// STATUS messages seen on --from are not relayed unless --relay-status (they would mix with the
// relay's own). Exits 0 on SIGINT/SIGTERM, or after --max-seconds.
//
// Log mode: --log-in IN --log-out OUT does the same to a log, with the log's timestamps as the
// clock (a delay moves an event later, a held one waits for the next event of its channel or
// --hold-ms of log time), and prints the counters: the same seed and rates drop the same messages
// as live (the decisions are core/sim/bus_faults.h's, drawn per channel in the same order), so a
// lossy run can be replayed deterministically offline (lanemap-offline --log OUT).
//
//   lanemap-fault-relay --log-in drive.lcmlog --log-out lossy.lcmlog --drop 0.1 --seed 7
#include "core/sim/bus_faults.h"
#include "processes/framework/channels.h"
#include "processes/framework/log_reader.h"
#include "processes/framework/process.h"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
using lanemap::sim::LossyBus;

int64_t steadyUs() { return std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch()).count(); }

void copyCounters(const LossyBus& bus, lanemap::Process& process) {
  for (const auto& [name, value] : bus.counters()) process.counters().set(name, value);
}

// The log mode: IN through the bus to OUT, in log time. Returns the exit code.
int filterLog(const std::string& in_path, const std::string& out_path, const std::string& channels, bool relay_status,
              LossyBus& bus) {
  lanemap::LogReader in(in_path);
  lcm::LogFile out(out_path, "w");
  if (!out.good()) throw std::runtime_error("cannot write log '" + out_path + "'");
  const std::regex select(channels);
  int64_t written = 0, passed = 0, last_us = 0;
  auto write = [&](const std::vector<LossyBus::Message>& msgs) {
    for (const auto& m : msgs) {
      lcm::LogEvent ev{};
      ev.eventnum = written;
      ev.timestamp = m.due_us;
      ev.channel = m.channel;
      ev.datalen = static_cast<int32_t>(m.data.size());
      ev.data = const_cast<uint8_t*>(m.data.data());
      if (out.writeEvent(&ev) != 0) throw std::runtime_error("cannot write log '" + out_path + "'");
      ++written;
    }
  };
  while (const lcm::LogEvent* ev = in.next()) {
    last_us = std::max(last_us, ev->timestamp);
    write(bus.takeDue(ev->timestamp));  // what is due before this event
    if ((ev->channel == lanemap::channels::kStatus && !relay_status) || !std::regex_match(ev->channel, select)) {
      ++passed;  // not relayed live either: not in the output
      continue;
    }
    bus.push(ev->channel, static_cast<const uint8_t*>(ev->data), static_cast<size_t>(ev->datalen), ev->timestamp);
    write(bus.takeDue(ev->timestamp));
  }
  write(bus.drain(last_us));
  std::cout << "fault_relay: " << in_path << " -> " << out_path << ": " << in.events() << " events read, " << written
            << " written, " << passed << " not relayed (STATUS or not --channels)\n";
  for (const auto& [name, value] : bus.counters()) std::cout << name << " " << value << "\n";
  return 0;
}

bool hasArg(int argc, char** argv, const char* name) {  // NAME or NAME=VALUE
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], name, std::strlen(name)) == 0) return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  // The log mode publishes nothing: no bus is needed (an explicit --lcm-url is still opened).
  const bool log_mode = hasArg(argc, argv, "--log-in");
  if (log_mode) setenv("LCM_DEFAULT_URL", "memq://", 1);
  lanemap::Process process("fault_relay");
  auto& cli = process.cli();
  cli.description(
      "lanemap-fault-relay: republishes the messages of one LCM URL (--from) on another (--lcm-url), dropping, "
      "duplicating, reordering and delaying them per channel at given rates, seeded; or does the same to a log "
      "(--log-in, --log-out)");
  std::string from, log_in, log_out;
  lanemap::sim::BusFaults defaults;
  std::vector<std::string> rule_texts;
  uint64_t seed = 1;
  bool relay_status = false;
  double hold_ms = 100.0, max_seconds = 0.0;
  std::string channels = ".*";
  auto* from_opt = cli.add_option("--from", from, "LCM URL to subscribe to (the relay publishes on --lcm-url)");
  auto* in_opt = cli.add_option("--log-in", log_in, "log mode: read this LCM log instead of --from ...")->excludes(from_opt);
  auto* out_opt = cli.add_option("--log-out", log_out, "... and write what the bus lets through to this log");
  in_opt->needs(out_opt);
  out_opt->needs(in_opt);
  cli.add_option("--channels", channels, "regular expression of the channels to relay (LCM subscribe syntax)");
  cli.add_option("--drop", defaults.drop, "probability that a message is dropped");
  cli.add_option("--duplicate", defaults.duplicate, "probability that a (kept) message is sent twice");
  cli.add_option("--reorder", defaults.reorder,
                 "probability that a message is held back and sent after the next one of its channel");
  cli.add_option("--delay-ms", defaults.delay_ms, "delay added to every message (ms)");
  cli.add_option("--jitter-ms", defaults.jitter_ms, "the delay varies uniformly by +- this (ms; <= --delay-ms)");
  cli.add_option("--rule", rule_texts,
                 "per-channel rates: 'REGEX:drop=P,duplicate=P,reorder=P,delay_ms=D,jitter_ms=J' "
                 "(repeatable; the first matching rule wins, the options above apply to the others)");
  cli.add_option("--seed", seed, "seed of the decisions");
  cli.add_option("--hold-ms", hold_ms, "a message held for reordering is sent anyway after this (ms)");
  cli.add_option("--max-seconds", max_seconds, "stop after this many seconds (0: until SIGINT/SIGTERM)");
  cli.add_flag("--relay-status", relay_status, "relay STATUS messages too (default: not, they mix with ours)");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;
  try {
    if (from.empty() && log_in.empty()) throw std::runtime_error("give --from URL (live) or --log-in IN --log-out OUT");
    defaults.validate("fault_relay");
    if (!(hold_ms > 0.0)) throw std::runtime_error("--hold-ms must be > 0");
    std::vector<lanemap::sim::BusFaultRule> rules;
    for (const auto& t : rule_texts) rules.push_back(lanemap::sim::parseBusFaultRule(t));
    LossyBus bus(defaults, std::move(rules), seed, static_cast<int64_t>(hold_ms * 1000.0));
    if (!log_in.empty()) return filterLog(log_in, log_out, channels, relay_status, bus);
    lcm::LCM in(from);
    if (!in.good()) throw std::runtime_error("cannot open LCM '" + from + "' (--from)");
    auto publish = [&](const std::vector<LossyBus::Message>& msgs) {
      for (const auto& m : msgs) process.lcm().publish(m.channel, m.data.data(), static_cast<unsigned int>(m.data.size()));
      copyCounters(bus, process);
    };
    struct Handler {
      LossyBus* bus;
      bool relay_status;
      void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
        if (channel == lanemap::channels::kStatus && !relay_status) return;
        bus->push(channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size, steadyUs());
      }
    } handler{&bus, relay_status};
    in.subscribe(channels, &Handler::on, &handler)->setQueueCapacity(10000);
    copyCounters(bus, process);
    const auto start = Clock::now();
    auto next_status = start;
    while (!lanemap::Process::stopRequested()) {
      publish(bus.takeDue(steadyUs()));
      // Wait for the next message at most until the next queued one is due (20 ms at most: a held
      // message's hold runs out too).
      int64_t wait_ms = 20;
      if (const auto due = bus.nextDue()) wait_ms = std::clamp<int64_t>((*due - steadyUs()) / 1000, 0, 20);
      const int rc = in.handleTimeout(static_cast<int>(wait_ms));
      if (rc < 0 && !lanemap::Process::stopRequested()) throw std::runtime_error("LCM handle failed on --from");
      publish(bus.takeDue(steadyUs()));
      const auto now = Clock::now();
      if (now >= next_status) {
        process.publishStatus();
        next_status = now + std::chrono::seconds(1);
      }
      if (max_seconds > 0 && now - start >= std::chrono::duration<double>(max_seconds)) break;
    }
    publish(bus.drain(steadyUs()));
    process.setState("stopped");
    process.publishStatus();
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fault_relay: " << e.what() << "\n";
    return 2;
  }
}
