// Client mode: the PLC is the Modbus TCP server and the service polls it. Every plc.poll_ms it
// reads CMD and REQ_ID; it writes the result block in one request, then STATUS, then ACK_ID, and
// the heartbeat. A PLC that cannot be reached is retried with a backoff doubling up to
// plc.reconnect_max_ms (logged); writes still owed are made once the link is back, and the
// heartbeat moving again tells the PLC side the link is up.
#pragma once

#include <cstdint>

#include "config/config_file.hpp"
#include "plc/modbus_server.hpp"

namespace pipeloc {

class PlcClientLink {
 public:
  explicit PlcClientLink(const PlcConfig& cfg);
  ~PlcClientLink();
  PlcClientLink(const PlcClientLink&) = delete;
  PlcClientLink& operator=(const PlcClientLink&) = delete;

  // One round of the link: reconnect when due, flush owed writes, read CMD/REQ_ID when the poll
  // period has passed. True when *req holds a newly submitted command.
  bool poll(PlcRequest* req);
  void set_busy();
  void publish(const reg::Result& result, std::uint16_t ack_id);
  void heartbeat();
  bool connected() const { return connected_; }
  long reconnects() const { return reconnects_; }

 private:
  bool connect();
  void disconnect(const char* why);
  bool flush();

  PlcConfig cfg_;
  modbus_t* ctx_ = nullptr;
  bool connected_ = false;
  std::uint16_t last_req_id_ = 0;
  std::uint16_t image_[reg::kSize] = {};
  bool owe_block_ = false, owe_status_ = false, owe_ack_ = false, owe_heartbeat_ = false;
  int backoff_ms_ = 100;
  long reconnects_ = 0;
  Clock::time_point next_attempt_{}, next_poll_{};
};

}  // namespace pipeloc
