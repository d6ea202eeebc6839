// NMEA 0183 (core/gnss/nmea): a byte stream through NmeaLineSplitter, NmeaParser and PoseCombiner,
// as the GNSS driver feeds them. Input: the bytes of a serial stream. Properties: nothing throws;
// lines are at most kMaxLineLength (+ a '\r'); every line gets one status; poses are finite and in
// range.
#include "core/gnss/nmea.h"
#include "fuzz/fuzz_util.h"

#include <cmath>

using namespace lanemap::gnss;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  NmeaLineSplitter splitter;
  NmeaParser parser;
  PoseCombiner combiner;
  // Feed in two pieces, split at a byte the input chooses, like datagrams that cut a line.
  const size_t cut = size ? data[0] % (size + 1) : 0;
  splitter.feed(reinterpret_cast<const char*>(data), cut);
  splitter.feed(reinterpret_cast<const char*>(data) + cut, size - cut);
  std::string line;
  std::vector<std::string> lines;
  while (splitter.next(line)) lines.push_back(line);
  lines.push_back(splitter.flush());
  std::vector<GnssPose> poses;
  int64_t t = 1700000000000000;
  for (const auto& l : lines) {
    FUZZ_CHECK(l.size() <= kMaxLineLength + 1);
    const ParseResult r = parser.parse(l);
    FUZZ_CHECK((r.status == LineStatus::kOk) == r.sentence.has_value());
    if (r.sentence) {
      for (auto& p : combiner.add(*r.sentence, t)) poses.push_back(p);
    }
    t += 100000;
  }
  for (auto& p : combiner.flush()) poses.push_back(p);
  size_t total = 0;
  for (const auto& [name, n] : parser.statusCounts()) total += n;
  FUZZ_CHECK(total == lines.size());
  for (const GnssPose& p : poses) {
    FUZZ_CHECK(std::isfinite(p.latitude_deg) && std::abs(p.latitude_deg) <= 90.0);
    FUZZ_CHECK(std::isfinite(p.longitude_deg) && std::abs(p.longitude_deg) <= 180.0);
    for (double v : p.orientation) FUZZ_CHECK(std::isfinite(v));
    for (double v : p.position_covariance) FUZZ_CHECK(std::isfinite(v) && v >= 0.0);
    FUZZ_CHECK(p.status != FixStatus::kInvalid);
  }
  return 0;
}
