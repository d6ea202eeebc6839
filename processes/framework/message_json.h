// lanemap's LCM messages as JSON, for the process replay references (tests/replay): what a process
// published, one object per message, in a form a reviewer can read in a diff. Decodes the outputs
// of the processes (ROAD_EVENT, BEV_ROAD, LANE_MAP, BEV_OPEN, SEMANTIC_FRONT: its pixels per
// class) by the channel registry's type; a file path in a message (the store is a temporary folder
// in a replay) is reduced to its name; a BEV_ROAD's grid file, when it is there, is summed per
// layer ("grid": what the builder stored).
// Other channels: their size and an FNV-1a hash of their bytes.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace lanemap {

// Throws std::runtime_error when a message of a known type does not decode.
nlohmann::json messageJson(const std::string& channel, const void* data, int size);

// Every event of an LCM log: {"t": event timestamp, "channel": ..., "msg": messageJson}, one per
// line. Throws std::runtime_error naming the file when it cannot be read.
std::string logJsonLines(const std::string& path);

// The differences between two such documents (reference first), one line each, naming the line and
// the field ("line 3 (ROAD_EVENT) msg.distance_m: 4.1 -> 4.2"); empty when they agree. Numbers
// agree within abs_tol + rel_tol * |reference| (floating point across compilers and libm); every
// other value, the lines' count and each object's keys exactly. At most max_lines differences.
std::vector<std::string> compareJsonLines(const std::string& reference, const std::string& actual, double abs_tol = 1e-6,
                                          double rel_tol = 1e-9, size_t max_lines = 50);

}  // namespace lanemap
