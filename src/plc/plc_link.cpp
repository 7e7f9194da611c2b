#include "plc/plc_link.hpp"

#include <poll.h>

#include "plc/modbus_client.hpp"
#include "plc/modbus_server.hpp"

namespace pipeloc {
namespace {

// plc.mode "none": LOCATE every trigger_ms, never two at once.
class TimerLink : public PlcLink {
 public:
  explicit TimerLink(int trigger_ms) : trigger_ms_(trigger_ms) {}
  bool poll(int timeout_ms, int wake_fd, PlcRequest* req) override {
    pollfd pfd{wake_fd, POLLIN, 0};
    ::poll(&pfd, 1, timeout_ms);
    if (waiting_ || Clock::now() < next_) return false;
    req->command = std::uint16_t(reg::Command::locate);
    req->req_id = ++req_id_;
    req->at = Clock::now();
    next_ = req->at + std::chrono::milliseconds(trigger_ms_);
    waiting_ = true;
    return true;
  }
  void set_busy() override {}
  void publish(const reg::Result&, std::uint16_t) override { waiting_ = false; }
  void heartbeat() override {}
  std::string describe() const override {
    return "none; LOCATE every " + std::to_string(trigger_ms_) + " ms";
  }

 private:
  int trigger_ms_;
  std::uint16_t req_id_ = 0;
  bool waiting_ = false;
  Clock::time_point next_ = Clock::now();
};

}  // namespace

std::unique_ptr<PlcLink> open_plc_link(const PlcConfig& cfg, int trigger_ms) {
  if (cfg.mode == "server") return std::make_unique<ModbusServer>(cfg);
  if (cfg.mode == "client") return std::make_unique<PlcClientLink>(cfg);
  return std::make_unique<TimerLink>(trigger_ms);
}

}  // namespace pipeloc
