// lanemap-replay: process replay tests in openpilot's manner. Each case of tests/replay/cases.yaml
// runs one process binary over a recorded input log with --replay (processes/framework/process.h:
// an in-process bus, one input at a time, its outputs written to a log), turns what it published
// into JSON lines (processes/framework/message_json.h) and compares them with the reference kept
// in the repository (numbers within a tolerance, everything else exactly).
//
//   lanemap-replay                 every case; exit 1 when one differs from its reference
//   lanemap-replay --update        writes the new references (prints what changed first);
//                                  then `git diff tests/replay` shows it for review
//   lanemap-replay --only NAME --keep    one case (and those before it), the work folder kept
//
// A case's input is one log, a list of logs (merged in time order: the viewer takes the poses and
// what the other processes published), or none (a driver reading its own file: only what it
// publishes is recorded). output_file: JSON lines the command writes besides (the viewer's state).
#include "processes/framework/log_reader.h"
#include "processes/framework/message_json.h"
#include "processes/framework/spawn_logged.h"

#include <CLI/CLI.hpp>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

std::string expand(std::string s, const std::map<std::string, std::string>& vars) {
  for (const auto& [k, v] : vars) {
    const std::string key = "${" + k + "}";
    for (size_t p = s.find(key); p != std::string::npos; p = s.find(key, p + v.size())) s.replace(p, key.size(), v);
  }
  return s;
}

// Runs args with stdout and stderr to `log`, in `dir`; the exit status (-1: could not start).
int run(const std::vector<std::string>& args, const std::string& log, const std::string& dir) {
  const pid_t pid = lanemap::spawnLogged(args, log, dir);
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0) return -1;
  return lanemap::exitCode(status);
}

// Several input logs as one, in time order (a tie keeps the order of the list, then of the log):
// the viewer's case takes the poses and what the other processes published on them.
void mergeLogs(const std::vector<fs::path>& inputs, const std::string& out) {
  struct Event {
    int64_t t;
    size_t log, index;
    std::string channel, data;
  };
  std::vector<Event> events;
  for (size_t l = 0; l < inputs.size(); ++l) {
    lanemap::LogReader in(inputs[l].string());
    for (size_t i = 0; const lcm::LogEvent* ev = in.next(); ++i) {
      events.push_back({ev->timestamp, l, i, ev->channel, std::string(static_cast<const char*>(ev->data), static_cast<size_t>(ev->datalen))});
    }
  }
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.t < b.t; });
  lcm::LogFile log(out, "w");
  if (!log.good()) throw std::runtime_error("cannot write " + out);
  int64_t n = 0;
  for (auto& e : events) {
    lcm::LogEvent ev;
    ev.eventnum = n++;
    ev.timestamp = e.t;
    ev.channel = e.channel;
    ev.datalen = static_cast<int32_t>(e.data.size());
    ev.data = e.data.data();
    log.writeEvent(&ev);
  }
}

std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("lanemap-replay: each process over its recorded input log, its outputs against the references in tests/replay");
  std::string source = LANEMAP_SOURCE_DIR, cases = "tests/replay/cases.yaml", only, work;
  bool update = false, keep = false;
  app.add_option("--source", source, "the source tree (cases' paths are relative to it)")->capture_default_str();
  app.add_option("--cases", cases, "the case list, relative to --source or absolute")->capture_default_str();
  app.add_option("--only", only, "run the cases up to and including this one, compare this one only");
  app.add_flag("--update", update, "write the outputs as the new references (after printing what changed)");
  app.add_option("--work", work, "work folder (default: a new temporary one, removed unless --keep)");
  app.add_flag("--keep", keep, "keep the work folder");
  CLI11_PARSE(app, argc, argv);
  try {
    const fs::path src = fs::absolute(source);
    const fs::path list = fs::path(cases).is_absolute() ? fs::path(cases) : src / cases;
    const fs::path bin = fs::canonical("/proc/self/exe").parent_path();
    const bool temporary = work.empty();
    if (temporary) {
      char tmpl[] = "/tmp/lanemap-replay.XXXXXX";
      if (!mkdtemp(tmpl)) throw std::runtime_error("cannot make a temporary folder");
      work = tmpl;
    }
    fs::create_directories(work);
    const std::map<std::string, std::string> vars{{"work", fs::absolute(work).string()}, {"src", src.string()}};
    const YAML::Node doc = YAML::LoadFile(list.string());
    if (!doc["cases"] || !doc["cases"].IsSequence()) throw std::runtime_error(list.string() + ": no `cases:` list");
    const double abs_tol = doc["abs_tolerance"] ? doc["abs_tolerance"].as<double>() : 1e-6;
    const double rel_tol = doc["rel_tolerance"] ? doc["rel_tolerance"].as<double>() : 1e-9;
    int differ = 0, ran = 0;
    bool found = only.empty();
    for (const auto& c : doc["cases"]) {
      for (const auto& k : c) {
        const auto key = k.first.as<std::string>();
        if (key != "name" && key != "command" && key != "input" && key != "reference" && key != "ignore" && key != "what" &&
            key != "abs_tolerance" && key != "rel_tolerance" && key != "output_file") {
          throw std::runtime_error(list.string() + ": unknown key `" + key + "` in a case");
        }
      }
      const auto name = c["name"].as<std::string>();
      std::vector<std::string> args;
      for (const auto& a : c["command"]) args.push_back(expand(a.as<std::string>(), vars));
      if (args.empty()) throw std::runtime_error("case " + name + ": empty command");
      if (args[0].rfind("lanemap-", 0) == 0) args[0] = (bin / args[0]).string();
      const fs::path reference = src / c["reference"].as<std::string>();
      const std::string out = (fs::path(work) / (name + ".out.lcmlog")).string();
      // input: one log, a list of logs (merged in time order), or none (the command reads its own
      // input, as a driver reads a file: the process only records what it publishes).
      if (c["input"] && c["input"].IsSequence()) {
        std::vector<fs::path> logs;
        for (const auto& i : c["input"]) logs.push_back(src / expand(i.as<std::string>(), vars));
        const std::string merged = (fs::path(work) / (name + ".input.lcmlog")).string();
        mergeLogs(logs, merged);
        args.insert(args.end(), {"--replay", merged});
      } else if (c["input"]) {
        args.insert(args.end(), {"--replay", (src / expand(c["input"].as<std::string>(), vars)).string()});
      }
      args.insert(args.end(), {"--replay-out", out});
      // output_file: JSON lines the command writes besides what it publishes (compared after them).
      const std::string output_file = c["output_file"] ? expand(c["output_file"].as<std::string>(), vars) : "";
      std::set<std::string> ignore;
      if (c["ignore"]) {
        for (const auto& ch : c["ignore"]) ignore.insert(ch.as<std::string>());
      }
      const std::string log = (fs::path(work) / (name + ".log")).string();
      const int rc = run(args, log, src.string());
      ++ran;
      if (rc != 0) {
        std::printf("%s: exited with %d (see %s):\n%s", name.c_str(), rc, log.c_str(), readFile(log).c_str());
        ++differ;
        if (name == only) break;
        continue;
      }
      std::string lines;
      {
        std::istringstream all(lanemap::logJsonLines(out));
        for (std::string l; std::getline(all, l);) {
          const auto j = nlohmann::json::parse(l);
          if (!ignore.count(j["channel"].get<std::string>())) lines += l + "\n";
        }
        if (!output_file.empty()) {
          if (!fs::exists(output_file)) throw std::runtime_error("case " + name + ": the command wrote no " + output_file);
          lines += readFile(output_file);
        }
      }
      const bool compared = only.empty() || name == only;
      if (compared) {
        const std::string ref = fs::exists(reference) ? readFile(reference.string()) : std::string();
        // A case may allow more (a model's output between CPUs) than the list's default.
        const double case_abs = c["abs_tolerance"] ? c["abs_tolerance"].as<double>() : abs_tol;
        const double case_rel = c["rel_tolerance"] ? c["rel_tolerance"].as<double>() : rel_tol;
        const auto diffs = lanemap::compareJsonLines(ref, lines, case_abs, case_rel);
        const size_t n = std::count(lines.begin(), lines.end(), '\n');
        if (diffs.empty()) {
          std::printf("%s: %zu messages, as the reference\n", name.c_str(), n);
        } else {
          ++differ;
          std::printf("%s: %zu messages, not as the reference %s:\n", name.c_str(), n, reference.c_str());
          for (const auto& d : diffs) std::printf("  %s\n", d.c_str());
        }
        if (update && !diffs.empty()) {
          std::ofstream(reference, std::ios::binary) << lines;
          std::printf("%s: reference written; review it with `git diff %s`\n", name.c_str(), fs::relative(reference, src).c_str());
        }
      }
      if (name == only) {
        found = true;
        break;
      }
    }
    if (!found) throw std::runtime_error("no case named " + only + " in " + list.string());
    if (temporary && !keep) fs::remove_all(work);
    else std::printf("work folder: %s\n", work.c_str());
    std::printf("%d case(s) run, %d %s\n", ran, differ, update ? "updated" : "differ from their reference");
    return differ > 0 && !update ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-replay: %s\n", e.what());
    return 2;
  }
}
