// A fixed set of threads started once; run() hands out task indices until all are done. The
// calling thread works too. No allocation per run (a task is a reference to the caller's callable).
// A waiting thread spins briefly before it blocks: a frame's runs follow one another closely.
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace pipeloc {

class WorkerPool {
 public:
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return int(threads_.size()) + 1; }
  // Runs fn(t, worker) for t in [0, tasks) on the pool's threads (worker: 0 the caller, up to
  // size() - 1); returns when all have finished. fn is used in place, never copied.
  template <typename Fn>
  void run(int tasks, Fn&& fn) {
    using Callable = std::remove_reference_t<Fn>;
    run_erased(
        tasks, [](void* f, int t, int worker) { (*static_cast<Callable*>(f))(t, worker); },
        const_cast<void*>(static_cast<const void*>(&fn)));
  }

 private:
  using Task = void (*)(void* fn, int task, int worker);
  void run_erased(int tasks, Task call, void* fn);
  void loop(int worker);
  void drain(int worker);

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::atomic<long> generation_{0};  // moves on with each run (written under mutex_)
  std::atomic<int> busy_{0};         // workers not done with this run (written under mutex_)
  bool stop_ = false;
  Task fn_ = nullptr;
  void* context_ = nullptr;
  int tasks_ = 0;
  std::atomic<int> next_{0};
};

}  // namespace pipeloc
