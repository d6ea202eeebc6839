// NMEA 0183 parsing (core/gnss/nmea.h): hand-made sentences with checksums computed here by an
// independent function parse to exact values; bad checksums, truncated lines and garbage are
// rejected and counted by reason; the combiner turns an epoch into a pose (heading 90 deg = east
// gives yaw 0; velocity, covariance, status, utime).
#include "core/gnss/nmea.h"

#include <gtest/gtest.h>

#include <cmath>
#include <ctime>
#include <string>

namespace {

using namespace lanemap::gnss;
constexpr double kPi = 3.14159265358979323846;

// Independent checksum: XOR of every character of the body, two upper-case hex digits.
std::string nmea(const std::string& body) {
  unsigned x = 0;
  for (unsigned char c : body) x ^= c;
  char hex[3];
  std::snprintf(hex, sizeof(hex), "%02X", x);
  return "$" + body + "*" + hex;
}

template <typename T>
T dataOf(const ParseResult& r) {
  EXPECT_TRUE(r.sentence.has_value()) << toString(r.status);
  if (!r.sentence) return T{};
  return std::get<T>(r.sentence->data);
}

// Unix time of a UTC civil time (timegm: independent of the code under test).
int64_t unixUtime(int y, int mo, int d, int h, int mi, double s) {
  std::tm tm{};
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = h;
  tm.tm_min = mi;
  return static_cast<int64_t>(timegm(&tm)) * 1000000 + static_cast<int64_t>(std::llround(s * 1e6));
}

TEST(NmeaChecksum, MatchesTheClassicExamples) {
  // The textbook sentences with their published checksums.
  EXPECT_EQ(nmeaChecksum("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), 0x47);
  EXPECT_EQ(nmeaChecksum("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"), 0x6A);
  // And the test's own helper agrees on them.
  const std::string gga = nmea("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,");
  EXPECT_EQ(gga.substr(gga.size() - 3), "*47");
}

TEST(NmeaAngle, DegreesAndMinutes) {
  // 48 deg 07.038 min = 48 + 7.038/60 = 48.1173 exactly (to double rounding: 1e-12).
  EXPECT_NEAR(*parseNmeaAngle("4807.038", "N", true), 48.1173, 1e-12);
  EXPECT_NEAR(*parseNmeaAngle("4807.038", "S", true), -48.1173, 1e-12);
  EXPECT_NEAR(*parseNmeaAngle("01131.000", "E", false), 11.0 + 31.0 / 60.0, 1e-12);
  EXPECT_NEAR(*parseNmeaAngle("12218.0070", "W", false), -(122.0 + 18.007 / 60.0), 1e-12);
  EXPECT_FALSE(parseNmeaAngle("4860.000", "N", true));  // 60 minutes
  EXPECT_FALSE(parseNmeaAngle("4807.038", "E", true));  // wrong hemisphere letter
  EXPECT_FALSE(parseNmeaAngle("9107.000", "N", true));  // > 90 deg
  EXPECT_FALSE(parseNmeaAngle("807.038", "N", true));   // ddmm needs 4 digits before the point
  EXPECT_NEAR(*parseNmeaTime("123519.25"), 12 * 3600 + 35 * 60 + 19.25, 1e-9);
  EXPECT_FALSE(parseNmeaTime("126019"));  // 60 minutes
}

TEST(NmeaParser, GgaExactValues) {
  NmeaParser parser;
  const auto r =
      parser.parse("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n");
  ASSERT_EQ(r.status, LineStatus::kOk);
  EXPECT_EQ(r.sentence->talker, "GP");
  EXPECT_EQ(r.sentence->type, "GGA");
  const auto& g = dataOf<GgaData>(r);
  EXPECT_DOUBLE_EQ(*g.utc_seconds, 12 * 3600 + 35 * 60 + 19);
  EXPECT_NEAR(*g.latitude_deg, 48.1173, 1e-12);
  EXPECT_NEAR(*g.longitude_deg, 11.5166666666667, 1e-12);
  EXPECT_EQ(g.fix_quality, 1);
  EXPECT_EQ(g.satellites, 8);
  EXPECT_DOUBLE_EQ(*g.hdop, 0.9);
  EXPECT_DOUBLE_EQ(*g.altitude_msl_m, 545.4);
  EXPECT_DOUBLE_EQ(*g.geoid_separation_m, 46.9);
}

TEST(NmeaParser, RmcHdtVtgExactValues) {
  NmeaParser parser;
  const auto& rmc = dataOf<RmcData>(
      parser.parse("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A"));
  EXPECT_TRUE(rmc.valid);
  EXPECT_NEAR(*rmc.speed_mps, 22.4 * 1852.0 / 3600.0, 1e-12);  // knots -> m/s
  EXPECT_DOUBLE_EQ(*rmc.course_deg, 84.4);
  ASSERT_TRUE(rmc.date);
  EXPECT_EQ(rmc.date->year, 1994);
  EXPECT_EQ(rmc.date->month, 3);
  EXPECT_EQ(rmc.date->day, 23);

  const auto& hdt = dataOf<HdtData>(parser.parse(nmea("GNHDT,271.25,T")));
  EXPECT_DOUBLE_EQ(hdt.heading_deg, 271.25);

  const auto& vtg = dataOf<VtgData>(parser.parse("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48"));
  EXPECT_DOUBLE_EQ(*vtg.course_true_deg, 54.7);
  EXPECT_NEAR(*vtg.speed_mps, 10.2 / 3.6, 1e-12);  // the km/h field

  // Other constellations' talkers; an RMC that is void.
  EXPECT_EQ(
      parser.parse(nmea("GLGGA,000001.00,0000.000,N,00000.000,E,2,5,1.0,1.0,M,0.0,M,,")).status,
      LineStatus::kOk);
  const auto& voided = dataOf<RmcData>(parser.parse(nmea("GARMC,000001.00,V,,,,,,,010126,,,N")));
  EXPECT_FALSE(voided.valid);
  EXPECT_FALSE(voided.latitude_deg);
  EXPECT_EQ(parser.sentenceCounts().at("GGA"), 1u);
  EXPECT_EQ(parser.sentenceCounts().at("RMC"), 2u);
  EXPECT_EQ(parser.rejected(), 0u);
}

TEST(NmeaParser, RejectsAndCountsBadLinesByReason) {
  NmeaParser parser;
  const std::string good = nmea("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,");
  std::string wrong = good;
  wrong[wrong.size() - 1] = wrong.back() == '0' ? '1' : '0';  // checksum off by a digit
  std::string corrupted = good;
  corrupted[10] = '9';  // a bit flip in the body
  EXPECT_EQ(parser.parse(wrong).status, LineStatus::kBadChecksum);
  EXPECT_EQ(parser.parse(corrupted).status, LineStatus::kBadChecksum);
  EXPECT_EQ(parser.parse(good.substr(0, 30)).status, LineStatus::kTruncated);  // cut short
  EXPECT_EQ(parser.parse(good.substr(0, good.size() - 1)).status, LineStatus::kTruncated);  // "*4"
  EXPECT_EQ(parser.parse("hello world").status, LineStatus::kNoStart);
  EXPECT_EQ(parser.parse(std::string("\x01\xff\x7f$GPGGA", 9)).status, LineStatus::kNoStart);
  EXPECT_EQ(parser.parse(std::string("$GP\x01GGA*00")).status, LineStatus::kBadCharacters);
  EXPECT_EQ(parser.parse(nmea("GPGGA,123519,4807.038,N")).status, LineStatus::kTooFewFields);
  EXPECT_EQ(
      parser.parse(nmea("GPGGA,123519,48x7.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,")).status,
      LineStatus::kBadField);
  EXPECT_EQ(parser.parse(nmea("GPHDT,abc,T")).status, LineStatus::kBadField);
  EXPECT_EQ(
      parser.parse(nmea("XXGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,")).status,
      LineStatus::kUnknownTalker);
  EXPECT_EQ(parser.parse("$" + std::string(200, 'A')).status, LineStatus::kTooLong);
  // Valid but unused: ignored, not rejected.
  EXPECT_EQ(
      parser.parse(nmea("GPGSV,3,1,11,03,03,111,00,04,15,270,00,06,01,010,00,13,06,292,00")).status,
      LineStatus::kIgnored);
  EXPECT_EQ(parser.parse(nmea("PUBX,00,123519")).status, LineStatus::kIgnored);

  const auto& c = parser.statusCounts();
  EXPECT_EQ(c.at("bad_checksum"), 2u);
  EXPECT_EQ(c.at("truncated"), 2u);
  EXPECT_EQ(c.at("no_start"), 2u);
  EXPECT_EQ(c.at("bad_characters"), 1u);
  EXPECT_EQ(c.at("too_few_fields"), 1u);
  EXPECT_EQ(c.at("bad_field"), 2u);
  EXPECT_EQ(c.at("unknown_talker"), 1u);
  EXPECT_EQ(c.at("too_long"), 1u);
  EXPECT_EQ(c.at("ignored"), 2u);
  EXPECT_EQ(c.count("ok"), 0u);
  EXPECT_EQ(parser.rejected(), 12u);
}

TEST(NmeaLineSplitter, CutsChunksIntoLines) {
  NmeaLineSplitter s;
  std::string line;
  s.feed("$GPHDT,1.0,T*");
  EXPECT_FALSE(s.next(line));
  s.feed("00\r\n$GPHDT,2.0");
  ASSERT_TRUE(s.next(line));
  EXPECT_EQ(line, "$GPHDT,1.0,T*00");  // CR dropped
  EXPECT_FALSE(s.next(line));
  s.feed(std::string(500, 'x') + "\nnext\n");  // oversize: dropped whole, counted once
  ASSERT_TRUE(s.next(line));
  EXPECT_EQ(line, "next");
  EXPECT_FALSE(s.next(line));
  EXPECT_EQ(s.oversize(), 1u);
  s.feed("tail");
  EXPECT_EQ(s.flush(), "tail");
}

TEST(NmeaHeading, EastIsYawZeroAndQuaternion) {
  EXPECT_NEAR(yawFromHeadingDeg(90.0), 0.0, 1e-12);             // east
  EXPECT_NEAR(yawFromHeadingDeg(0.0), kPi / 2, 1e-12);          // north: CCW from east
  EXPECT_NEAR(yawFromHeadingDeg(180.0), -kPi / 2, 1e-12);       // south
  EXPECT_NEAR(std::abs(yawFromHeadingDeg(270.0)), kPi, 1e-12);  // west
  EXPECT_NEAR(yawFromHeadingDeg(45.0), kPi / 4, 1e-12);         // north-east
  const auto q = quaternionFromYaw(yawFromHeadingDeg(0.0));
  EXPECT_NEAR(q[0], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(q[3], std::sqrt(0.5), 1e-12);
  // The rotation of the vehicle's x axis by q points north: R(q) * (1,0,0) = (0,1,0).
  const double w = q[0], z = q[3];
  EXPECT_NEAR(1 - 2 * z * z, 0.0, 1e-12);  // east component
  EXPECT_NEAR(2 * w * z, 1.0, 1e-12);      // north component
  const auto e = quaternionFromYaw(yawFromHeadingDeg(90.0));
  EXPECT_NEAR(e[0], 1.0, 1e-12);
  EXPECT_NEAR(e[3], 0.0, 1e-12);
}

// One epoch of an RTK receiver heading east at 10 m/s (19.438 kn), course 90.
std::vector<std::string> epoch(const std::string& time, int quality,
                               const std::string& date = "231126") {
  return {nmea("GNGGA," + time + ",4807.038,N,01131.000,E," + std::to_string(quality) +
               ",12,0.8,545.4,M,46.9,M,,"),
          nmea("GNRMC," + time + ",A,4807.038,N,01131.000,E,19.438445,90.0," + date + ",,,R"),
          nmea("GNHDT,90.0,T")};
}

std::vector<GnssPose> feed(PoseCombiner& c, NmeaParser& p, const std::vector<std::string>& lines,
                           int64_t recv = 0) {
  std::vector<GnssPose> out;
  for (const auto& l : lines) {
    auto r = p.parse(l);
    EXPECT_TRUE(r.sentence) << l;
    if (!r.sentence) continue;
    for (auto& pose : c.add(*r.sentence, recv)) out.push_back(pose);
  }
  return out;
}

TEST(PoseCombiner, EpochBecomesPoseWithExactValues) {
  NmeaParser parser;
  PoseCombiner combiner;
  // First epoch: emitted when the second starts (the set of sentences per epoch is not yet known).
  EXPECT_TRUE(feed(combiner, parser, epoch("123519.00", 4)).empty());
  auto poses = feed(combiner, parser, epoch("123519.10", 4));
  // The second epoch is complete with its last sentence (same types as the first): no delay.
  ASSERT_EQ(poses.size(), 2u);
  const GnssPose& p = poses[0];
  EXPECT_EQ(p.utime, unixUtime(2026, 11, 23, 12, 35, 19.0));
  EXPECT_EQ(poses[1].utime - p.utime, 100000);
  EXPECT_NEAR(p.latitude_deg, 48.1173, 1e-12);
  EXPECT_NEAR(p.longitude_deg, 11.0 + 31.0 / 60.0, 1e-12);
  EXPECT_NEAR(p.altitude_m, 545.4 + 46.9, 1e-9);  // ellipsoidal = MSL + geoid separation
  EXPECT_EQ(p.status, FixStatus::kRtkFixed);
  EXPECT_EQ(p.heading_source, HeadingSource::kHdt);
  // Heading 90 (east) -> yaw 0 -> identity quaternion.
  EXPECT_NEAR(p.orientation[0], 1.0, 1e-12);
  EXPECT_NEAR(p.orientation[3], 0.0, 1e-12);
  // 19.438445 kn = 10.0000 m/s towards course 90: all east.
  EXPECT_NEAR(p.velocity_enu[0], 10.0, 1e-5);
  EXPECT_NEAR(p.velocity_enu[1], 0.0, 1e-9);
  // RTK fixed: sigma = HDOP 0.8 x 0.02 m; vertical twice that.
  EXPECT_NEAR(p.position_covariance[0], std::pow(0.8 * 0.02, 2), 1e-12);
  EXPECT_NEAR(p.position_covariance[4], std::pow(0.8 * 0.02, 2), 1e-12);
  EXPECT_NEAR(p.position_covariance[8], std::pow(2 * 0.8 * 0.02, 2), 1e-12);
  EXPECT_NEAR(p.orientation_covariance[8], std::pow(0.2 * kPi / 180, 2), 1e-15);
  EXPECT_EQ(p.satellites, 12);
  EXPECT_EQ(combiner.epochsEmitted(), 2u);
}

TEST(PoseCombiner, StatusFromFixQuality) {
  EXPECT_EQ(fixStatusFromQuality(0), FixStatus::kInvalid);
  EXPECT_EQ(fixStatusFromQuality(1), FixStatus::kSingle);
  EXPECT_EQ(fixStatusFromQuality(2), FixStatus::kDgnss);
  EXPECT_EQ(fixStatusFromQuality(4), FixStatus::kRtkFixed);
  EXPECT_EQ(fixStatusFromQuality(5), FixStatus::kRtkFloat);
  EXPECT_EQ(fixStatusFromQuality(6), FixStatus::kDeadReckoning);
  // Through the combiner: a no-fix epoch is dropped and counted, the float one is published
  // with the float UERE (0.3 m) in its covariance.
  NmeaParser parser;
  PoseCombiner combiner;
  auto poses = feed(combiner, parser, epoch("000000.00", 0));
  for (auto& p : feed(combiner, parser, epoch("000001.00", 5))) poses.push_back(p);
  for (auto& p : combiner.flush()) poses.push_back(p);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].status, FixStatus::kRtkFloat);
  EXPECT_NEAR(poses[0].position_covariance[0], std::pow(0.8 * 0.3, 2), 1e-12);
  EXPECT_EQ(combiner.epochsWithoutFix(), 1u);
}

TEST(PoseCombiner, CourseGivesHeadingOnlyWhenMoving) {
  NmeaParser parser;
  PoseCombiner combiner;
  const auto gga = [](const std::string& t) {
    return nmea("GPGGA," + t + ",4807.038,N,01131.000,E,1,08,1.0,545.4,M,46.9,M,,");
  };
  // 2 kn = 1.03 m/s towards course 0 (north): heading 0 from the course -> yaw +90 deg.
  auto poses =
      feed(combiner, parser,
           {gga("100000"), nmea("GPRMC,100000,A,4807.038,N,01131.000,E,2.0,0.0,010126,,,A"),
            gga("100001"), nmea("GPRMC,100001,A,4807.038,N,01131.000,E,0.5,0.0,010126,,,A")});
  for (auto& p : combiner.flush()) poses.push_back(p);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].heading_source, HeadingSource::kCourse);
  EXPECT_NEAR(poses[0].orientation[3], std::sin(kPi / 4), 1e-12);
  EXPECT_NEAR(poses[0].velocity_enu[1], 2.0 * 1852 / 3600, 1e-12);
  EXPECT_NEAR(poses[0].orientation_covariance[8], std::pow(3.0 * kPi / 180, 2), 1e-15);
  EXPECT_EQ(poses[1].heading_source, HeadingSource::kNone);  // 0.26 m/s: course is noise
  EXPECT_NEAR(poses[1].orientation[0], 1.0, 1e-12);
  EXPECT_NEAR(poses[1].orientation_covariance[8], kPi * kPi, 1e-12);
  EXPECT_EQ(poses[0].utime, unixUtime(2026, 1, 1, 10, 0, 0.0));
  // Single fix, HDOP 1.0: sigma 2.5 m.
  EXPECT_NEAR(poses[0].position_covariance[0], 6.25, 1e-12);
}

TEST(PoseCombiner, DateFromReceiveTimeBeforeAnyRmc) {
  NmeaParser parser;
  PoseCombiner combiner;
  // Received 2026-11-23 00:00:02 UTC; GGA says 23:59:59: that is the previous day.
  const int64_t recv = unixUtime(2026, 11, 23, 0, 0, 2.0);
  feed(combiner, parser, {nmea("GPGGA,235959.50,4807.038,N,01131.000,E,1,08,1.0,545.4,M,46.9,M,,")},
       recv);
  const auto poses = combiner.flush();
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].utime, unixUtime(2026, 11, 22, 23, 59, 59.5));
}

TEST(PoseCombiner, BadOptionsAreRejected) {
  CombinerOptions o;
  o.uere_single_m = -1.0;
  EXPECT_THROW({ PoseCombiner c(o); }, NmeaError);
}

}  // namespace
