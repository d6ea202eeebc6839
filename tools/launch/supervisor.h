// lanemap-launch's supervisor, like libbot2's procman deputy: each process in its own process
// group with LCM_DEFAULT_URL = the launch's lcm_url, restarted per its policy (never / on-failure /
// always, with a doubling back-off; not a process exiting io::kExitStoreInUse), all stopped on
// SIGINT/SIGTERM/SIGHUP (SIGTERM, then SIGKILL after stop_timeout_s), a status table every
// status_interval_s and a line on every start and exit.
#pragma once

#include "tools/launch/config.h"

#include <string>
#include <vector>

namespace lanemap::launch {

// SIGINT, SIGTERM and SIGHUP stop a running supervise().
void stopOnSignals();

// Runs `mine` (processes of `launch`) until none runs or will restart, or a stop: 0 when every
// process ended with status 0 (and after a stop), else 1. `log_dir` not empty: each process's
// output goes to LOG_DIR/<name>.log.
int supervise(Launch launch, std::vector<Spec> mine, const std::string& log_dir, double status_interval_s);

}  // namespace lanemap::launch
