// A fixed set of threads started once; run() hands out task indices until all are done. The
// calling thread works too. No allocation per run (tasks are a function pointer and a context).
// A waiting thread spins briefly before it blocks: a frame's runs follow one another closely.
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace pipeloc {

class WorkerPool {
 public:
  using Task = void (*)(void* context, int task, int worker);

  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return int(threads_.size()) + 1; }
  // Runs fn(context, t, worker) for t in [0, tasks); returns when all have finished.
  void run(int tasks, Task fn, void* context);

 private:
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
