// Client mode: the PLC is the Modbus TCP server and the service polls it. Every plc.poll_ms it
// reads CMD and REQ_ID; it writes the result block in one request (ERROR .. QZ), HELD .. REGIONS
// in another where plc.write_held is set, then STATUS, then ACK_ID, and the heartbeat. A PLC that
// answers that second write with an exception (its registers end at QZ) is warned about once
// per connection and not written there again; the rest runs as before. A PLC that cannot be
// reached is retried with a backoff doubling up to plc.reconnect_max_ms (logged); writes still
// owed are made once the link is back, and the heartbeat moving again tells the PLC side the link
// is up.
#pragma once

#include <cstdint>

#include "config/config_file.hpp"
#include "plc/plc_link.hpp"

typedef struct _modbus modbus_t;

namespace pipeloc {

class PlcClientLink : public PlcLink {
 public:
  explicit PlcClientLink(const PlcConfig& cfg);
  ~PlcClientLink() override;
  PlcClientLink(const PlcClientLink&) = delete;
  PlcClientLink& operator=(const PlcClientLink&) = delete;

  // Waits for wake_fd up to min(timeout_ms, plc.poll_ms), then one round of the link: reconnect
  // when due, flush owed writes, read CMD/REQ_ID when the poll period has passed. True when *req
  // holds a newly submitted command.
  bool poll(int timeout_ms, int wake_fd, PlcRequest* req) override;
  void set_busy() override;
  void publish(const reg::Result& result, std::uint16_t ack_id) override;
  void heartbeat() override;
  std::string describe() const override;
  bool connected() const { return connected_; }
  // The PLC, while connected (requests: CMD/REQ_ID reads on this connection).
  int client_list(PlcClientInfo* out, int max) const override;
  long reconnects() const { return reconnects_; }

 private:
  bool connect();
  void disconnect(const char* why);
  bool flush();
  bool round(PlcRequest* req);

  PlcConfig cfg_;
  modbus_t* ctx_ = nullptr;
  bool connected_ = false;
  std::uint16_t last_req_id_ = 0;
  std::uint16_t image_[reg::kSize] = {};
  bool owe_block_ = false, owe_status_ = false, owe_ack_ = false, owe_heartbeat_ = false;
  bool plc_holds_held_ = false;  // HELD .. REGIONS are written (plc.write_held, this connection)
  int backoff_ms_ = 100;
  long reconnects_ = 0;
  Clock::time_point next_attempt_{}, next_poll_{};
  Clock::time_point connected_at_{}, last_read_{};
  long reads_ = 0;
};

}  // namespace pipeloc
