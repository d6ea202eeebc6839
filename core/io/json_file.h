// A lanemap JSON file read back (core/io/lane_map_json.h, core/io/passage_json.h): its text
// parsed and handed to a *FromJson function, which throws IoError on JSON that is not its own;
// every error names the file.
#pragma once

#include "core/io/atomic_file.h"
#include "core/io/read_file.h"

#include <nlohmann/json.hpp>

#include <string>

namespace lanemap::io {

template <typename From>
auto readJsonFile(const std::string& path, From from) -> decltype(from(nlohmann::json())) {
  const auto text = readFile(path);
  if (!text) throw IoError("cannot read " + path);
  const nlohmann::json j = nlohmann::json::parse(*text, nullptr, false);
  if (j.is_discarded()) throw IoError(path + " is not JSON");
  try {
    return from(j);
  } catch (const IoError& e) {
    throw IoError(path + ": " + e.what());
  }
}

}  // namespace lanemap::io
