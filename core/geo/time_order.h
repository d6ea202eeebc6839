// The order of a stream of timestamps that should increase (poses, camera frames): each new utime
// is in order, a duplicate, out of order (a late or stale message: drop it), or the first message
// of a restarted stream (a log played again from its start, a receiver whose clock was reset).
// A restart is a jump backwards by more than `restart_after_s`, confirmed by `confirm` messages
// in a row that increase from there with steps no larger than `restart_after_s` -- so one stale
// message with an old time stays "out of order" and does not throw the history away.
#pragma once

#include <cstdint>

namespace lanemap::geo {

class TimeOrder {
 public:
  enum class Verdict { kInOrder, kDuplicate, kOutOfOrder, kRestart };

  explicit TimeOrder(double restart_after_s = 1.0, int confirm = 3)
      : restart_after_us_(restart_after_s * 1e6), confirm_(confirm < 1 ? 1 : confirm) {}

  // Classifies `utime` and, for kInOrder and kRestart, makes it the latest time.
  Verdict check(int64_t utime) {
    if (!have_last_ || utime > last_) {
      have_last_ = true;
      last_ = utime;
      candidates_ = 0;
      return Verdict::kInOrder;
    }
    if (utime == last_) return Verdict::kDuplicate;
    // Differences in double: hostile utimes (INT64_MIN after INT64_MAX) must not overflow.
    const double back_us = static_cast<double>(last_) - static_cast<double>(utime);
    if (back_us <= restart_after_us_) return Verdict::kOutOfOrder;
    const bool continues = candidates_ > 0 && utime > candidate_last_ &&
                           static_cast<double>(utime) - static_cast<double>(candidate_last_) <= restart_after_us_;
    candidates_ = continues ? candidates_ + 1 : 1;
    candidate_last_ = utime;
    if (candidates_ < confirm_) return Verdict::kOutOfOrder;
    last_ = utime;
    candidates_ = 0;
    return Verdict::kRestart;
  }

  bool empty() const { return !have_last_; }
  int64_t last() const { return last_; }

 private:
  double restart_after_us_;
  int confirm_;
  bool have_last_ = false;
  int64_t last_ = 0;
  int candidates_ = 0;        // messages of a possible restarted stream seen in a row
  int64_t candidate_last_ = 0;
};

}  // namespace lanemap::geo
