// The launch configuration (tools/launch/config.h loadLaunch, lanemap-launch's parser: YAML, vars,
// ${...} substitution, hosts, restart policies). Input: a launch YAML file (seeds:
// config/launch/*.yaml). Property: a bad file is a std::exception with a message (lanemap-launch
// prints it and exits 2), never a crash; a good one has processes that all run on a declared host
// with a non-empty command.
#include "fuzz/fuzz_util.h"
#include "tools/launch/config.h"

#include <algorithm>

using namespace lanemap::launch;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = lanemap::fuzz::scratchFile(data, size, "launch", ".yaml");
  try {
    const Launch l = loadLaunch(path, {}, "/nonexistent-bin", "");
    for (const Spec& s : l.processes) {
      FUZZ_CHECK(!s.resolved.empty());
      FUZZ_CHECK(std::any_of(l.hosts.begin(), l.hosts.end(), [&](const Host& h) { return h.name == s.host; }));
    }
  } catch (const std::exception& e) {
    FUZZ_CHECK(e.what() != nullptr);
  }
  return 0;
}
