#include "status/status_server.hpp"

#include <httplib.h>
#undef _res  // <resolv.h> (included by httplib) defines it; Eigen names parameters so
#include <pthread.h>

#include <condition_variable>
#include <deque>
#include <mutex>

#include "status/metrics_text.hpp"
#include "status/status_json.hpp"
#include "status/status_page.hpp"

namespace pipeloc {
namespace {

// Named so that `top -H` (and the allocation-counting test) can tell them from the cycle's.
void name_this_thread() { pthread_setname_np(pthread_self(), kStatusThreadName); }

// httplib's request workers: its ThreadPool, with named threads.
class StatusWorkers : public httplib::TaskQueue {
 public:
  explicit StatusWorkers(int n) {
    for (int i = 0; i < n; ++i) threads_.emplace_back([this] { work(); });
  }
  void enqueue(std::function<void()> fn) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      jobs_.push_back(std::move(fn));
    }
    wake_.notify_one();
  }
  void shutdown() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }

 private:
  void work() {
    name_this_thread();
    for (;;) {
      std::function<void()> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
        if (stop_ && jobs_.empty()) return;
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      job();
    }
  }

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  bool stop_ = false;
};

}  // namespace

StatusServer::StatusServer(const StatusConfig& cfg, const StatusBoard& board, StatusInfo info)
    : board_(board),
      info_(std::move(info)),
      address_(cfg.address),
      server_(std::make_unique<httplib::Server>()) {
  httplib::Server& s = *server_;
  s.new_task_queue = [] { return new StatusWorkers(2); };
  s.set_keep_alive_max_count(1);
  // httplib's default adds SO_REUSEPORT: a second pipeloc would then share the port unnoticed.
  s.set_socket_options([](socket_t sock) {
    const int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  s.set_read_timeout(2, 0);
  s.set_write_timeout(2, 0);
  s.Get("/", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(render_status_page(view(), info_), "text/html; charset=utf-8");
  });
  s.Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(render_metrics(view(), info_), "text/plain; version=0.0.4; charset=utf-8");
  });
  s.Get("/api/status", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(render_status_json(view(), info_), "application/json");
  });
  s.Get("/overlay.png", [this](const httplib::Request&, httplib::Response& res) {
    std::vector<std::uint8_t> png;
    std::uint64_t cycle = 0;
    if (!board_.overlay(&png, &cycle)) {
      res.status = 404;
      res.set_content("no overlay yet (one is drawn after each LOCATE, status.overlay_every)\n",
                      "text/plain");
      return;
    }
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Pipeloc-Cycle", std::to_string(cycle));
    res.set_content(std::string(png.begin(), png.end()), "image/png");
  });
  const std::string where = cfg.address + ":" + std::to_string(cfg.port);
  if (cfg.port == 0) {
    port_ = s.bind_to_any_port(cfg.address.c_str());
    if (port_ <= 0) throw StatusError("status: cannot listen on " + cfg.address + " (any port)");
  } else {
    if (!s.bind_to_port(cfg.address.c_str(), cfg.port))
      throw StatusError("status: cannot listen on " + where +
                        " (status.address, status.port): in use or not this machine's address");
    port_ = cfg.port;
  }
  thread_ = std::thread([this] {
    name_this_thread();
    server_->listen_after_bind();
    listen_returned_ = true;
  });
}

StatusServer::~StatusServer() {
  // stop() only reaches a server that is listening: wait for it to start (or to have given up).
  while (!server_->is_running() && !listen_returned_)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  server_->stop();
  if (thread_.joinable()) thread_.join();
}

std::string StatusServer::url() const { return "http://" + address_ + ":" + std::to_string(port_) + "/"; }

StatusView StatusServer::view() const {
  StatusView v;
  board_.snapshot(&v.s);
  v.now = Clock::now();
  v.now_unix_ms = unix_ms_now();
  v.history.resize(std::size_t(v.s.history_count));
  history_in_order(v.s, v.history.data());
  return v;
}

}  // namespace pipeloc
