// The one strict reader of lanemap's YAML configs (config/*.yaml). A YamlReader wraps a YAML map and
// knows the file it came from and where in it it is ("lidar.ground"). Every fromYaml reads its keys
// through it; a key read is remembered, and finish() refuses every key present that nobody asked
// for, so a typo is an error, never a silently kept default:
//
//   auto r = config::YamlReader::loadFile("config/bev_builder.yaml");
//   auto grid = r.section("grid");
//   grid.read("resolution_m", o.resolution_m);   // optional: absent keeps the default
//   r.finish();  // "config/bev_builder.yaml:21: unknown key 'resoluton' in 'grid'; did you mean 'resolution_m'?"
//
// Every error is a ConfigError naming the file, the line and the key:
//   "config/bev_builder.yaml:21: key 'grid.resolution_m' must be a number, not 'fine'".
// A key whose value is null (`key:` with nothing after it) counts as absent.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace lanemap::config {

class ConfigError : public std::runtime_error {
 public:
  // file: the config file ("" when read from a string); key: the dotted key ("grid.resolution_m"),
  // "" for the file itself.
  ConfigError(std::string file, std::string key, const std::string& message)
      : std::runtime_error(message), file_(std::move(file)), key_(std::move(key)) {}
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_, key_;
};

// What a value of type T must be, for the error message: "a number", "an integer", ...
template <typename T>
std::string typeDescription() {
  if constexpr (std::is_same_v<T, bool>) {
    return "true or false";
  } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
    return "a non-negative integer";
  } else if constexpr (std::is_integral_v<T>) {
    return "an integer";
  } else if constexpr (std::is_floating_point_v<T>) {
    return "a number";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "a string";
  } else if constexpr (std::is_same_v<T, std::vector<double>> || std::is_same_v<T, std::vector<float>>) {
    return "a list of numbers";
  } else if constexpr (std::is_same_v<T, std::vector<int>> || std::is_same_v<T, std::vector<int64_t>>) {
    return "a list of integers";
  } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    return "a list of strings";
  } else if constexpr (std::is_same_v<T, std::array<double, 3>>) {
    return "a list of 3 numbers";
  } else {
    return "a value of another type";
  }
}

class YamlReader {
 public:
  // Loads `path`. A missing or unreadable file, a YAML syntax error or a document that is not a map
  // (an empty file is an empty map) throws ConfigError naming the file.
  static YamlReader loadFile(const std::string& path);
  // Over a node already loaded; `file` names it in errors (empty: "config"). A null or undefined
  // node is an empty map; any other non-map throws ConfigError.
  explicit YamlReader(const YAML::Node& node, std::string file = "", std::string path = "");

  const std::string& file() const { return s_->file; }
  const std::string& path() const { return s_->path; }  // "" at the top, "lidar.ground" below
  // The dotted name of `key` here: "lidar.ground.sectors".
  std::string keyPath(const std::string& key) const { return s_->path.empty() ? key : s_->path + "." + key; }
  // Whether the map was given at all (false for a missing section).
  bool present() const { return s_->node.IsDefined() && !s_->node.IsNull(); }
  const YAML::Node& node() const { return s_->node; }

  // Whether `key` is present with a non-null value. Marks it as known.
  bool has(const std::string& key) const;
  // Sets `value` from `key` when present (true); absent keeps `value` (false). A value of the wrong
  // type throws ConfigError "FILE:LINE: key 'a.b' must be a number, not 'x'".
  template <typename T>
  bool read(const std::string& key, T& value) const {
    const YAML::Node v = raw(key);
    if (!v.IsDefined() || v.IsNull()) return false;
    try {
      value = v.as<T>();
    } catch (const YAML::Exception&) {
      fail(key, v, "must be " + typeDescription<T>() + ", not " + describe(v));
    }
    return true;
  }
  template <typename T>
  T get(const std::string& key, T fallback) const {
    read(key, fallback);
    return fallback;
  }
  // As get, but an absent key throws ConfigError "... key 'a.b' is required".
  template <typename T>
  T required(const std::string& key) const {
    T value{};
    if (!read(key, value)) fail(key, "is required");
    return value;
  }

  // The map under `key` (a missing or null key: an empty, absent section). Not a map: ConfigError.
  // Its keys are checked by this reader's finish().
  YamlReader section(const std::string& key) const;
  // The raw node under `key` (marks the key known; its content is the caller's to check).
  YAML::Node raw(const std::string& key) const;
  // Marks keys as known without reading them (read by another reader of the same file).
  void allow(std::initializer_list<const char*> keys) const;

  // Throws ConfigError for the first key present here or in a section that was never asked for:
  // "FILE:LINE: unknown key 'resoluton' in 'grid'; did you mean 'resolution_m'?" (with no close
  // match: the keys known there).
  void finish() const;
  // finish() for the sections only, not this map's own keys (a reader of part of a file).
  void finishSections() const;

  // Throws ConfigError for `key` with `what` ("must be > 0"), naming the file, the key's line and
  // the key: for the checks a fromYaml makes on the values it read.
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  // Throws ConfigError for this map as a whole ("FILE:LINE: 'explorer': what"): for checks over
  // several keys.
  [[noreturn]] void failHere(const std::string& what) const;

 private:
  struct State {
    YAML::Node node;
    std::string file, path;
    std::set<std::string> known;
    std::map<std::string, std::shared_ptr<State>> sections;
  };
  explicit YamlReader(std::shared_ptr<State> s) : s_(std::move(s)) {}
  [[noreturn]] void fail(const std::string& key, const YAML::Node& at, const std::string& what) const;
  static std::string describe(const YAML::Node& v);
  std::string where(const YAML::Node& at) const;
  static void finishState(const State& s);

  std::shared_ptr<State> s_;
};

}  // namespace lanemap::config
