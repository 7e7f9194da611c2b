#include "service/cycle_runner.hpp"

#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <system_error>

namespace pipeloc {

CycleRunner::CycleRunner(Service& service) : service_(service) {
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) throw std::system_error(errno, std::generic_category(), "cycle runner: eventfd");
  service_.cancel_cycles(&cancel_);
  thread_ = std::thread([this] { loop(); });
}

CycleRunner::~CycleRunner() {
  stop();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void CycleRunner::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cancel_ = true;  // a running LOCATE ends at its next check
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void CycleRunner::submit(const PlcRequest& request) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = request;
    has_pending_ = true;
    waiting_ = true;
  }
  wake_.notify_all();
}

bool CycleRunner::take_result(Published* out) {
  std::uint64_t n;
  [[maybe_unused]] const auto r = ::read(wake_fd_, &n, sizeof n);  // clears the wake-up
  std::lock_guard<std::mutex> lock(mutex_);
  if (!has_result_) return false;
  *out = result_;
  has_result_ = false;
  return true;
}

bool CycleRunner::healthy(double slack_ms) const {
  if (failed_) return false;
  const long since = busy_since_ns_.load();
  if (since == 0) return true;
  const double busy_ms = double(Clock::now().time_since_epoch().count() - since) / 1e6;
  return busy_ms < service_.budget_ms() + slack_ms;
}

void CycleRunner::loop() {
  for (;;) {
    PlcRequest req;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || has_pending_; });
      if (stop_) return;
      req = pending_;
      has_pending_ = false;
      waiting_ = false;
    }
    try {
      run_one(req);
    } catch (const std::exception& e) {
      // The cycle reports by status codes; an exception here is a bug or the heap gone. The
      // thread stops, healthy() turns false, the heartbeat and the watchdog stop, systemd restarts.
      spdlog::critical("cycle thread stopped: req {}: {}", req.req_id, e.what());
      failed_ = true;
      return;
    }
  }
}

void CycleRunner::run_one(const PlcRequest& req) {
  busy_since_ns_ = long(Clock::now().time_since_epoch().count());
  const reg::Result& r = service_.run(req.command, req.req_id, req.at);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    result_.result = r;
    result_.ack_id = req.req_id;
    result_.record = service_.record();
    has_result_ = true;
  }
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto w = ::write(wake_fd_, &one, sizeof one);
  // The PLC has its result: these are for the log and the overlay, and end when a command waits.
  service_.search_again(&waiting_);
  service_.log().write(service_.record());
  service_.publish_status();
  service_.after_publish(cancel_);
  busy_since_ns_ = 0;
  ++completed_;
}

}  // namespace pipeloc
