// NMEA 0183 parsing and epoch combination (see nmea.h).
#include "core/gnss/nmea.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace lanemap::gnss {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kKnotsToMps = 1852.0 / 3600.0;
constexpr double kSecondsPerDay = 86400.0;

std::vector<std::string_view> splitFields(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = s.find(',', start);
    if (comma == std::string_view::npos) {
      out.push_back(s.substr(start));
      return out;
    }
    out.push_back(s.substr(start, comma - start));
    start = comma + 1;
  }
}

// A whole field as a number; nullopt if empty or not entirely a number.
std::optional<double> toDouble(std::string_view s) {
  if (s.empty()) return std::nullopt;
  if (s.front() == '+') s.remove_prefix(1);
  double v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<int> toInt(std::string_view s) {
  if (s.empty()) return std::nullopt;
  int v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// Marks a field problem while parsing one sentence.
struct FieldCheck {
  bool bad = false;
  // Optional number: empty -> nullopt; malformed -> bad.
  std::optional<double> number(std::string_view s) {
    if (s.empty()) return std::nullopt;
    auto v = toDouble(s);
    if (!v) bad = true;
    return v;
  }
};

LineStatus parseGga(const std::vector<std::string_view>& f, GgaData& out) {
  if (f.size() < 12) return LineStatus::kTooFewFields;  // through the geoid separation's unit
  FieldCheck check;
  if (!f[0].empty()) {
    out.utc_seconds = parseNmeaTime(f[0]);
    if (!out.utc_seconds) return LineStatus::kBadField;
  }
  if (!f[1].empty() || !f[3].empty()) {
    out.latitude_deg = parseNmeaAngle(f[1], f[2], true);
    out.longitude_deg = parseNmeaAngle(f[3], f[4], false);
    if (!out.latitude_deg || !out.longitude_deg) return LineStatus::kBadField;
  }
  if (!f[5].empty()) {
    auto q = toInt(f[5]);
    if (!q || *q < 0 || *q > 9) return LineStatus::kBadField;
    out.fix_quality = *q;
  }
  if (!f[6].empty()) {
    auto n = toInt(f[6]);
    if (!n || *n < 0) return LineStatus::kBadField;
    out.satellites = *n;
  }
  out.hdop = check.number(f[7]);
  out.altitude_msl_m = check.number(f[8]);
  out.geoid_separation_m = check.number(f[10]);
  if (check.bad || (out.hdop && *out.hdop < 0)) return LineStatus::kBadField;
  return LineStatus::kOk;
}

LineStatus parseRmc(const std::vector<std::string_view>& f, RmcData& out) {
  if (f.size() < 9) return LineStatus::kTooFewFields;  // through the date
  FieldCheck check;
  if (!f[0].empty()) {
    out.utc_seconds = parseNmeaTime(f[0]);
    if (!out.utc_seconds) return LineStatus::kBadField;
  }
  if (f[1] == "A") {
    out.valid = true;
  } else if (f[1] != "V" && !f[1].empty()) {
    return LineStatus::kBadField;
  }
  if (!f[2].empty() || !f[4].empty()) {
    out.latitude_deg = parseNmeaAngle(f[2], f[3], true);
    out.longitude_deg = parseNmeaAngle(f[4], f[5], false);
    if (!out.latitude_deg || !out.longitude_deg) return LineStatus::kBadField;
  }
  if (auto kn = check.number(f[6])) out.speed_mps = *kn * kKnotsToMps;
  out.course_deg = check.number(f[7]);
  if (check.bad || (out.speed_mps && *out.speed_mps < 0)) return LineStatus::kBadField;
  if (!f[8].empty()) {
    auto d = toInt(f[8]);
    if (f[8].size() != 6 || !d) return LineStatus::kBadField;
    const int day = *d / 10000, month = (*d / 100) % 100, yy = *d % 100;
    if (day < 1 || day > 31 || month < 1 || month > 12) return LineStatus::kBadField;
    out.date = Date{yy < 80 ? 2000 + yy : 1900 + yy, month, day};
  }
  return LineStatus::kOk;
}

LineStatus parseHdt(const std::vector<std::string_view>& f, HdtData& out) {
  if (f.size() < 2) return LineStatus::kTooFewFields;
  auto h = toDouble(f[0]);
  if (!h || *h < 0 || *h > 360.0 || (f[1] != "T" && !f[1].empty())) return LineStatus::kBadField;
  out.heading_deg = *h;
  return LineStatus::kOk;
}

LineStatus parseVtg(const std::vector<std::string_view>& f, VtgData& out) {
  if (f.size() < 8) return LineStatus::kTooFewFields;
  FieldCheck check;
  out.course_true_deg = check.number(f[0]);
  const auto knots = check.number(f[4]);
  const auto kmh = check.number(f[6]);
  if (check.bad) return LineStatus::kBadField;
  if (kmh) {
    out.speed_mps = *kmh / 3.6;
  } else if (knots) {
    out.speed_mps = *knots * kKnotsToMps;
  }
  if (out.speed_mps && *out.speed_mps < 0) return LineStatus::kBadField;
  return LineStatus::kOk;
}

// Days since 1970-01-01 of a civil date (H. Hinnant's algorithm).
int64_t daysFromCivil(int y, int m, int d) {
  y -= m <= 2;
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const int64_t yoe = y - era * 400;
  const int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

}  // namespace

const char* toString(LineStatus status) {
  switch (status) {
    case LineStatus::kOk:
      return "ok";
    case LineStatus::kIgnored:
      return "ignored";
    case LineStatus::kNoStart:
      return "no_start";
    case LineStatus::kBadCharacters:
      return "bad_characters";
    case LineStatus::kTooLong:
      return "too_long";
    case LineStatus::kTruncated:
      return "truncated";
    case LineStatus::kBadChecksum:
      return "bad_checksum";
    case LineStatus::kUnknownTalker:
      return "unknown_talker";
    case LineStatus::kTooFewFields:
      return "too_few_fields";
    case LineStatus::kBadField:
      return "bad_field";
  }
  return "unknown";
}

uint8_t nmeaChecksum(std::string_view body) {
  uint8_t sum = 0;
  for (char c : body) sum ^= static_cast<uint8_t>(c);
  return sum;
}

std::optional<double> parseNmeaAngle(std::string_view value, std::string_view hemisphere,
                                     bool is_latitude) {
  const std::size_t dot = value.find('.');
  const std::size_t int_digits = dot == std::string_view::npos ? value.size() : dot;
  const std::size_t deg_digits = is_latitude ? 2 : 3;
  if (int_digits != deg_digits + 2) return std::nullopt;  // ddmm / dddmm
  auto deg = toInt(value.substr(0, deg_digits));
  auto min = toDouble(value.substr(deg_digits));
  if (!deg || !min || *deg < 0 || *min < 0 || *min >= 60.0) return std::nullopt;
  double v = *deg + *min / 60.0;
  if (v > (is_latitude ? 90.0 : 180.0)) return std::nullopt;
  if (hemisphere == (is_latitude ? "S" : "W")) {
    v = -v;
  } else if (hemisphere != (is_latitude ? "N" : "E")) {
    return std::nullopt;
  }
  return v;
}

std::optional<double> parseNmeaTime(std::string_view value) {
  const std::size_t dot = value.find('.');
  if ((dot == std::string_view::npos ? value.size() : dot) != 6) return std::nullopt;
  auto hh = toInt(value.substr(0, 2));
  auto mm = toInt(value.substr(2, 2));
  auto ss = toDouble(value.substr(4));
  if (!hh || !mm || !ss || *hh > 23 || *mm > 59 || *ss < 0 || *ss >= 61.0) return std::nullopt;
  if (value[0] == '-' || value[2] == '-' || value[4] == '-') return std::nullopt;
  return *hh * 3600.0 + *mm * 60.0 + *ss;
}

// --- NmeaParser ----------------------------------------------------------------------------------

NmeaParser::NmeaParser() : NmeaParser({"GP", "GN", "GL", "GA", "GB", "BD", "GQ", "HE", "IN"}) {}

NmeaParser::NmeaParser(std::set<std::string> talkers) : talkers_(std::move(talkers)) {}

std::size_t NmeaParser::rejected() const {
  std::size_t n = 0;
  for (const auto& [name, count] : status_counts_) {
    if (name != "ok" && name != "ignored") n += count;
  }
  return n;
}

ParseResult NmeaParser::parse(std::string_view line) {
  ParseResult r = parseChecked(line);
  ++status_counts_[toString(r.status)];
  if (r.sentence) ++sentence_counts_[r.sentence->type];
  return r;
}

ParseResult NmeaParser::parseChecked(std::string_view line) {
  ParseResult r;
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n' || line.back() == ' ')) {
    line.remove_suffix(1);
  }
  auto fail = [&r](LineStatus s) {
    r.status = s;
    return r;
  };
  if (line.empty()) return fail(LineStatus::kIgnored);
  if (line.size() > kMaxLineLength) return fail(LineStatus::kTooLong);
  if (line.front() != '$') return fail(LineStatus::kNoStart);
  for (char c : line) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u > 0x7E) return fail(LineStatus::kBadCharacters);
  }
  const std::size_t star = line.rfind('*');
  if (star == std::string_view::npos || star + 3 != line.size())
    return fail(LineStatus::kTruncated);
  const int hi = hexDigit(line[star + 1]), lo = hexDigit(line[star + 2]);
  if (hi < 0 || lo < 0) return fail(LineStatus::kTruncated);
  const std::string_view body = line.substr(1, star - 1);
  if (nmeaChecksum(body) != static_cast<uint8_t>(hi * 16 + lo))
    return fail(LineStatus::kBadChecksum);

  auto fields = splitFields(body);
  const std::string_view address = fields.front();
  if (!address.empty() && address.front() == 'P') return fail(LineStatus::kIgnored);  // proprietary
  if (address.size() != 5) return fail(LineStatus::kBadField);
  const std::string talker(address.substr(0, 2)), type(address.substr(2));
  if (!talkers_.count(talker)) return fail(LineStatus::kUnknownTalker);
  fields.erase(fields.begin());

  Sentence s;
  s.talker = talker;
  s.type = type;
  LineStatus status;
  if (type == "GGA") {
    GgaData d;
    status = parseGga(fields, d);
    s.data = d;
  } else if (type == "RMC") {
    RmcData d;
    status = parseRmc(fields, d);
    s.data = d;
  } else if (type == "HDT") {
    HdtData d;
    status = parseHdt(fields, d);
    s.data = d;
  } else if (type == "VTG") {
    VtgData d;
    status = parseVtg(fields, d);
    s.data = d;
  } else {
    return fail(LineStatus::kIgnored);
  }
  if (status != LineStatus::kOk) return fail(status);
  r.sentence = std::move(s);
  return r;
}

// --- NmeaLineSplitter --------------------------------------------------------------------------

void NmeaLineSplitter::feed(const char* data, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) {
    const char c = data[i];
    if (c == '\n') {
      if (!discarding_) {
        if (!partial_.empty() && partial_.back() == '\r') partial_.pop_back();
        lines_.push_back(std::move(partial_));
      }
      partial_.clear();
      discarding_ = false;
      continue;
    }
    if (discarding_) continue;
    partial_.push_back(c);
    if (partial_.size() > kMaxLineLength + 1) {  // +1: a '\r' may still come
      ++oversize_;
      partial_.clear();
      discarding_ = true;
    }
  }
}

bool NmeaLineSplitter::next(std::string& line) {
  if (read_ >= lines_.size()) {
    lines_.clear();
    read_ = 0;
    return false;
  }
  line = std::move(lines_[read_++]);
  return true;
}

std::string NmeaLineSplitter::flush() {
  std::string rest = discarding_ ? std::string() : std::move(partial_);
  partial_.clear();
  discarding_ = false;
  return rest;
}

// --- pose ----------------------------------------------------------------------------------------

FixStatus fixStatusFromQuality(int q) {
  switch (q) {
    case 1:
      return FixStatus::kSingle;
    case 2:
      return FixStatus::kDgnss;
    case 3:
      return FixStatus::kSingle;  // PPS fix: a precise single-point fix
    case 4:
      return FixStatus::kRtkFixed;
    case 5:
      return FixStatus::kRtkFloat;
    case 6:
      return FixStatus::kDeadReckoning;
    case 8:
      return FixStatus::kSimulated;
    default:
      return FixStatus::kInvalid;  // 0 invalid, 7 manual input
  }
}

double yawFromHeadingDeg(double heading_deg) {
  double yaw = (90.0 - heading_deg) * kDegToRad;
  yaw = std::remainder(yaw, 2.0 * kPi);  // (-pi, pi]
  if (yaw <= -kPi) yaw += 2.0 * kPi;
  return yaw;
}

std::array<double, 4> quaternionFromYaw(double yaw_rad) {
  return {std::cos(yaw_rad / 2.0), 0.0, 0.0, std::sin(yaw_rad / 2.0)};
}

void CombinerOptions::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw NmeaError(std::string("NMEA combiner option ") + name + " must be > 0, got " +
                      std::to_string(v));
    }
  };
  positive(uere_single_m, "uere_single_m");
  positive(uere_dgnss_m, "uere_dgnss_m");
  positive(uere_rtk_float_m, "uere_rtk_float_m");
  positive(uere_rtk_fixed_m, "uere_rtk_fixed_m");
  positive(uere_dead_reckoning_m, "uere_dead_reckoning_m");
  positive(vertical_factor, "vertical_factor");
  positive(heading_sigma_deg, "heading_sigma_deg");
  positive(course_heading_sigma_deg, "course_heading_sigma_deg");
  positive(roll_pitch_sigma_deg, "roll_pitch_sigma_deg");
  if (!(min_speed_for_course_mps >= 0.0)) {
    throw NmeaError("NMEA combiner option min_speed_for_course_mps must be >= 0");
  }
}

PoseCombiner::PoseCombiner(CombinerOptions options) : options_(options) { options_.validate(); }

std::set<std::string> PoseCombiner::Epoch::types() const {
  std::set<std::string> t;
  if (gga) t.insert("GGA");
  if (rmc) t.insert("RMC");
  if (hdt) t.insert("HDT");
  if (vtg) t.insert("VTG");
  return t;
}

void PoseCombiner::store(const Sentence& sentence) {
  if (const auto* gga = std::get_if<GgaData>(&sentence.data)) {
    current_.gga = *gga;
  } else if (const auto* rmc = std::get_if<RmcData>(&sentence.data)) {
    current_.rmc = *rmc;
    if (rmc->date && rmc->utc_seconds) {
      date_ = rmc->date;
      date_utc_seconds_ = *rmc->utc_seconds;
    }
  } else if (const auto* hdt = std::get_if<HdtData>(&sentence.data)) {
    current_.hdt = *hdt;
  } else if (const auto* vtg = std::get_if<VtgData>(&sentence.data)) {
    current_.vtg = *vtg;
  }
}

bool PoseCombiner::complete(const Epoch& e) const {
  if (expected_types_.empty() || !e.utc_seconds) return false;
  const auto have = e.types();
  return std::includes(have.begin(), have.end(), expected_types_.begin(), expected_types_.end());
}

std::vector<GnssPose> PoseCombiner::add(const Sentence& sentence, int64_t receive_utime) {
  std::vector<GnssPose> out;
  std::optional<double> t;
  if (const auto* gga = std::get_if<GgaData>(&sentence.data)) t = gga->utc_seconds;
  if (const auto* rmc = std::get_if<RmcData>(&sentence.data)) t = rmc->utc_seconds;

  if (t) {
    const bool new_time = !current_.utc_seconds || std::abs(*current_.utc_seconds - *t) > 5e-4;
    if (current_.utc_seconds && new_time) {  // the open epoch closes
      if (!current_emitted_) emit(out);
      expected_types_ = current_.types();
      current_ = Epoch{};
      current_emitted_ = false;
    }
    if (current_emitted_) return out;  // a repeat of an already emitted epoch's sentence
    if (!current_.utc_seconds) current_.receive_utime = receive_utime;
    current_.utc_seconds = t;
  } else if (current_emitted_) {  // untimed, after the emission: for the next epoch
    current_ = Epoch{};
    current_emitted_ = false;
  }
  if (!current_.utc_seconds && current_.receive_utime == 0) current_.receive_utime = receive_utime;
  store(sentence);
  if (!current_emitted_ && complete(current_)) emit(out);
  return out;
}

std::vector<GnssPose> PoseCombiner::flush() {
  std::vector<GnssPose> out;
  if (!current_emitted_ && current_.utc_seconds) emit(out);
  current_ = Epoch{};
  current_emitted_ = false;
  return out;
}

void PoseCombiner::emit(std::vector<GnssPose>& out) {
  current_emitted_ = true;
  if (auto pose = toPose(current_)) {
    out.push_back(*pose);
    ++emitted_;
  } else {
    ++no_fix_;
  }
}

int64_t PoseCombiner::utimeOf(double t, int64_t receive_utime) const {
  int64_t day;
  if (date_) {
    day = daysFromCivil(date_->year, date_->month, date_->day);
    if (t < date_utc_seconds_ - kSecondsPerDay / 2) ++day;  // past midnight, before the next RMC
  } else {
    const double recv_s = static_cast<double>(receive_utime) * 1e-6;
    day = static_cast<int64_t>(std::floor(recv_s / kSecondsPerDay));
    const double recv_tod = recv_s - static_cast<double>(day) * kSecondsPerDay;
    if (t - recv_tod > kSecondsPerDay / 2) --day;
    if (t - recv_tod < -kSecondsPerDay / 2) ++day;
  }
  return day * 86400000000LL + static_cast<int64_t>(std::llround(t * 1e6));
}

std::optional<GnssPose> PoseCombiner::toPose(const Epoch& e) const {
  GnssPose p;
  int quality = 0;
  if (e.gga && e.gga->latitude_deg) {
    p.latitude_deg = *e.gga->latitude_deg;
    p.longitude_deg = *e.gga->longitude_deg;
    quality = e.gga->fix_quality;
    p.altitude_m = e.gga->altitude_msl_m.value_or(0.0) + e.gga->geoid_separation_m.value_or(0.0);
    p.satellites = e.gga->satellites;
  } else if (e.rmc && e.rmc->latitude_deg) {
    p.latitude_deg = *e.rmc->latitude_deg;
    p.longitude_deg = *e.rmc->longitude_deg;
    quality = e.rmc->valid ? 1 : 0;
  } else {
    return std::nullopt;  // no position in this epoch
  }
  p.status = fixStatusFromQuality(quality);
  if (p.status == FixStatus::kInvalid && !options_.publish_invalid) return std::nullopt;
  p.utime = utimeOf(*e.utc_seconds, e.receive_utime);

  // Position covariance: sigma = HDOP x UERE of the fix type (no HDOP: a pessimistic 5).
  p.hdop = e.gga && e.gga->hdop ? *e.gga->hdop : 5.0;
  double uere = options_.uere_single_m;
  switch (p.status) {
    case FixStatus::kDgnss:
      uere = options_.uere_dgnss_m;
      break;
    case FixStatus::kRtkFloat:
      uere = options_.uere_rtk_float_m;
      break;
    case FixStatus::kRtkFixed:
      uere = options_.uere_rtk_fixed_m;
      break;
    case FixStatus::kDeadReckoning:
      uere = options_.uere_dead_reckoning_m;
      break;
    default:
      break;
  }
  const double sh = p.hdop * uere, sv = options_.vertical_factor * sh;
  p.position_covariance = {sh * sh, 0, 0, 0, sh * sh, 0, 0, 0, sv * sv};

  // Speed and course: RMC, else VTG.
  std::optional<double> speed, course;
  if (e.rmc) {
    speed = e.rmc->speed_mps;
    course = e.rmc->course_deg;
  }
  if (e.vtg) {
    if (!speed) speed = e.vtg->speed_mps;
    if (!course) course = e.vtg->course_true_deg;
  }

  // Heading: HDT, else the course when moving fast enough for it to mean something.
  double yaw_sigma_deg = 180.0;  // unknown
  if (e.hdt) {
    p.heading_source = HeadingSource::kHdt;
    p.heading_deg = e.hdt->heading_deg;
    yaw_sigma_deg = options_.heading_sigma_deg;
  } else if (options_.use_course_as_heading && course && speed &&
             *speed >= options_.min_speed_for_course_mps) {
    p.heading_source = HeadingSource::kCourse;
    p.heading_deg = *course;
    yaw_sigma_deg = options_.course_heading_sigma_deg;
  }
  if (p.heading_source != HeadingSource::kNone) {
    p.orientation = quaternionFromYaw(yawFromHeadingDeg(p.heading_deg));
  }
  const double rp = options_.roll_pitch_sigma_deg * kDegToRad, ys = yaw_sigma_deg * kDegToRad;
  p.orientation_covariance = {rp * rp, 0, 0, 0, rp * rp, 0, 0, 0, ys * ys};

  // Velocity ENU: speed along the course (or the heading when there is no course).
  if (speed) {
    std::optional<double> dir = course;
    if (!dir && p.heading_source == HeadingSource::kHdt) dir = p.heading_deg;
    if (dir) {
      p.velocity_enu = {*speed * std::sin(*dir * kDegToRad), *speed * std::cos(*dir * kDegToRad),
                        0.0};
    }
  }
  return p;
}

}  // namespace lanemap::gnss
