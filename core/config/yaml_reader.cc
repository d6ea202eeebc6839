#include "core/config/yaml_reader.h"

#include <algorithm>
#include <sstream>

namespace lanemap::config {

namespace {

// Levenshtein distance, for "did you mean".
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

}  // namespace

YamlReader YamlReader::loadFile(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path, "", path + ": cannot read config file (missing or unreadable)");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path, "", path + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  return YamlReader(root, path);
}

YamlReader::YamlReader(const YAML::Node& node, std::string file, std::string path)
    : s_(std::make_shared<State>(State{node, std::move(file), std::move(path), {}, {}})) {
  if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
    const std::string what = s_->path.empty() ? "the config must be a map of keys" : "'" + s_->path + "' must be a map of keys";
    throw ConfigError(s_->file, s_->path, where(node) + ": " + what + ", not " + describe(node));
  }
}

bool YamlReader::has(const std::string& key) const {
  const YAML::Node v = raw(key);
  return v.IsDefined() && !v.IsNull();
}

YAML::Node YamlReader::raw(const std::string& key) const {
  s_->known.insert(key);
  const YAML::Node& n = s_->node;
  if (!n.IsDefined() || !n.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  return n[key];
}

void YamlReader::allow(std::initializer_list<const char*> keys) const {
  for (const char* k : keys) s_->known.insert(k);
}

YamlReader YamlReader::section(const std::string& key) const {
  if (auto it = s_->sections.find(key); it != s_->sections.end()) return YamlReader(it->second);
  const YAML::Node v = raw(key);
  if (v.IsDefined() && !v.IsNull() && !v.IsMap()) fail(key, v, "must be a map of keys, not " + describe(v));
  YamlReader child(v.IsDefined() && !v.IsNull() ? v : YAML::Node(), s_->file, keyPath(key));
  s_->sections[key] = child.s_;
  return child;
}

void YamlReader::finish() const { finishState(*s_); }

void YamlReader::finishSections() const {
  for (const auto& [name, child] : s_->sections) finishState(*child);
}

void YamlReader::finishState(const State& s) {
  if (s.node.IsDefined() && s.node.IsMap()) {
    for (const auto& kv : s.node) {
      std::string key;
      try {
        key = kv.first.as<std::string>();
      } catch (const YAML::Exception&) {
        key = "?";
      }
      if (s.known.count(key)) continue;
      std::ostringstream msg;
      YamlReader at(std::make_shared<State>(s));
      msg << at.where(kv.first) << ": unknown key '" << key << "'";
      if (!s.path.empty()) msg << " in '" << s.path << "'";
      // The key it was most likely meant to be, else the keys known here.
      std::string best;
      size_t best_d = std::string::npos;
      for (const auto& k : s.known) {
        const size_t d = editDistance(key, k);
        if (d < best_d) best_d = d, best = k;
      }
      if (!best.empty() && best_d <= std::max<size_t>(2, key.size() / 3)) {
        msg << "; did you mean '" << best << "'?";
      } else if (!s.known.empty()) {
        msg << " (known:";
        for (const auto& k : s.known) msg << " " << k;
        msg << ")";
      }
      throw ConfigError(s.file, s.path.empty() ? key : s.path + "." + key, msg.str());
    }
  }
  for (const auto& [name, child] : s.sections) finishState(*child);
}

void YamlReader::fail(const std::string& key, const std::string& what) const {
  // Yaml-cpp's Node::operator= writes through references: copies only.
  const YAML::Node& n = s_->node;
  if (n.IsDefined() && n.IsMap() && n[key].IsDefined()) fail(key, n[key], what);
  fail(key, n, what);
}

void YamlReader::fail(const std::string& key, const YAML::Node& at, const std::string& what) const {
  throw ConfigError(s_->file, keyPath(key), where(at) + ": key '" + keyPath(key) + "' " + what);
}

void YamlReader::failHere(const std::string& what) const {
  throw ConfigError(s_->file, s_->path, where(s_->node) + ": " + (s_->path.empty() ? "" : "'" + s_->path + "': ") + what);
}

std::string YamlReader::where(const YAML::Node& at) const {
  // "file:line", or "line N" for a node read from a string, "config" when neither is known.
  const YAML::Mark m = at.IsDefined() ? at.Mark() : YAML::Mark::null_mark();
  if (s_->file.empty()) return m.is_null() ? std::string("config") : "line " + std::to_string(m.line + 1);
  return m.is_null() ? s_->file : s_->file + ":" + std::to_string(m.line + 1);
}

std::string YamlReader::describe(const YAML::Node& v) {
  if (!v.IsDefined() || v.IsNull()) return "nothing";
  if (v.IsMap()) return "a map";
  if (v.IsSequence()) return "a list";
  std::string s = v.Scalar();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return "'" + s + "'";
}

}  // namespace lanemap::config
