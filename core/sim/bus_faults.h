// A lossy, unordered bus, LCM-free: what lanemap-fault-relay does to the messages between two LCM
// URLs, and what it does to a log (lanemap-fault-relay --log-in/--log-out), with the same
// decisions. Every message pushed in comes out (when due) unless it is dropped; it may be
// duplicated, reordered (held back and sent after the next message of its channel) and delayed.
// Rates are per channel: rules 'REGEX:drop=0.1,duplicate=0.02' for the channels whose name matches
// REGEX (first matching rule wins), the defaults for the others. Decisions are seeded and drawn
// from one random stream per channel (four draws per message, whatever the rates), so a channel's
// fate does not depend on the traffic of the others: the same seed and the same messages give the
// same drops and duplicates, live or from a log.
//
// Time is the caller's, in microseconds: the steady clock live, the log's timestamps offline.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <queue>
#include <regex>
#include <string>
#include <vector>

namespace lanemap::sim {

struct BusFaults {
  double drop = 0.0, duplicate = 0.0, reorder = 0.0;
  double delay_ms = 0.0, jitter_ms = 0.0;
  // Throws std::runtime_error (prefixed with `where`) for a rate outside [0, 1] or a jitter that is
  // negative or larger than the delay.
  void validate(const std::string& where) const;
};

struct BusFaultRule {
  std::string pattern;
  std::regex re;
  BusFaults faults;
};

// "REGEX:drop=0.1,duplicate=0.02,reorder=0.05,delay_ms=20,jitter_ms=5"; throws std::runtime_error
// naming the rule and what is wrong with it.
BusFaultRule parseBusFaultRule(const std::string& text);

// splitmix64: small, fast, and the same on every platform (std distributions are not).
struct SplitMix64 {
  uint64_t s;
  uint64_t next();
  double uniform();  // [0, 1)
};

class LossyBus {
 public:
  struct Message {
    std::string channel;
    std::vector<uint8_t> data;
    int64_t due_us = 0;  // when it is sent (the caller's clock)
  };

  // hold_us: a message held back for reordering is sent anyway (in order) after this.
  LossyBus(BusFaults defaults, std::vector<BusFaultRule> rules, uint64_t seed, int64_t hold_us);

  // A message received at now_us. Counters: received, dropped, duplicated, reordered, delayed, each
  // also per channel ("dropped:POSE").
  void push(const std::string& channel, const uint8_t* data, size_t size, int64_t now_us);
  // The messages due at now_us (held ones whose hold expired included), in the order to send them.
  std::vector<Message> takeDue(int64_t now_us);
  // Everything held (sent at now_us) or queued, in order: the end, nothing is lost that was not
  // dropped.
  std::vector<Message> drain(int64_t now_us);
  // When the next queued message is due; nullopt when none is queued (held ones are not counted).
  std::optional<int64_t> nextDue() const;

  // received, published (taken out), dropped, duplicated, reordered, reorder_expired, delayed; and
  // received:<CH>, dropped:<CH>, duplicated:<CH>, reordered:<CH> from their first event.
  const std::map<std::string, int64_t>& counters() const { return counters_; }

 private:
  struct Held {
    Message msg;
    int copies = 1;
    int64_t expires_us = 0;
  };
  struct Channel {
    const BusFaults* faults = nullptr;
    SplitMix64 rng{0};
    std::optional<Held> held;
  };
  struct Due {
    int64_t at;
    uint64_t order;  // FIFO among messages due at the same time
    Message msg;
    bool operator>(const Due& o) const { return at != o.at ? at > o.at : order > o.order; }
  };

  Channel& channelState(const std::string& name);
  void schedule(int64_t at, Message m, int copies);
  void add(const std::string& counter, int64_t n = 1) { counters_[counter] += n; }

  BusFaults defaults_;
  std::vector<BusFaultRule> rules_;
  uint64_t seed_;
  int64_t hold_us_;
  std::map<std::string, Channel> channels_;
  std::priority_queue<Due, std::vector<Due>, std::greater<Due>> queue_;
  uint64_t next_order_ = 0;
  std::map<std::string, int64_t> counters_;
};

}  // namespace lanemap::sim
