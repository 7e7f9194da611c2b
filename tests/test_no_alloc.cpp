// After the first cycle, locate() performs no heap allocation: every buffer is sized by the
// Locator's constructor. malloc, calloc, realloc and operator new are counted in this binary only,
// on every thread (the cycle's and its worker pool) but the status page's: its server threads and
// the test's poller, named kStatusThreadName, allocate freely beside the cycle and are not part of it.
#include <gtest/gtest.h>
#include <httplib.h>
#undef _res  // <resolv.h> (included by httplib) defines it; Eigen names parameters so

#include <pthread.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>
#include <thread>

#include "config/config_file.hpp"
#include "locate/locator.hpp"
#include "model/make_pipe.hpp"
#include "service/service.hpp"
#include "service/sim_source.hpp"
#include "sim/scene.hpp"
#include "sim_config.hpp"
#include "status/status_server.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
thread_local int t_kind = 0;  // 0: not known yet, 1: counted, 2: a status page thread (not counted)

bool counted_thread() {
  if (t_kind == 0) {  // threads are named when they start, before any counting
    char name[16] = {};
    pthread_getname_np(pthread_self(), name, sizeof name);
    t_kind = std::strcmp(name, pipeloc::kStatusThreadName) == 0 ? 2 : 1;
  }
  return t_kind == 1;
}
}  // namespace

// glibc's own entry points, so that malloc itself (used by Eigen, FLANN, C code) is counted too.
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);
extern "C" void* malloc(std::size_t n) {
  if (g_counting && counted_thread()) ++g_allocations;
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t n, std::size_t size) {
  if (g_counting && counted_thread()) ++g_allocations;
  return __libc_calloc(n, size);
}
extern "C" void* realloc(void* p, std::size_t n) {
  if (g_counting && counted_thread()) ++g_allocations;
  return __libc_realloc(p, n);
}

void* operator new(std::size_t n) {
  if (void* p = std::malloc(n ? n : 1)) return p;  // counted by malloc
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace pipeloc {
namespace {

TEST(NoAllocation, FiftyCyclesOnSimulatedFramesAllocateNothing) {
  const PipeModel model = derive_pipe_model(make_pipe(pipe_preset("sbend")), "sbend");
  std::mt19937 rng(5);
  SceneParams params;
  params.pile.pipes = 15;
  std::vector<SimulatedScene> frames;
  for (int i = 0; i < 5; ++i) frames.push_back(simulate_scene(model, params, rng));
  LocateConfig cfg;
  Locator locator(model, cfg, params.intrinsics);
  locator.locate(frames[0].depth_mm, frames[0].camera);  // the first cycle may settle
  int found = 0;
  // The counter is live: an allocation made while counting is seen.
  g_counting = true;
  { std::vector<int> probe(10); }
  g_counting = false;
  ASSERT_GT(g_allocations.load(), 0);
  g_allocations = 0;
  g_counting = true;
  for (int cycle = 0; cycle < 50; ++cycle) {
    const SimulatedScene& f = frames[std::size_t(cycle % 5)];
    found += int(locator.locate(f.depth_mm, f.camera).estimates.size());
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_GT(found, 0);  // the cycles did real work
}

// The service's 50 LOCATE cycles after the first, as the PLC thread runs them: the cycle, the
// register contents and the timing-log line (and the status board, if `publish_status`) counted;
// the pick's effect on the bin between cycles not.
// The sim source's service with a budget no cycle reaches: how many cycles find a pose must not
// depend on the machine's load.
AppConfig service_config(const test::TempDir& dir) {
  AppConfig cfg = test::sim_config(dir, 15, 9);
  cfg.service.summary_every = 10;
  cfg.service.budget_ms = 60000;
  return cfg;
}

struct CountedCycles {
  long allocations = 0;
  int done_ok = 0;
};
CountedCycles count_service_cycles(Service& service, const AppConfig& cfg, bool publish_status) {
  CountedCycles out;
  for (int cycle = 0; cycle < 50; ++cycle) {
    g_allocations = 0;
    g_counting = true;
    const reg::Result& r = service.run(1, std::uint16_t(cycle + 2), Clock::now());
    std::uint16_t map[reg::kSize];
    reg::write_result(r, std::uint16_t(cycle + 2), cfg.plc.encoding, map);
    service.search_again();  // the second searches, after the result, as the cycle thread runs them
    service.log().write(service.record());
    if (publish_status) service.publish_status();
    g_counting = false;
    out.allocations += g_allocations.load();
    out.done_ok += r.status == reg::Status::done_ok;
    service.after_publish();
  }
  return out;
}

// The service's whole LOCATE cycle on the sim source: fresh frame, localization under the budget,
// ranking, robot poses, the register contents and the timing-log line. Between cycles the
// simulated robot takes the pipe handed out (the bin changes: not part of the cycle, not counted).
TEST(NoAllocation, FiftyServiceCyclesOnTheSimSourceAllocateNothing) {
  static const PipeModel model = derive_pipe_model(make_pipe(pipe_preset("sbend")), "sbend");
  test::TempDir dir;
  AppConfig cfg = service_config(dir);
  Service service(cfg, model, std::make_unique<SimSource>(model, cfg.source.sim));
  service.run(1, 1, Clock::now());  // the first cycle may settle
  service.search_again();
  service.log().write(service.record());
  service.after_publish();
  const CountedCycles counted = count_service_cycles(service, cfg, false);
  EXPECT_EQ(counted.allocations, 0);
  EXPECT_GT(counted.done_ok, 10);  // the cycles did real work
}

// The same 50 cycles with the status page on, polled from another thread all along: the cycle
// publishes to the status board (a copy under a lock), the overlay is drawn after the result is
// out (not counted, as the timing log's overlay is not), and the page's threads copy and format.
TEST(NoAllocation, FiftyServiceCyclesAllocateNothingWithTheStatusPagePolled) {
  static const PipeModel model = derive_pipe_model(make_pipe(pipe_preset("sbend")), "sbend");
  test::TempDir dir;
  AppConfig cfg = service_config(dir);
  cfg.status.enabled = true;
  cfg.status.port = 0;  // any free port
  cfg.status.overlay_every = 1;
  Service service(cfg, model, std::make_unique<SimSource>(model, cfg.source.sim));
  StatusBoard board;
  service.set_status_board(&board);
  StatusInfo info;
  info.budget_ms = cfg.service.budget_ms;
  info.config = describe_config(cfg);
  StatusServer server(cfg.status, board, info);
  std::atomic<bool> stop{false};
  std::atomic<long> polls{0}, failed{0};
  std::thread poller([&] {
    pthread_setname_np(pthread_self(), kStatusThreadName);  // a browser, not part of the cycle
    httplib::Client client("127.0.0.1", server.port());
    while (!stop) {
      for (const char* path : {"/", "/metrics", "/api/status", "/overlay.png"}) {
        const auto res = client.Get(path);
        (res && (res->status == 200 || res->status == 404) ? polls : failed)++;
      }
    }
  });
  service.run(1, 1, Clock::now());  // the first cycle may settle
  service.search_again();
  service.log().write(service.record());
  service.publish_status();
  service.after_publish();
  // Counting is live: an allocation of this thread is seen.
  g_allocations = 0;
  g_counting = true;
  { std::vector<int> probe(10); }
  g_counting = false;
  ASSERT_GT(g_allocations.load(), 0);
  const long polls_before = polls.load();
  const CountedCycles counted = count_service_cycles(service, cfg, true);
  const long polls_during = polls.load() - polls_before;
  stop = true;
  poller.join();
  EXPECT_EQ(counted.allocations, 0);
  EXPECT_GT(counted.done_ok, 10);
  EXPECT_GT(polls_during, 0);  // the page was really read while the cycles ran
  EXPECT_EQ(failed.load(), 0);
  StatusSnapshot s;
  board.snapshot(&s);
  EXPECT_EQ(s.cycle_count, 51u);  // every cycle reached the board
  EXPECT_GT(s.overlay_cycle, 0u);
}

}  // namespace
}  // namespace pipeloc
