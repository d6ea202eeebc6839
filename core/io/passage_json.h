// A driven passage (core/intersections/driven_passage.h: the car's path through an intersection)
// as JSON, losslessly (each coordinate the double it is): what a drive's projection
// (lanemap-offline --project-only), a shard (--shard) and the lane mapper's store
// (<store>/passages/) keep of the car's paths, so the junctions they shape come out the same
// whichever way the map is made.
#pragma once

#include "core/intersections/driven_passage.h"

#include <nlohmann/json.hpp>

#include <string>

namespace lanemap::io {

nlohmann::json passageToJson(const intersections::DrivenPassage& passage);
// Throws IoError (core/io/atomic_file.h) on JSON that is not passageToJson's.
intersections::DrivenPassage passageFromJson(const nlohmann::json& j);

// Files: written atomically; read back with the path in any error.
void writePassageJson(const intersections::DrivenPassage& passage, const std::string& path);
intersections::DrivenPassage readPassageJson(const std::string& path);

}  // namespace lanemap::io
