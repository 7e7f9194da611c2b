#include "plc/modbus_client.hpp"

#include <modbus/modbus.h>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>

namespace pipeloc {

PlcClientLink::PlcClientLink(const PlcConfig& cfg) : cfg_(cfg) {
  ctx_ = modbus_new_tcp(cfg.address.c_str(), cfg.port);
  if (!ctx_)
    throw PlcError("plc.address '" + cfg.address + ":" + std::to_string(cfg.port) +
                   "': " + modbus_strerror(errno));
  modbus_set_slave(ctx_, cfg.unit_id);
  const auto response_us = std::uint32_t(cfg.byte_timeout_ms) * 5000u;
  modbus_set_response_timeout(ctx_, response_us / 1000000u, response_us % 1000000u);
  const auto byte_us = std::uint32_t(cfg.byte_timeout_ms) * 1000u;
  modbus_set_byte_timeout(ctx_, byte_us / 1000000u, byte_us % 1000000u);
  reg::write_initial(cfg.encoding, image_);
  owe_block_ = owe_status_ = true;
}

PlcClientLink::~PlcClientLink() {
  if (connected_) modbus_close(ctx_);
  modbus_free(ctx_);
}

bool PlcClientLink::connect() {
  if (modbus_connect(ctx_) < 0) {
    spdlog::warn("plc: cannot reach the PLC at {}:{}: {}; next try in {} ms", cfg_.address, cfg_.port,
                 modbus_strerror(errno), backoff_ms_);
    next_attempt_ = Clock::now() + std::chrono::milliseconds(backoff_ms_);
    backoff_ms_ = std::min(2 * backoff_ms_, cfg_.reconnect_max_ms);
    return false;
  }
  connected_ = true;
  plc_holds_held_ = cfg_.write_held;
  connected_at_ = last_read_ = Clock::now();
  reads_ = 0;
  backoff_ms_ = 100;
  // Where the PLC stands: a result owed is written only if the PLC still waits for exactly it
  // (a restarted PLC must not see an old ACK_ID with an old pose); a REQ_ID it set while the
  // link was down (REQ_ID != its ACK_ID, CMD set) still runs; otherwise its REQ_ID is the baseline.
  std::uint16_t head[reg::kAckId + 1];
  if (modbus_read_registers(ctx_, cfg_.base, reg::kAckId + 1, head) != reg::kAckId + 1) {
    disconnect("reading CMD..ACK_ID");
    return false;
  }
  const std::uint16_t plc_cmd = head[reg::kCmd], plc_req = head[reg::kReqId], plc_ack = head[reg::kAckId];
  if (owe_ack_ && image_[reg::kAckId] == plc_req) {
    last_req_id_ = plc_req;
  } else {
    if (owe_ack_) spdlog::warn("plc: result for REQ_ID {} dropped: the PLC moved on", image_[reg::kAckId]);
    owe_ack_ = false;
    reg::Result none;
    none.status = reg::Status::ready;
    reg::write_result(none, plc_ack, cfg_.encoding, image_);
    owe_block_ = owe_status_ = true;
    last_req_id_ = (plc_req != plc_ack && plc_cmd != 0) ? plc_ack : plc_req;
  }
  ++reconnects_;
  spdlog::info("plc: connected to the PLC at {}:{}", cfg_.address, cfg_.port);
  return true;
}

void PlcClientLink::disconnect(const char* why) {
  spdlog::warn("plc: link to {}:{} lost while {}: {}", cfg_.address, cfg_.port, why, modbus_strerror(errno));
  modbus_close(ctx_);
  connected_ = false;
  next_attempt_ = Clock::now() + std::chrono::milliseconds(backoff_ms_);
}

bool PlcClientLink::flush() {
  const int base = cfg_.base;
  if (owe_block_) {  // ERROR .. QZ in one request, so the PLC never sees half a result
    if (modbus_write_registers(ctx_, base + reg::kError, reg::kPoseEnd - reg::kError, &image_[reg::kError]) <
        0)
      return disconnect("writing the result block"), false;
    // ... and, where plc.write_held says the PLC has them, HELD .. REGIONS, before STATUS and
    // ACK_ID as well. A PLC that refuses them (any exception reply: no such registers, a gateway's
    // path) is told about once per connection and served without them; no reply is a lost link.
    if (plc_holds_held_ &&
        modbus_write_registers(ctx_, base + reg::kHeld, reg::kSize - reg::kHeld, &image_[reg::kHeld]) < 0) {
      if (!(errno > MODBUS_ENOBASE && errno <= MODBUS_ENOBASE + MODBUS_EXCEPTION_GATEWAY_TARGET))
        return disconnect("writing HELD .. REGIONS"), false;
      spdlog::warn(
          "plc: the PLC at {}:{} refused registers {}..{} (HELD, HELD_WHY, REGIONS: what a LOCATE saw "
          "but did not hand out): {}; they are not written on this connection. Give its block {} "
          "registers from {}, or set plc.write_held = false",
          cfg_.address, cfg_.port, base + reg::kHeld, base + reg::kSize - 1, modbus_strerror(errno),
          reg::kSize, base);
      plc_holds_held_ = false;
    }
    owe_block_ = false;
    owe_heartbeat_ = false;
  }
  if (owe_status_) {
    if (modbus_write_register(ctx_, base + reg::kStatus, image_[reg::kStatus]) < 0)
      return disconnect("writing STATUS"), false;
    owe_status_ = false;
  }
  if (owe_ack_) {
    if (modbus_write_register(ctx_, base + reg::kAckId, image_[reg::kAckId]) < 0)
      return disconnect("writing ACK_ID"), false;
    owe_ack_ = false;
  }
  if (owe_heartbeat_) {
    if (modbus_write_register(ctx_, base + reg::kHeartbeat, image_[reg::kHeartbeat]) < 0)
      return disconnect("writing HEARTBEAT"), false;
    owe_heartbeat_ = false;
  }
  return true;
}

bool PlcClientLink::poll(int timeout_ms, int wake_fd, PlcRequest* req) {
  pollfd pfd{wake_fd, POLLIN, 0};
  ::poll(&pfd, 1, std::min(timeout_ms, cfg_.poll_ms));
  return round(req);
}

int PlcClientLink::client_list(PlcClientInfo* out, int max) const {
  if (!connected_ || max < 1) return 0;
  PlcClientInfo& info = out[0];
  std::snprintf(info.ip, sizeof info.ip, "%s", cfg_.address.c_str());
  info.plc = true;
  info.requests = reads_;
  info.connected = connected_at_;
  info.last_request = last_read_;
  return 1;
}

std::string PlcClientLink::describe() const {
  return "polling the PLC at " + cfg_.address + ":" + std::to_string(cfg_.port) + " every " +
         std::to_string(cfg_.poll_ms) + " ms, registers from " + std::to_string(cfg_.base);
}

bool PlcClientLink::round(PlcRequest* req) {
  const auto now = Clock::now();
  if (!connected_ && (now < next_attempt_ || !connect())) return false;
  if (!flush()) return false;
  if (now < next_poll_) return false;
  next_poll_ = now + std::chrono::milliseconds(cfg_.poll_ms);
  std::uint16_t cmd_req[2];
  if (modbus_read_registers(ctx_, cfg_.base + reg::kCmd, 2, cmd_req) != 2) {
    disconnect("reading CMD/REQ_ID");
    return false;
  }
  last_read_ = Clock::now();
  ++reads_;
  if (cmd_req[1] == last_req_id_) return false;
  last_req_id_ = cmd_req[1];
  req->command = cmd_req[0];
  req->req_id = cmd_req[1];
  req->at = Clock::now();
  return true;
}

void PlcClientLink::set_busy() {
  reg::write_busy(cfg_.encoding, image_);
  owe_block_ = owe_status_ = true;
  if (connected_) flush();
}

void PlcClientLink::publish(const reg::Result& r, std::uint16_t ack_id) {
  reg::write_result(r, ack_id, cfg_.encoding, image_);
  owe_block_ = owe_status_ = owe_ack_ = true;
  if (connected_) flush();
}

void PlcClientLink::heartbeat() {
  ++image_[reg::kHeartbeat];
  owe_heartbeat_ = true;
  if (connected_) flush();
}

}  // namespace pipeloc
