// The status page's HTTP server (cpp-httplib), on threads of its own: it only copies the
// StatusBoard out and formats it, so it never touches the cycle's buffers or timing.
//   /             the page (HTML, inline SVG, reloads itself)
//   /overlay.png  the latest overlay
//   /metrics      Prometheus text format 0.0.4
//   /api/status   JSON
// Connections are served one request each (no keep-alive) by two workers, with 2 s timeouts, so a
// slow or stuck browser holds up no one for long.
#pragma once

#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "config/config_file.hpp"
#include "service/status_board.hpp"
#include "status/status_info.hpp"

namespace httplib {
class Server;
}

namespace pipeloc {

struct StatusError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The name of the server's threads (ps -L, top -H).
constexpr const char* kStatusThreadName = "pipeloc-status";

class StatusServer {
 public:
  // Binds status.address:status.port (0: any free port) and starts serving; throws StatusError
  // naming the address when it cannot.
  StatusServer(const StatusConfig& cfg, const StatusBoard& board, StatusInfo info);
  ~StatusServer();  // stops and joins
  StatusServer(const StatusServer&) = delete;
  StatusServer& operator=(const StatusServer&) = delete;

  int port() const { return port_; }
  std::string url() const;

 private:
  StatusView view() const;

  const StatusBoard& board_;
  StatusInfo info_;
  std::string address_;
  int port_ = 0;
  std::unique_ptr<httplib::Server> server_;
  std::atomic<bool> listen_returned_{false};
  std::thread thread_;
};

}  // namespace pipeloc
