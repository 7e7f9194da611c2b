// Server mode (the default): the PLC is the Modbus TCP client. One thread owns the libmodbus
// context and the register map; a select() loop serves up to plc.max_clients connections at
// once. A client that stalls mid-request (plc.byte_timeout_ms), sends garbage or disconnects
// loses its own connection and costs the others nothing.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "config/config_file.hpp"
#include "core/clock.hpp"
#include "plc/register_map.hpp"

typedef struct _modbus modbus_t;
typedef struct _modbus_mapping_t modbus_mapping_t;

namespace pipeloc {

struct PlcError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A command the PLC submitted: REQ_ID changed.
struct PlcRequest {
  std::uint16_t command = 0, req_id = 0;
  Clock::time_point at{};
};

// What the server does with one received request: an exception for writes outside CMD/REQ_ID,
// else libmodbus's reply from the map (which answers reads outside it with exception 02).
// Returns modbus_reply's result (-1: the connection failed). Used by the server and the fuzzer.
int reply_to_request(modbus_t* ctx, modbus_mapping_t* mapping, int base, const std::uint8_t* query,
                     int length);
// Timeouts of a server context: a stalled request costs at most byte_timeout_ms, and libmodbus's
// flush before some exception replies (an unknown function code) sleeps 1 ms instead of its
// default 0.5 s response timeout, which would stall every client.
void set_server_timeouts(modbus_t* ctx, int byte_timeout_ms);

class ModbusServer {
 public:
  explicit ModbusServer(const PlcConfig& cfg);  // binds and listens; throws PlcError naming address:port
  ~ModbusServer();
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  // Serves requests until one submits a command (returned in *req), `wake_fd` becomes readable,
  // or timeout_ms pass. Returns true when *req holds a new command.
  bool poll(int timeout_ms, int wake_fd, PlcRequest* req);

  void set_busy();
  void publish(const reg::Result& result, std::uint16_t ack_id);
  void heartbeat();
  int clients() const { return int(clients_.size()); }
  int port() const { return port_; }
  const std::uint16_t* registers() const;

  struct Counters {
    long requests = 0, exceptions = 0, dropped = 0, refused = 0;
  };
  const Counters& counters() const { return counters_; }

 private:
  void accept_client();
  void serve_client(std::size_t i);
  void drop_client(std::size_t i);
  std::uint16_t* map();

  PlcConfig cfg_;
  modbus_t* ctx_ = nullptr;
  modbus_mapping_t* mapping_ = nullptr;
  int listen_fd_ = -1;
  int port_ = 0;
  std::vector<int> clients_;
  std::uint16_t last_req_id_ = 0;
  Counters counters_;
};

}  // namespace pipeloc
