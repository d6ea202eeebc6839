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
#include "processes/framework/channels.h"
#include "processes/framework/process.h"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <queue>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

struct Faults {
  double drop = 0.0, duplicate = 0.0, reorder = 0.0;
  double delay_ms = 0.0, jitter_ms = 0.0;
  void validate(const std::string& where) const {
    for (double p : {drop, duplicate, reorder}) {
      if (!(p >= 0.0 && p <= 1.0)) throw std::runtime_error(where + ": rates must be in [0, 1]");
    }
    if (!(delay_ms >= 0.0) || !(jitter_ms >= 0.0) || jitter_ms > delay_ms) {
      throw std::runtime_error(where + ": need 0 <= jitter_ms <= delay_ms");
    }
  }
};

struct Rule {
  std::string pattern;
  std::regex re;
  Faults faults;
};

// "REGEX:drop=0.1,duplicate=0.02,reorder=0.05,delay_ms=20,jitter_ms=5"
Rule parseRule(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) {
    throw std::runtime_error("--rule '" + text + "': expected REGEX:key=value,...");
  }
  Rule r;
  r.pattern = text.substr(0, colon);
  try {
    r.re = std::regex(r.pattern);
  } catch (const std::regex_error& e) {
    throw std::runtime_error("--rule '" + text + "': bad regular expression: " + e.what());
  }
  std::stringstream ss(text.substr(colon + 1));
  std::string kv;
  while (std::getline(ss, kv, ',')) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) throw std::runtime_error("--rule '" + text + "': '" + kv + "' is not key=value");
    const std::string key = kv.substr(0, eq);
    double v = 0.0;
    try {
      size_t used = 0;
      v = std::stod(kv.substr(eq + 1), &used);
      if (used != kv.size() - eq - 1) throw std::invalid_argument(kv);
    } catch (const std::exception&) {
      throw std::runtime_error("--rule '" + text + "': '" + kv + "' is not a number");
    }
    if (key == "drop") r.faults.drop = v;
    else if (key == "duplicate") r.faults.duplicate = v;
    else if (key == "reorder") r.faults.reorder = v;
    else if (key == "delay_ms") r.faults.delay_ms = v;
    else if (key == "jitter_ms") r.faults.jitter_ms = v;
    else throw std::runtime_error("--rule '" + text + "': unknown key '" + key + "' (drop, duplicate, reorder, delay_ms, jitter_ms)");
  }
  r.faults.validate("--rule '" + text + "'");
  return r;
}

// splitmix64: small, fast, and the same on every platform (std distributions are not).
struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

uint64_t fnv1a(const std::string& s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

struct Message {
  std::string channel;
  std::vector<uint8_t> data;
};

struct Due {
  Clock::time_point at;
  uint64_t order;  // FIFO among messages due at the same time
  Message msg;
  bool operator>(const Due& o) const { return at != o.at ? at > o.at : order > o.order; }
};

class Relay {
 public:
  Relay(lanemap::Process& process, Faults defaults, std::vector<Rule> rules, uint64_t seed, bool relay_status,
        double hold_ms)
      : process_(process),
        defaults_(defaults),
        rules_(std::move(rules)),
        seed_(seed),
        relay_status_(relay_status),
        hold_(std::chrono::microseconds(static_cast<int64_t>(hold_ms * 1000))) {
    for (const char* c : {"received", "published", "dropped", "duplicated", "reordered", "reorder_expired", "delayed"}) {
      process_.counters().set(c, 0);
    }
  }

  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (channel == lanemap::channels::kStatus && !relay_status_) return;
    Channel& ch = channelState(channel);
    auto& c = process_.counters();
    c.add("received");
    c.add("received:" + channel);
    const Faults& f = *ch.faults;
    // Always four draws per message, whatever the rates, so one decision does not shift the others.
    const double u_drop = ch.rng.uniform(), u_dup = ch.rng.uniform(), u_reorder = ch.rng.uniform(),
                 u_delay = ch.rng.uniform();
    if (u_drop < f.drop) {
      c.add("dropped");
      c.add("dropped:" + channel);
      return;
    }
    Message m{channel, std::vector<uint8_t>(static_cast<const uint8_t*>(rbuf->data),
                                            static_cast<const uint8_t*>(rbuf->data) + rbuf->data_size)};
    const int copies = u_dup < f.duplicate ? 2 : 1;
    if (copies == 2) {
      c.add("duplicated");
      c.add("duplicated:" + channel);
    }
    const auto now = Clock::now();
    auto delay = std::chrono::microseconds(0);
    if (f.delay_ms > 0) {
      const double ms = f.delay_ms + (2.0 * u_delay - 1.0) * f.jitter_ms;
      delay = std::chrono::microseconds(static_cast<int64_t>(ms * 1000.0));
      c.add("delayed");
    }
    if (ch.held) {  // this message overtakes the one held back
      schedule(now + delay, m, copies);
      schedule(now + delay, std::move(ch.held->msg), ch.held->copies);
      ch.held.reset();
      c.add("reordered");
      c.add("reordered:" + channel);
      return;
    }
    if (u_reorder < f.reorder) {
      // Held back (with its duplicate) until the next message of the channel overtakes it, or
      // hold_ms passes and it is sent in order after all.
      ch.held = Held{std::move(m), copies, now + hold_};
      return;
    }
    schedule(now + delay, std::move(m), copies);
  }

  // Publishes what is due; returns the time until the next due message (capped).
  std::chrono::milliseconds flush() {
    const auto now = Clock::now();
    for (auto& [name, ch] : channels_) {
      if (ch.held && ch.held->expires <= now) {  // nothing overtook it: sent late, in order
        schedule(now, std::move(ch.held->msg), ch.held->copies);
        ch.held.reset();
        process_.counters().add("reorder_expired");
      }
    }
    while (!queue_.empty() && queue_.top().at <= now) {
      const Due& d = queue_.top();
      process_.lcm().publish(d.msg.channel, d.msg.data.data(), static_cast<unsigned int>(d.msg.data.size()));
      process_.counters().add("published");
      queue_.pop();
    }
    auto wait = std::chrono::milliseconds(20);
    if (!queue_.empty()) {
      wait = std::min(wait, std::chrono::duration_cast<std::chrono::milliseconds>(queue_.top().at - now));
    }
    return std::max(wait, std::chrono::milliseconds(0));
  }

  // At the end: what is held or queued is sent, so nothing is lost that was not dropped.
  void drain() {
    for (auto& [name, ch] : channels_) {
      if (ch.held) schedule(Clock::now(), std::move(ch.held->msg), ch.held->copies);
      ch.held.reset();
    }
    while (!queue_.empty()) {
      const Due& d = queue_.top();
      process_.lcm().publish(d.msg.channel, d.msg.data.data(), static_cast<unsigned int>(d.msg.data.size()));
      process_.counters().add("published");
      queue_.pop();
    }
  }

 private:
  struct Held {
    Message msg;
    int copies = 1;
    Clock::time_point expires;
  };
  struct Channel {
    const Faults* faults = nullptr;
    Rng rng{0};
    std::optional<Held> held;
  };

  Channel& channelState(const std::string& name) {
    auto it = channels_.find(name);
    if (it != channels_.end()) return it->second;
    Channel ch;
    ch.faults = &defaults_;
    for (const Rule& r : rules_) {
      if (std::regex_match(name, r.re)) {
        ch.faults = &r.faults;
        break;
      }
    }
    ch.rng = Rng{seed_ ^ fnv1a(name)};
    return channels_.emplace(name, std::move(ch)).first->second;
  }

  void schedule(Clock::time_point at, Message m, int copies) {
    for (int i = 0; i < copies; ++i) {
      queue_.push(Due{at, next_order_++, i + 1 < copies ? m : std::move(m)});
    }
  }

  lanemap::Process& process_;
  Faults defaults_;
  std::vector<Rule> rules_;
  uint64_t seed_;
  bool relay_status_;
  Clock::duration hold_;
  std::map<std::string, Channel> channels_;
  std::priority_queue<Due, std::vector<Due>, std::greater<Due>> queue_;
  uint64_t next_order_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  lanemap::Process process("fault_relay");
  auto& cli = process.cli();
  cli.description(
      "lanemap-fault-relay: republishes the messages of one LCM URL (--from) on another (--lcm-url), dropping, "
      "duplicating, reordering and delaying them per channel at given rates, seeded");
  std::string from;
  Faults defaults;
  std::vector<std::string> rule_texts;
  uint64_t seed = 1;
  bool relay_status = false;
  double hold_ms = 100.0, max_seconds = 0.0;
  std::string channels = ".*";
  cli.add_option("--from", from, "LCM URL to subscribe to (the relay publishes on --lcm-url)")->required();
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
    defaults.validate("fault_relay");
    if (!(hold_ms > 0.0)) throw std::runtime_error("--hold-ms must be > 0");
    std::vector<Rule> rules;
    for (const auto& t : rule_texts) rules.push_back(parseRule(t));
    lcm::LCM in(from);
    if (!in.good()) throw std::runtime_error("cannot open LCM '" + from + "' (--from)");
    Relay relay(process, defaults, std::move(rules), seed, relay_status, hold_ms);
    struct Handler {
      Relay* relay;
      void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { relay->onMessage(rbuf, channel); }
    } handler{&relay};
    in.subscribe(channels, &Handler::on, &handler)->setQueueCapacity(10000);
    const auto start = Clock::now();
    auto next_status = start;
    while (!lanemap::Process::stopRequested()) {
      const auto wait = relay.flush();
      const int rc = in.handleTimeout(static_cast<int>(wait.count()));
      if (rc < 0 && !lanemap::Process::stopRequested()) throw std::runtime_error("LCM handle failed on --from");
      relay.flush();
      const auto now = Clock::now();
      if (now >= next_status) {
        process.publishStatus();
        next_status = now + std::chrono::seconds(1);
      }
      if (max_seconds > 0 && now - start >= std::chrono::duration<double>(max_seconds)) break;
    }
    relay.drain();
    process.setState("stopped");
    process.publishStatus();
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fault_relay: " << e.what() << "\n";
    return 2;
  }
}
