// lanemap-port-bridge: makes a web page served inside a private network namespace reachable from
// this host's loopback. `make demo` runs the live graph (and its lanemap-viewer) inside
// `unshare -rn`, so that no LCM multicast reaches the host's network; the viewer listens on
// 127.0.0.1:8765 of that namespace, which a browser on the host cannot reach. The bridge listens on
// 127.0.0.1:LISTEN of the namespace it is started in, then joins the user and network namespaces
// of process PID (setns: allowed to the user that made them) and forwards each TCP connection to
// 127.0.0.1:PORT there. Loopback on both sides: nothing goes to a real interface. It exits when
// PID exits (or on SIGINT/SIGTERM).
//
//   lanemap-port-bridge --pid PID --port 8765 [--listen-port 8765] [--ready-file F]
#include <CLI/CLI.hpp>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace {

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

std::string errnoText() { return std::strerror(errno); }

ino_t nsInode(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? st.st_ino : 0;
}

bool alive(pid_t pid) { return ::kill(pid, 0) == 0 || errno == EPERM; }

sockaddr_in loopback(uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

// Joins namespace `kind` ("user", "net") of pid unless this process is in it already.
void join(pid_t pid, const char* kind, int nstype) {
  const std::string theirs = "/proc/" + std::to_string(pid) + "/ns/" + kind;
  if (nsInode(theirs) == nsInode(std::string("/proc/self/ns/") + kind)) return;
  const int fd = ::open(theirs.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + theirs + ": " + errnoText());
  const int rc = ::setns(fd, nstype);
  const std::string why = errnoText();
  ::close(fd);
  if (rc != 0) throw std::runtime_error(std::string("cannot join the ") + kind + " namespace of process " + std::to_string(pid) + ": " + why);
}

struct Pair {
  int client = -1, server = -1;
};

// Moves what is readable on `from` to `to`; false when `from` closed or either side failed.
bool pump(int from, int to) {
  char buf[65536];
  const ssize_t n = ::recv(from, buf, sizeof buf, 0);
  if (n <= 0) return false;
  for (ssize_t off = 0; off < n;) {
    const ssize_t w = ::send(to, buf + off, static_cast<size_t>(n - off), MSG_NOSIGNAL);
    if (w <= 0) return false;
    off += w;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Forward 127.0.0.1:LISTEN on this host to 127.0.0.1:PORT inside the network namespace of process PID"};
  int pid = 0, port = 8765, listen_port = 0, max_connections = 64;
  double wait_s = 10.0;
  std::string ready_file;
  app.add_option("--pid", pid, "a process inside the namespace (e.g. the `unshare -rn` that started the graph)")->required();
  app.add_option("--port", port, "the port listened on inside the namespace (127.0.0.1)")->capture_default_str();
  app.add_option("--listen-port", listen_port, "the port to listen on here (127.0.0.1; default: --port)");
  app.add_option("--max-connections", max_connections, "connections forwarded at once; more are refused")->capture_default_str();
  app.add_option("--wait", wait_s, "seconds to wait for PID to be in its own network namespace")->capture_default_str();
  app.add_option("--ready-file", ready_file, "write the URL here once listening and joined");
  CLI11_PARSE(app, argc, argv);
  if (listen_port == 0) listen_port = port;
  if (port < 1 || port > 65535 || listen_port < 1 || listen_port > 65535) {
    std::cerr << "lanemap-port-bridge: ports must be 1..65535\n";
    return 2;
  }
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  std::signal(SIGPIPE, SIG_IGN);
  try {
    // Listen first, in the namespace we were started in: the socket stays there after setns.
    const int listener = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const int one = 1;
    ::setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    const sockaddr_in here = loopback(static_cast<uint16_t>(listen_port));
    if (::bind(listener, reinterpret_cast<const sockaddr*>(&here), sizeof here) != 0 || ::listen(listener, 16) != 0) {
      throw std::runtime_error("cannot listen on 127.0.0.1:" + std::to_string(listen_port) + ": " + errnoText());
    }
    // The process may not have unshared yet: wait until its network namespace is not ours.
    const std::string their_net = "/proc/" + std::to_string(pid) + "/ns/net";
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
    while (alive(pid) && nsInode(their_net) == nsInode("/proc/self/ns/net")) {
      if (std::chrono::steady_clock::now() > deadline) throw std::runtime_error("process " + std::to_string(pid) + " is in this network namespace: nothing to bridge");
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (!alive(pid)) throw std::runtime_error("no process " + std::to_string(pid));
    join(pid, "user", CLONE_NEWUSER);  // single-threaded here, as setns(CLONE_NEWUSER) requires
    join(pid, "net", CLONE_NEWNET);
    const std::string url = "http://127.0.0.1:" + std::to_string(listen_port) + "/";
    if (!ready_file.empty()) std::ofstream(ready_file) << url << "\n";
    std::cerr << "lanemap-port-bridge: " << url << " -> 127.0.0.1:" << port << " in the network namespace of process " << pid << "\n";

    const sockaddr_in there = loopback(static_cast<uint16_t>(port));
    std::vector<Pair> pairs;
    int64_t forwarded = 0, refused = 0;
    while (!g_stop && alive(pid)) {
      std::vector<pollfd> fds{{listener, POLLIN, 0}};
      for (const auto& p : pairs) {
        fds.push_back({p.client, POLLIN, 0});
        fds.push_back({p.server, POLLIN, 0});
      }
      if (::poll(fds.data(), fds.size(), 500) < 0) {
        if (errno == EINTR) continue;
        throw std::runtime_error("poll: " + errnoText());
      }
      std::vector<Pair> kept;
      for (size_t i = 0; i < pairs.size(); ++i) {
        const pollfd& c = fds[1 + 2 * i];
        const pollfd& s = fds[2 + 2 * i];
        bool ok = true;
        if (c.revents & (POLLIN | POLLHUP | POLLERR)) ok = pump(pairs[i].client, pairs[i].server);
        if (ok && (s.revents & (POLLIN | POLLHUP | POLLERR))) ok = pump(pairs[i].server, pairs[i].client);
        if (ok) {
          kept.push_back(pairs[i]);
        } else {
          ::close(pairs[i].client);
          ::close(pairs[i].server);
        }
      }
      pairs.swap(kept);
      if (fds[0].revents & POLLIN) {
        const int client = ::accept4(listener, nullptr, nullptr, SOCK_CLOEXEC);
        if (client < 0) continue;
        const int server = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);  // made in the joined namespace
        if (static_cast<int>(pairs.size()) >= max_connections || server < 0 ||
            ::connect(server, reinterpret_cast<const sockaddr*>(&there), sizeof there) != 0) {
          ++refused;
          ::close(client);
          if (server >= 0) ::close(server);
          continue;
        }
        ++forwarded;
        pairs.push_back({client, server});
      }
    }
    for (const auto& p : pairs) {
      ::close(p.client);
      ::close(p.server);
    }
    ::close(listener);
    std::cerr << "lanemap-port-bridge: " << forwarded << " connections forwarded, " << refused << " refused\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "lanemap-port-bridge: " << e.what() << "\n";
    return 1;
  }
}
