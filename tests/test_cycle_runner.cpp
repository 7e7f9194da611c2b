// The cycle thread between the PLC link and the Service: what it publishes, and how it fails.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "model/make_pipe.hpp"
#include "service/cycle_runner.hpp"
#include "service/sim_source.hpp"
#include "sim_config.hpp"

namespace pipeloc {
namespace {

const PipeModel& sbend() {
  static const PipeModel m = derive_pipe_model(make_pipe(pipe_preset("sbend")), "sbend");
  return m;
}

bool wait_for(const CycleRunner& runner, long completed) {
  for (int i = 0; i < 6000 && runner.completed() < completed; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return runner.completed() >= completed;
}

PlcRequest request(reg::Command command, std::uint16_t req_id) {
  return PlcRequest{std::uint16_t(command), req_id, Clock::now()};
}

// serve() used to log a result with service.record() read on the main thread, while the cycle
// thread may already have reset the record for the next command. Here the front end is slow on
// purpose: the next command has run before it looks at the first result. The published record
// must still be the first command's (the Service's own is the second's by then: what serve()
// logged for REQ_ID 1 on the old code).
TEST(CycleRunner, APublishedResultCarriesTheRecordOfItsOwnCommand) {
  test::TempDir dir;
  const AppConfig cfg = test::sim_config(dir, 8, 21);
  Service service(cfg, sbend(), std::make_unique<SimSource>(sbend(), cfg.source.sim));
  CycleRunner runner(service);
  runner.submit(request(reg::Command::locate, 1));
  ASSERT_TRUE(wait_for(runner, 1));
  Published first;
  ASSERT_TRUE(runner.take_result(&first));
  runner.submit(PlcRequest{7, 2, Clock::now()});  // a bad command: runs at once
  ASSERT_TRUE(wait_for(runner, 2));
  EXPECT_EQ(first.ack_id, 1);
  EXPECT_EQ(first.record.req_id, 1);
  EXPECT_EQ(first.record.command, std::uint16_t(reg::Command::locate));
  EXPECT_EQ(first.record.status, first.result.status);
  EXPECT_EQ(service.record().req_id, 2);
  Published second;
  ASSERT_TRUE(runner.take_result(&second));
  EXPECT_EQ(second.record.req_id, 2);
  EXPECT_EQ(second.result.error, reg::Error::bad_command);
}

// A source that throws (a bug, or the heap gone): the cycle thread stops with a message instead of
// taking the process down with std::terminate, and healthy() turns false so that the heartbeat and
// the systemd watchdog stop.
class ThrowingSource : public FrameSource {
 public:
  explicit ThrowingSource(const SimSourceConfig& cfg) : sim_(sbend(), cfg) {}
  const char* kind() const override { return "throwing"; }
  const Intrinsics& intrinsics() const override { return sim_.intrinsics(); }
  std::string describe() const override { return "throws on grab"; }
  GrabStatus grab(Clock::time_point, Clock::time_point, Frame*) override {
    throw std::runtime_error("grab failed unexpectedly");
  }

 private:
  SimSource sim_;
};

TEST(CycleRunner, AnExceptionInTheCycleStopsItAndTurnsItUnhealthy) {
  test::TempDir dir;
  const AppConfig cfg = test::sim_config(dir, 4, 21);
  Service service(cfg, sbend(), std::make_unique<ThrowingSource>(cfg.source.sim));
  CycleRunner runner(service);
  EXPECT_TRUE(runner.healthy(2000));
  runner.submit(request(reg::Command::locate, 1));
  for (int i = 0; i < 2000 && !runner.failed(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(runner.failed());
  EXPECT_FALSE(runner.healthy(2000));
  Published p;
  EXPECT_FALSE(runner.take_result(&p));
}


// A LOCATE queued behind another command (REQ_ID changed while BUSY) starts after its trigger by
// up to a whole cycle. Its budget counts from when it starts: it is tried, not failed with
// ERROR 3 at once (today's main: budget_exhausted, no candidate tried).
TEST(CycleRunner, AQueuedLocateGetsItsWholeBudget) {
  test::TempDir dir;
  AppConfig cfg = test::sim_config(dir, 8, 21);
  cfg.service.budget_ms = 3000;
  Service service(cfg, sbend(), std::make_unique<SimSource>(sbend(), cfg.source.sim));
  const Clock::time_point queued_at = Clock::now() - std::chrono::milliseconds(3100);
  const reg::Result& r = service.run(std::uint16_t(reg::Command::locate), 1, queued_at);
  EXPECT_TRUE(r.status == reg::Status::done_ok || r.status == reg::Status::done_none) << int(r.error);
  EXPECT_GT(service.record().tried, 0);
  EXPECT_GE(service.record().queued_ms, 3100.0);
  EXPECT_GE(service.record().cycle_ms, 3100.0);  // CYCLE_MS: from the PLC's trigger
}

// The LOCATE a cell stood still on is often the last one before someone stops the service to look
// at it. Its frame is kept (log.no_pick_frames) even when the stop comes while the cycle thread,
// the PLC already answered DONE_NONE, is still searching again or drawing.
TEST(CycleRunner, ALocateWithoutAPickKeepsItsFrameWhenTheServiceStopsRightAfter) {
  test::TempDir dir;
  AppConfig cfg = test::sim_config(dir, 1, 21);
  cfg.source.sim.refill = false;
  cfg.service.budget_ms = 20000;
  Service service(cfg, sbend(), std::make_unique<SimSource>(sbend(), cfg.source.sim));
  CycleRunner runner(service);
  Published published;
  for (std::uint16_t id = 1; id <= 3; ++id) {  // the one pipe picked (or not found), then none
    runner.submit(request(reg::Command::locate, id));
    const Clock::time_point give_up = Clock::now() + std::chrono::seconds(60);
    while (!runner.take_result(&published) && Clock::now() < give_up) std::this_thread::yield();
    ASSERT_EQ(published.ack_id, id);
    if (published.result.status == reg::Status::done_none) break;
    ASSERT_TRUE(wait_for(runner, id));
  }
  ASSERT_EQ(published.result.status, reg::Status::done_none);
  runner.stop();  // at once: the PLC has its answer, the records are not written yet
  int depth_files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.file("log/no-pick")))
    depth_files += entry.path().string().find("-depth.png") != std::string::npos;
  EXPECT_EQ(depth_files, 1);
}

}  // namespace
}  // namespace pipeloc
