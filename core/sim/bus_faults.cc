#include "core/sim/bus_faults.h"

#include <sstream>
#include <stdexcept>

namespace lanemap::sim {

namespace {

uint64_t fnv1a(const std::string& s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

}  // namespace

void BusFaults::validate(const std::string& where) const {
  for (double p : {drop, duplicate, reorder}) {
    if (!(p >= 0.0 && p <= 1.0)) throw std::runtime_error(where + ": rates must be in [0, 1]");
  }
  if (!(delay_ms >= 0.0) || !(jitter_ms >= 0.0) || jitter_ms > delay_ms) {
    throw std::runtime_error(where + ": need 0 <= jitter_ms <= delay_ms");
  }
}

BusFaultRule parseBusFaultRule(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) {
    throw std::runtime_error("--rule '" + text + "': expected REGEX:key=value,...");
  }
  BusFaultRule r;
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

uint64_t SplitMix64::next() {
  uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double SplitMix64::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

LossyBus::LossyBus(BusFaults defaults, std::vector<BusFaultRule> rules, uint64_t seed, int64_t hold_us)
    : defaults_(defaults), rules_(std::move(rules)), seed_(seed), hold_us_(hold_us) {
  for (const char* c : {"received", "published", "dropped", "duplicated", "reordered", "reorder_expired", "delayed"}) counters_[c] = 0;
}

void LossyBus::push(const std::string& channel, const uint8_t* data, size_t size, int64_t now_us) {
  Channel& ch = channelState(channel);
  add("received");
  add("received:" + channel);
  const BusFaults& f = *ch.faults;
  // Always four draws per message, whatever the rates, so one decision does not shift the others.
  const double u_drop = ch.rng.uniform(), u_dup = ch.rng.uniform(), u_reorder = ch.rng.uniform(), u_delay = ch.rng.uniform();
  if (u_drop < f.drop) {
    add("dropped");
    add("dropped:" + channel);
    return;
  }
  Message m{channel, std::vector<uint8_t>(data, data + size), 0};
  const int copies = u_dup < f.duplicate ? 2 : 1;
  if (copies == 2) {
    add("duplicated");
    add("duplicated:" + channel);
  }
  int64_t delay_us = 0;
  if (f.delay_ms > 0) {
    const double ms = f.delay_ms + (2.0 * u_delay - 1.0) * f.jitter_ms;
    delay_us = static_cast<int64_t>(ms * 1000.0);
    add("delayed");
  }
  if (ch.held) {  // this message overtakes the one held back
    schedule(now_us + delay_us, std::move(m), copies);
    schedule(now_us + delay_us, std::move(ch.held->msg), ch.held->copies);
    ch.held.reset();
    add("reordered");
    add("reordered:" + channel);
    return;
  }
  if (u_reorder < f.reorder) {
    // Held back (with its duplicate) until the next message of the channel overtakes it, or
    // hold_us passes and it is sent in order after all.
    ch.held = Held{std::move(m), copies, now_us + hold_us_};
    return;
  }
  schedule(now_us + delay_us, std::move(m), copies);
}

std::vector<LossyBus::Message> LossyBus::takeDue(int64_t now_us) {
  for (auto& [name, ch] : channels_) {
    if (ch.held && ch.held->expires_us <= now_us) {  // nothing overtook it: sent late, in order
      schedule(now_us, std::move(ch.held->msg), ch.held->copies);
      ch.held.reset();
      add("reorder_expired");
    }
  }
  std::vector<Message> out;
  while (!queue_.empty() && queue_.top().at <= now_us) {
    out.push_back(queue_.top().msg);
    out.back().due_us = queue_.top().at;
    queue_.pop();
    add("published");
  }
  return out;
}

std::vector<LossyBus::Message> LossyBus::drain(int64_t now_us) {
  for (auto& [name, ch] : channels_) {
    if (ch.held) schedule(now_us, std::move(ch.held->msg), ch.held->copies);
    ch.held.reset();
  }
  std::vector<Message> out;
  while (!queue_.empty()) {
    out.push_back(queue_.top().msg);
    out.back().due_us = queue_.top().at;
    queue_.pop();
    add("published");
  }
  return out;
}

std::optional<int64_t> LossyBus::nextDue() const {
  if (queue_.empty()) return std::nullopt;
  return queue_.top().at;
}

LossyBus::Channel& LossyBus::channelState(const std::string& name) {
  auto it = channels_.find(name);
  if (it != channels_.end()) return it->second;
  Channel ch;
  ch.faults = &defaults_;
  for (const BusFaultRule& r : rules_) {
    if (std::regex_match(name, r.re)) {
      ch.faults = &r.faults;
      break;
    }
  }
  ch.rng = SplitMix64{seed_ ^ fnv1a(name)};
  return channels_.emplace(name, std::move(ch)).first->second;
}

void LossyBus::schedule(int64_t at, Message m, int copies) {
  for (int i = 0; i < copies; ++i) {
    queue_.push(Due{at, next_order_++, i + 1 < copies ? m : std::move(m)});
  }
}

}  // namespace lanemap::sim
