// lanemap-logplayer: plays an LCM log onto the bus at its recorded pace, like LCM's own
// lcm-logplayer, but reads a damaged log the way lanemap-offline does (LogReader,
// processes/framework/log_reader.h): where lcm-logplayer stops at the first bad header, this goes
// on from the next readable event and says at the end what it passed over. The launch files
// (config/launch/demo.yaml, replay.yaml) play drives with it.
//
//   lanemap-logplayer [--speed 1] [-l URL] [--max-gap 5] [-q] LOG
//
// Event i is published (timestamp_i - timestamp_0) / speed after the first (--speed 0: as fast
// as it can). A timestamp that goes back, or forward by more than --max-gap seconds of the log
// (damage, or two recordings joined), is played at once and the clock is taken from it: a bad
// timestamp never stalls the replay. Exit 0 when it played at least one event (a damaged log
// too: the report goes to stderr), 2 when the file is not an LCM log or holds no whole event.
#include "processes/framework/log_reader.h"
#include "tools/cli_checks.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdint>
#include <iostream>
#include <string>
#include <thread>

int main(int argc, char** argv) {
  CLI::App app{"Play an LCM log onto the bus at its recorded pace, going on past damage (lcm-logplayer stops there)"};
  std::string path, url;
  double speed = 1.0, max_gap_s = 5.0;
  bool quiet = false;
  app.add_option("log", path, "the LCM log file")->required();
  app.add_option("-s,--speed", speed, "pace multiplier (2: twice as fast; 0: as fast as it can)")->capture_default_str()->check(lanemap::cli::kNonNegative);
  app.add_option("-l,--lcm-url", url, "LCM URL to publish on (default $LCM_DEFAULT_URL)");
  app.add_option("--max-gap", max_gap_s, "a jump between two timestamps larger than this (s of log time) is not waited for")
      ->capture_default_str()
      ->check(lanemap::cli::kPositive);
  app.add_flag("-q,--quiet", quiet, "no summary at the end of an undamaged log");
  CLI11_PARSE(app, argc, argv);

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::cerr << "lanemap-logplayer: cannot open LCM" << (url.empty() ? std::string() : " at " + url) << "\n";
    return 2;
  }
  try {
    lanemap::LogReader log(path);
    using Clock = std::chrono::steady_clock;
    Clock::time_point wall0{};
    int64_t log0 = 0, last = 0, jumps = 0, failed = 0;
    bool started = false;
    while (const lcm::LogEvent* ev = log.next()) {
      const int64_t t = ev->timestamp;
      if (!started || t < last || static_cast<double>(t - last) * 1e-6 > max_gap_s) {
        if (started) ++jumps;
        started = true;
        wall0 = Clock::now();
        log0 = t;
      } else if (speed > 0.0) {
        std::this_thread::sleep_until(wall0 + std::chrono::microseconds(static_cast<int64_t>(static_cast<double>(t - log0) / speed)));
      }
      last = t;
      if (lcm.publish(ev->channel, ev->data, static_cast<unsigned int>(ev->datalen)) != 0) ++failed;
    }
    if (log.events() == 0) {
      std::cerr << "lanemap-logplayer: " << path << ": not an LCM log, or no whole event in it\n";
      return 2;
    }
    if (log.damaged()) {
      std::cerr << "lanemap-logplayer: warning: " << path << " is damaged, played what could be read: " << log.damageReport() << "\n";
    } else if (!quiet) {
      std::cerr << "lanemap-logplayer: " << log.events() << " events played from " << path << "\n";
    }
    if (failed > 0) std::cerr << "lanemap-logplayer: " << failed << " events LCM would not publish (too large for the URL's transport?)\n";
    if (jumps > 0) std::cerr << "lanemap-logplayer: " << jumps << " timestamp jumps (back, or over " << max_gap_s << " s) not waited for\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "lanemap-logplayer: " << e.what() << "\n";
    return 2;
  }
}
