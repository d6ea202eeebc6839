// Starting a program with its output in a log file, for the tools that run other lanemap programs
// (lanemap-replay runs each process of a case, lanemap-city runs lanemap-offline per drive).
#pragma once

#include <fcntl.h>
#include <spawn.h>
#include <sys/types.h>
#include <sys/wait.h>

#include <string>
#include <vector>

extern char** environ;

namespace lanemap {

// Starts args (args[0]: the program's path) with stdout and stderr into `log` (truncated), in the
// folder `dir` when one is given. The pid, or -1 when it could not be started.
inline pid_t spawnLogged(const std::vector<std::string>& args, const std::string& log, const std::string& dir = "") {
  if (args.empty()) return -1;
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  if (!dir.empty()) posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  return rc == 0 ? pid : -1;
}

// A waitpid status as a shell's exit code: the exit status, or 128 + the signal.
inline int exitCode(int wait_status) {
  return WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : 128 + WTERMSIG(wait_status);
}

}  // namespace lanemap
