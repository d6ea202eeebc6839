// Keeps SIGINT/SIGTERM away from the thread that runs Process::spin(): spin() treats an interrupted
// LCM wait as a failure (exit 1), so the main thread blocks the stop signals and a worker thread
// takes them instead (the handler still sets the stop flag; the worker's poll() just returns).
#pragma once

#include <signal.h>

#include <pthread.h>

namespace lanemap {

inline void setStopSignalsBlocked(bool blocked) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(blocked ? SIG_BLOCK : SIG_UNBLOCK, &set, nullptr);
}

}  // namespace lanemap
