#include "core/osm/coordinate_guard.h"

#include <fstream>
#include <vector>

namespace lanemap::osm {

std::string exponentCoordinate(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  // Read in blocks (a city's Lanelet2 truth is some 150 MB; a character iterator took seconds);
  // the lexer below keeps its state from one block to the next.
  std::vector<char> block(1 << 20);
  size_t pos = 0, len = 0;
  const auto next = [&](char& c) {
    if (pos == len) {
      in.read(block.data(), static_cast<std::streamsize>(block.size()));
      len = static_cast<size_t>(in.gcount());
      pos = 0;
      if (len == 0) return false;
    }
    c = block[pos++];
    return true;
  };
  char c = 0;
  // The first non-blank byte: an XML file starts with '<'.
  bool more = next(c);
  while (more && (c == ' ' || c == '\n' || c == '\r' || c == '\t')) more = next(c);
  if (!more || c != '<') return "";
  // A small lexer: inside a tag, outside quotes, the characters before '=' are an attribute's
  // name; the quoted value after it is checked when the name is lat or lon.
  bool in_tag = false;
  char quote = 0;
  std::string name, before_blank, named, value;  // named: the attribute the value belongs to
  bool coordinate = false;                       // named is lat or lon
  for (; more; more = next(c)) {
    if (quote) {
      if (c == quote) {
        if (value.find_first_of("eE") != std::string::npos) return (named + "=\"" + value).substr(0, 40) + "\"";
        quote = 0;
        value.clear();
      } else if (coordinate && value.size() < 64) {
        value.push_back(c);
      }
      continue;
    }
    if (!in_tag) {
      in_tag = c == '<';
      name.clear();
      continue;
    }
    if (c == '>') {
      in_tag = false;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '=') {
      named = name.empty() ? before_blank : name;  // lat = "..." is XML too
      coordinate = named == "lat" || named == "lon";
      name.clear();
    } else if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '/') {
      if (!name.empty()) before_blank = name;
      name.clear();
    } else if (name.size() < 16) {
      name.push_back(c);
    }
  }
  return "";
}

}  // namespace lanemap::osm
