#include "core/osm/coordinate_guard.h"

#include <fstream>
#include <iterator>

namespace lanemap::osm {

std::string exponentCoordinate(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::istreambuf_iterator<char> it(in), end;
  // The first non-blank byte: an XML file starts with '<'.
  while (it != end && (*it == ' ' || *it == '\n' || *it == '\r' || *it == '\t')) ++it;
  if (it == end || *it != '<') return "";
  // A small lexer: inside a tag, outside quotes, the characters before '=' are an attribute's
  // name; the quoted value after it is checked when the name is lat or lon.
  bool in_tag = false;
  char quote = 0;
  std::string name, before_blank, named, value;  // named: the attribute the value belongs to
  for (; it != end; ++it) {
    const char c = *it;
    if (quote) {
      if (c == quote) {
        if (value.find_first_of("eE") != std::string::npos) return (named + "=\"" + value).substr(0, 40) + "\"";
        quote = 0;
        value.clear();
      } else if ((named == "lat" || named == "lon") && value.size() < 64) {
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
