// Server mode (the default): the PLC is the Modbus TCP client. One thread owns the register map
// and every socket, all non-blocking, so nothing a client does (dribbling a request byte by
// byte, stopping half-way, sending garbage, never reading its replies, opening connection after
// connection) delays another client, the heartbeat, the watchdog or shutdown:
// - each request is framed by its MBAP length in the connection's own buffer and answered once
//   complete; one not complete plc.request_timeout_ms after its first byte closes its connection;
// - the listen socket is drained each round, kAcceptsPerRound at a time; its backlog is the
//   kernel's largest (not max_clients), so connects queued while the thread is descheduled are
//   not dropped (a dropped SYN costs the client 1 s);
// - a connection without a request for plc.idle_timeout_ms is closed; TCP keepalive finds peers
//   that vanished (a PLC rebooted);
// - slots: when plc.max_clients are taken, a new connection closes one that never sent a request,
//   else the one quiet the longest;
//   connections from plc.plc_addresses are only closed to make room for another from the PLC.
// libmodbus stays the protocol layer: modbus_reply() on each framed, checked request.
#pragma once

#include <cstdint>
#include <vector>

#include "plc/modbus_request.hpp"
#include "plc/plc_link.hpp"

namespace pipeloc {

// Connection messages: at most kBurst lines per kWindowS, then one line saying how many were left out.
class LogLimiter {
 public:
  static constexpr int kBurst = 10;
  static constexpr double kWindowS = 10;
  bool allow(Clock::time_point now);

 private:
  Clock::time_point window_start_{};
  int shown_ = 0;
  long left_out_ = 0;
};

class ModbusServer : public PlcLink {
 public:
  static constexpr int kListenBacklog = 4096;   // SOMAXCONN; the kernel caps it at net.core.somaxconn
  static constexpr int kAcceptsPerRound = 256;  // then clients are served before the next ones
  static constexpr int kRequestsPerRound = 16;  // per connection, so pipelining cannot starve others

  explicit ModbusServer(const PlcConfig& cfg);  // binds and listens; throws PlcError naming address:port
  ~ModbusServer() override;
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  // Serves requests until one submits a command (returned in *req), `wake_fd` becomes readable,
  // or timeout_ms pass. Returns true when *req holds a new command.
  bool poll(int timeout_ms, int wake_fd, PlcRequest* req) override;

  void set_busy() override;
  void publish(const reg::Result& result, std::uint16_t ack_id) override;
  void heartbeat() override;
  std::string describe() const override;
  int clients() const { return int(conns_.size()); }
  int client_list(PlcClientInfo* out, int max) const override;
  int port() const { return port_; }
  const std::uint16_t* registers() const;

  struct Counters {
    long accepted = 0, requests = 0, exceptions = 0, dropped = 0, refused = 0, evicted = 0, idle_closed = 0;
  };
  const Counters& counters() const { return counters_; }

 private:
  struct Connection {
    int fd = -1;
    bool plc = false;   // from one of plc.plc_addresses
    int have = 0;       // bytes of the current request in buf
    long requests = 0;  // answered on this connection
    Clock::time_point connected{}, last_request{}, request_started{};
    char ip[16] = {};
    std::uint8_t buf[mbtcp::kMaxAduBytes] = {};
  };
  void accept_clients(Clock::time_point now);
  bool admit(bool plc, Clock::time_point now);
  void serve_client(std::size_t i, Clock::time_point now);
  int serve_ready(int timeout_ms, Clock::time_point now);
  void close_expired(Clock::time_point now);
  void drop(std::size_t i, const char* why, Clock::time_point now);
  std::uint16_t* map();

  PlcConfig cfg_;
  modbus_t* ctx_ = nullptr;
  modbus_mapping_t* mapping_ = nullptr;
  int listen_fd_ = -1;
  int port_ = 0;
  std::vector<Connection> conns_;
  std::uint16_t last_req_id_ = 0;
  Counters counters_;
  LogLimiter log_limit_;
};

}  // namespace pipeloc
