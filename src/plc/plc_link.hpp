// The PLC side of the service, as FrameSource is the camera side: one interface, three links.
// - server: the PLC is the Modbus TCP client (ModbusServer, the default);
// - client: the service polls the PLC's registers (PlcClientLink);
// - none:   no PLC; a LOCATE every --trigger-ms, the next once the last one is published.
// The serve loop only polls the link, submits what it returns, publishes results and beats.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "config/config_file.hpp"
#include "core/clock.hpp"
#include "plc/register_map.hpp"

namespace pipeloc {

struct PlcError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A command the PLC submitted: REQ_ID changed.
struct PlcRequest {
  std::uint16_t command = 0, req_id = 0;
  Clock::time_point at{};
};

// A connected Modbus peer, for the status page.
struct PlcClientInfo {
  char ip[16] = {};
  bool plc = false;  // from plc.plc_addresses (server mode), or the PLC itself (client mode)
  long requests = 0;
  Clock::time_point connected{}, last_request{};
};

class PlcLink {
 public:
  virtual ~PlcLink() = default;
  // Serves the link until a command is submitted (returned in *req, true), `wake_fd` becomes
  // readable or timeout_ms pass. Never waits on a peer longer than that.
  virtual bool poll(int timeout_ms, int wake_fd, PlcRequest* req) = 0;
  virtual void set_busy() = 0;  // STATUS = BUSY, pose NaN
  virtual void publish(const reg::Result& result, std::uint16_t ack_id) = 0;
  virtual void heartbeat() = 0;  // HEARTBEAT + 1
  virtual std::string describe() const = 0;
  // Fills at most `max` entries of `out` with the peers connected now; returns how many.
  virtual int client_list(PlcClientInfo* out, int max) const {
    (void)out, (void)max;
    return 0;
  }
};

// The link plc.mode names; trigger_ms is the period of mode "none". Throws PlcError naming the
// address when the port cannot be bound.
std::unique_ptr<PlcLink> open_plc_link(const PlcConfig& cfg, int trigger_ms);

}  // namespace pipeloc
