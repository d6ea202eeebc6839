// NMEA 0183 input of a GNSS receiver (or GNSS/INS), LCM-free: a byte stream is cut into lines
// (NmeaLineSplitter), each line is checked (start '$', '*hh' checksum, printable characters,
// talker id) and parsed (NmeaParser: GGA, RMC, HDT, VTG), and the sentences of one fix epoch are
// combined into one pose (PoseCombiner): WGS84 position with ellipsoidal height, orientation
// vehicle->ENU from the true heading, ENU velocity from speed and course, covariance from HDOP and
// a status from the GGA fix quality. Every rejected line is counted by reason, nothing throws on
// bad input.
//
// Conventions: heading and course are degrees clockwise from true north (NMEA); ENU yaw is
// counter-clockwise from east, so yaw = 90 deg - heading (heading 90 = east -> yaw 0).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace lanemap::gnss {

// Thrown for bad configuration values (e.g. a negative UERE), never for bad NMEA input.
class NmeaError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Why a line was not used. kIgnored lines are valid NMEA of a type we do not use (GSV, GSA ...).
enum class LineStatus : uint8_t {
  kOk,
  kIgnored,        // valid sentence of an unsupported type (or proprietary $P...)
  kNoStart,        // does not start with '$' (garbage, binary data, a split line's tail)
  kBadCharacters,  // non-printable or non-ASCII bytes
  kTooLong,        // longer than kMaxLineLength
  kTruncated,      // no "*hh" checksum at the end (line cut short)
  kBadChecksum,    // checksum does not match
  kUnknownTalker,  // talker id not accepted (see NmeaParser)
  kTooFewFields,   // checksum fine but fewer fields than the sentence type needs
  kBadField,       // a field that must be a number, hemisphere, status ... is not
};
const char* toString(LineStatus status);  // "ok", "ignored", "no_start", ..., "bad_field"

// NMEA says 82 characters; real receivers exceed it with high-precision fields. We allow more.
inline constexpr std::size_t kMaxLineLength = 160;

// XOR of the characters between '$' and '*' (exclusive), as NMEA 0183 defines the checksum.
uint8_t nmeaChecksum(std::string_view body);

// "ddmm.mmmm" + hemisphere ('N','S','E','W') -> signed decimal degrees. nullopt if malformed,
// minutes >= 60 or out of range (|lat| > 90, |lon| > 180).
std::optional<double> parseNmeaAngle(std::string_view value, std::string_view hemisphere,
                                     bool is_latitude);
// "hhmmss.sss" -> seconds of the UTC day; nullopt if malformed.
std::optional<double> parseNmeaTime(std::string_view value);

struct Date {
  int year = 0, month = 0, day = 0;  // e.g. 2026, 11, 23
};

// --- sentences ---------------------------------------------------------------------------------
struct GgaData {                      // Global positioning system fix data
  std::optional<double> utc_seconds;  // seconds of the UTC day
  std::optional<double> latitude_deg, longitude_deg;
  int fix_quality = 0;  // 0 invalid, 1 single, 2 DGNSS, 4 RTK fixed, 5 RTK float, 6 DR
  int satellites = 0;
  std::optional<double> hdop;
  std::optional<double> altitude_msl_m;      // above mean sea level (the geoid)
  std::optional<double> geoid_separation_m;  // geoid above the WGS84 ellipsoid
};
struct RmcData {  // Recommended minimum data
  std::optional<double> utc_seconds;
  bool valid = false;  // status 'A' (active) vs 'V' (void)
  std::optional<double> latitude_deg, longitude_deg;
  std::optional<double> speed_mps;   // speed over ground (from knots)
  std::optional<double> course_deg;  // course over ground, true, clockwise from north
  std::optional<Date> date;
};
struct HdtData {  // True heading
  double heading_deg = 0.0;
};
struct VtgData {  // Course and speed over ground
  std::optional<double> course_true_deg;
  std::optional<double> speed_mps;  // from the km/h field, else from knots
};
using SentenceData = std::variant<GgaData, RmcData, HdtData, VtgData>;

struct Sentence {
  std::string talker;  // "GP", "GN", ...
  std::string type;    // "GGA", "RMC", "HDT", "VTG"
  SentenceData data;
};

struct ParseResult {
  LineStatus status = LineStatus::kOk;
  std::optional<Sentence> sentence;  // set when status == kOk
};

// Parses one line (without or with trailing CR/LF). Stateless apart from the counters.
class NmeaParser {
 public:
  // Talker ids accepted. Default: GP (GPS), GN (multi-GNSS), GL (GLONASS), GA (Galileo),
  // GB/BD (BeiDou), GQ (QZSS), and HE/IN (gyro compass / INS, which send HDT).
  NmeaParser();
  explicit NmeaParser(std::set<std::string> talkers);

  ParseResult parse(std::string_view line);

  // Lines seen per status name ("ok", "bad_checksum", ...) and accepted sentences per type.
  const std::map<std::string, std::size_t>& statusCounts() const { return status_counts_; }
  const std::map<std::string, std::size_t>& sentenceCounts() const { return sentence_counts_; }
  std::size_t rejected() const;  // every status except ok and ignored

 private:
  ParseResult parseChecked(std::string_view line);
  std::set<std::string> talkers_;
  std::map<std::string, std::size_t> status_counts_;
  std::map<std::string, std::size_t> sentence_counts_;
};

// --- byte stream -> lines ----------------------------------------------------------------------
// Cuts a byte stream (serial port, UDP datagrams, file) into lines at '\n' (a '\r' before it is
// dropped). A line longer than kMaxLineLength is cut and reported once as oversize; its remainder
// up to the next newline is discarded.
class NmeaLineSplitter {
 public:
  void feed(const char* data, std::size_t size);
  void feed(std::string_view data) { feed(data.data(), data.size()); }
  bool next(std::string& line);  // the next complete line; false when none is ready
  std::string flush();           // what is left after the last newline (end of stream)
  std::size_t oversize() const { return oversize_; }

 private:
  std::string partial_;
  std::vector<std::string> lines_;
  std::size_t read_ = 0;
  bool discarding_ = false;
  std::size_t oversize_ = 0;
};

// --- epoch -> pose -----------------------------------------------------------------------------
// Status values match lanemap.pose_t's STATUS_* constants.
enum class FixStatus : int8_t {
  kInvalid = 0,
  kSingle = 1,
  kDgnss = 2,
  kRtkFloat = 3,
  kRtkFixed = 4,
  kDeadReckoning = 5,
  kSimulated = 6,
};
FixStatus fixStatusFromQuality(int gga_fix_quality);  // 1->single, 2->DGNSS, 4->RTK fixed, ...

enum class HeadingSource : uint8_t { kNone, kHdt, kCourse };

struct GnssPose {
  int64_t utime = 0;  // UTC time of the fix, microseconds since the epoch
  double latitude_deg = 0, longitude_deg = 0;
  double altitude_m = 0;  // above the WGS84 ellipsoid (MSL + geoid separation)
  std::array<double, 4> orientation{1, 0, 0, 0};  // w, x, y, z: vehicle -> ENU (yaw only)
  std::array<double, 3> velocity_enu{0, 0, 0};
  std::array<double, 9> position_covariance{};     // m^2, ENU, row-major (diagonal)
  std::array<double, 9> orientation_covariance{};  // rad^2, roll/pitch/yaw, row-major (diagonal)
  FixStatus status = FixStatus::kInvalid;
  HeadingSource heading_source = HeadingSource::kNone;
  double heading_deg = 0;  // clockwise from north, when heading_source != kNone
  int satellites = 0;
  double hdop = 0;
};

// Yaw of the vehicle in ENU (counter-clockwise from east, radians in (-pi, pi]) from a heading
// (degrees clockwise from north), and the quaternion (w, x, y, z) of that pure yaw rotation.
double yawFromHeadingDeg(double heading_deg);
std::array<double, 4> quaternionFromYaw(double yaw_rad);

struct CombinerOptions {
  // 1-sigma user equivalent range error per status (m); horizontal sigma = HDOP * UERE and the
  // vertical one is vertical_factor times that (GGA carries no VDOP; VDOP ~ 1.5-2 x HDOP).
  double uere_single_m = 2.5, uere_dgnss_m = 0.7, uere_rtk_float_m = 0.3, uere_rtk_fixed_m = 0.02,
         uere_dead_reckoning_m = 5.0;
  double vertical_factor = 2.0;
  double heading_sigma_deg = 0.2;         // HDT (dual antenna / INS)
  double course_heading_sigma_deg = 3.0;  // heading taken from the course over ground
  double roll_pitch_sigma_deg = 10.0;     // not measured by NMEA: a loose prior
  // Below this speed the course over ground is noise: no heading from it (and no velocity
  // direction: velocity stays 0).
  double min_speed_for_course_mps = 1.0;
  bool use_course_as_heading = true;  // when no HDT is available
  bool publish_invalid = false;       // emit epochs whose fix quality is 0 / RMC void
  void validate() const;              // throws NmeaError naming the bad value
};

// Groups sentences into fix epochs by their UTC time and turns each into a GnssPose.
// GGA and RMC carry the time: a new time opens a new epoch and closes the open one. HDT and VTG
// carry none: they belong to the open epoch (the one of the latest time seen), or, when that one
// was already emitted, to the next. An epoch is emitted as soon as it holds every sentence type the
// previous epoch held (so after the first epoch there is no added latency), else when it closes or
// at flush(). (A receiver sending HDT before GGA thus gets its heading one epoch late.) The date
// comes from RMC; before the first RMC the UTC date of the receive time is used.
class PoseCombiner {
 public:
  explicit PoseCombiner(CombinerOptions options = {});

  // Adds one parsed sentence received at `receive_utime` (host clock); returns the poses of the
  // epochs this completed (0, 1, or rarely 2).
  std::vector<GnssPose> add(const Sentence& sentence, int64_t receive_utime);
  std::vector<GnssPose> flush();  // end of stream: the open epoch, if usable

  std::size_t epochsEmitted() const { return emitted_; }
  std::size_t epochsWithoutFix() const { return no_fix_; }  // dropped: no position / invalid
  const CombinerOptions& options() const { return options_; }

 private:
  struct Epoch {
    std::optional<double> utc_seconds;
    std::optional<GgaData> gga;
    std::optional<RmcData> rmc;
    std::optional<HdtData> hdt;
    std::optional<VtgData> vtg;
    int64_t receive_utime = 0;
    std::set<std::string> types() const;
  };

  void store(const Sentence& sentence);
  bool complete(const Epoch& e) const;
  void emit(std::vector<GnssPose>& out);  // turns current_ into a pose (or counts it)
  std::optional<GnssPose> toPose(const Epoch& e) const;
  int64_t utimeOf(double utc_seconds, int64_t receive_utime) const;

  CombinerOptions options_;
  Epoch current_;
  bool current_emitted_ = false;
  std::set<std::string> expected_types_;  // types of the last closed epoch
  std::optional<Date> date_;
  double date_utc_seconds_ = 0;  // time of the epoch that gave date_
  std::size_t emitted_ = 0, no_fix_ = 0;
};

}  // namespace lanemap::gnss
