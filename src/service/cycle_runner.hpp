// The cycle thread: takes commands from the PLC front end (which owns the Modbus context) and
// runs them on the Service, one at a time. A command submitted while one runs waits; a newer
// one replaces it (each REQ_ID change runs once, the latest wins). Results come back through
// take_result(); wake_fd() becomes readable when one is ready, for the front end's poll(). After
// a LOCATE's result is handed over, its second searches run (for the log and the overlay) until
// a command is submitted.
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "plc/plc_link.hpp"
#include "service/service.hpp"

namespace pipeloc {

// One command's outcome, copied under the runner's lock: the registers and the record of the
// same command, so that the front end never reads the Service while the next command runs.
struct Published {
  reg::Result result;
  std::uint16_t ack_id = 0;
  CycleRecord record;
};

class CycleRunner {
 public:
  explicit CycleRunner(Service& service);  // throws std::system_error when no eventfd can be made
  ~CycleRunner();  // finishes the running command, then stops
  CycleRunner(const CycleRunner&) = delete;
  CycleRunner& operator=(const CycleRunner&) = delete;

  void submit(const PlcRequest& request);
  bool take_result(Published* out);
  int wake_fd() const { return wake_fd_; }
  // False when a command has been running for longer than the budget plus `slack_ms`.
  // Also false once the cycle thread has stopped on an exception (the watchdog then lapses).
  bool healthy(double slack_ms) const;
  bool failed() const { return failed_.load(); }
  long completed() const { return completed_.load(); }
  void stop();

 private:
  void loop();
  void run_one(const PlcRequest& req);

  Service& service_;
  std::mutex mutex_;
  std::condition_variable wake_;
  PlcRequest pending_;
  bool has_pending_ = false;
  Published result_;
  bool has_result_ = false;
  bool stop_ = false;
  std::atomic<bool> cancel_{false};
  std::atomic<bool> waiting_{false};    // a command is submitted: the second searches give way
  std::atomic<long> busy_since_ns_{0};  // steady clock; 0 when idle
  std::atomic<long> completed_{0};
  std::atomic<bool> failed_{false};
  int wake_fd_ = -1;
  std::thread thread_;
};

}  // namespace pipeloc
