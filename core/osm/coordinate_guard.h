// A guard in front of libosmium's XML reader. Debian's libosmium 2.18 parses a coordinate with a
// decimal exponent by multiplying by 10 once per unit of the exponent before it checks the range
// (osmium/osm/location.hpp string_to_location_coordinate): lat="49.0E11383" overflows a signed
// 64-bit integer, undefined behaviour (found by the lanelet2 fuzz harness). No OSM or Lanelet2
// writer uses exponents, so readOsm and readLanelet2 refuse a plain XML file whose node has a lat
// or lon attribute with one, before osmium reads it.
#pragma once

#include <string>

namespace lanemap::osm {

// The first lat/lon attribute (as `lat="..."`, cut to 40 characters) of the XML file at `path`
// whose value has an exponent (e or E); "" when there is none, or when the file does not start
// with '<' (compressed or PBF: not scanned). Reads the file once, as a stream.
std::string exponentCoordinate(const std::string& path);

// Throws Error(prefix + ": a coordinate in exponent notation, lat="..."") when the file has one
// (every reader in front of libosmium calls this with its own error type and message prefix).
template <class Error>
void refuseExponentCoordinate(const std::string& path, const std::string& prefix) {
  if (const std::string bad = exponentCoordinate(path); !bad.empty()) {
    throw Error(prefix + ": a coordinate in exponent notation, " + bad);
  }
}

}  // namespace lanemap::osm
