#include "core/osm/turn_lanes.h"

#include <algorithm>
#include <sstream>

namespace lanemap::osm {

LaneMovements parseTurnLane(const std::string& entry) {
  LaneMovements m;
  std::stringstream ss(entry);
  std::string tok;
  while (std::getline(ss, tok, ';')) {
    tok.erase(0, tok.find_first_not_of(' '));
    tok.erase(tok.find_last_not_of(' ') + 1);
    if (tok.empty() || tok == "none") continue;
    if (tok == "reverse") {
      m.reverse = m.specified = true;
    } else if (tok.find("merge") != std::string::npos || tok == "through") {
      m.straight = m.specified = true;
    } else if (tok.find("left") != std::string::npos) {
      m.left = m.specified = true;
    } else if (tok.find("right") != std::string::npos) {
      m.right = m.specified = true;
    }
  }
  return m;
}

std::vector<std::string> splitTurnLanes(const std::string& value) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : value) {
    if (ch == '|') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += ch;
    }
  }
  out.push_back(cur);
  return out;
}

int turnLaneCount(const std::string& value) {
  if (value.empty()) return -1;
  return static_cast<int>(std::count(value.begin(), value.end(), '|')) + 1;
}

}  // namespace lanemap::osm
