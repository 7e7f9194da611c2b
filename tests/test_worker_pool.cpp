// The worker pool.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "core/worker_pool.hpp"

namespace pipeloc {
namespace {

// The pool's threads spin briefly between runs, then block: every run still runs each of its
// tasks exactly once and returns only when all are done, whether the runs follow one another at
// once (spinning) or after a pause longer than the spin (blocked and woken).
TEST(WorkerPool, EveryTaskOnceWhetherRunsFollowAtOnceOrAfterAPause) {
  for (const int threads : {1, 2, 3}) {
    WorkerPool pool(threads);
    struct Run {
      std::atomic<int> count[8];
      std::atomic<int> slow_done{0};
    } run;
    const auto task = [&run](int t, int) {
      Run& r = run;
      if (t % 3 == 0) {  // some tasks take a while, so that run() has to wait for them
        const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(50);
        while (std::chrono::steady_clock::now() < until) {
        }
        r.slow_done.fetch_add(1);
      }
      r.count[t].fetch_add(1);
    };
    for (int rep = 0; rep < 300; ++rep) {
      const int tasks = rep % 9;  // 0 to 8 tasks (0: a run with nothing to do)
      for (auto& c : run.count) c = 0;
      run.slow_done = 0;
      pool.run(tasks, task);
      for (int t = 0; t < 8; ++t) ASSERT_EQ(run.count[t].load(), t < tasks ? 1 : 0) << threads << " " << rep;
      ASSERT_EQ(run.slow_done.load(), (tasks + 2) / 3);
      if (rep % 50 == 49) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // past the spin
    }
  }
}

}  // namespace
}  // namespace pipeloc
