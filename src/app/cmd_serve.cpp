// pipeloc serve: the long-running service. Lifecycle as a ros2_control hardware interface:
// init (config validated, every value logged), configure (model, buffers, frame source, PLC
// port, timing log), activate (READY to systemd), cycle until SIGTERM/SIGINT, deactivate.
#include <spdlog/spdlog.h>

#include <atomic>
#include <csignal>
#include <cstring>
#include <memory>

#include "app/commands.hpp"
#include "config/config_file.hpp"
#include "plc/plc_link.hpp"
#include "service/cycle_runner.hpp"
#include "service/sd_notify.hpp"
#include "service/service.hpp"
#include "status/status_server.hpp"

namespace pipeloc::app {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) {
  g_signal = sig;
  g_stop = true;
}

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);  // a closed terminal or `systemctl kill -s HUP`: stop cleanly too
  std::signal(SIGPIPE, SIG_IGN);
}

void log_result(const Published& p) {
  const reg::Result& r = p.result;
  if (p.record.cut_by_shutdown)
    spdlog::info("req {}: cut short by shutdown after {:.0f} ms", p.ack_id, p.record.cycle_ms);
  else if (r.status == reg::Status::done_ok && r.pose)
    spdlog::info(
        "req {}: {} pose {}/{} x {:.1f} y {:.1f} z {:.1f} mm, r {:.1f} {:.1f} {:.1f} deg, score {:.3f}, "
        "cycle {} ms",
        p.ack_id, status_name(r.status), r.index + 1, r.count, r.pose->xyz_mm[0], r.pose->xyz_mm[1],
        r.pose->xyz_mm[2], r.pose->rxyz_deg[0], r.pose->rxyz_deg[1], r.pose->rxyz_deg[2], r.score,
        p.record.command == std::uint16_t(reg::Command::locate) ? r.cycle_ms : 0);
  else
    spdlog::info("req {}: {} (error {} {}{}{}), cycle {} ms", p.ack_id, status_name(r.status), int(r.error),
                 error_name(r.error), *p.record.frame_check ? ": " : "", p.record.frame_check, r.cycle_ms);
}

struct Options {
  std::string config, log_dir;
  long cycles = 0;     // stop after this many commands (0: until a signal)
  int trigger_ms = 0;  // plc.mode "none": LOCATE every this many ms
};

// HEARTBEAT every 250 ms and the systemd watchdog every WatchdogSec/3, while the cycle is healthy;
// the status page learns the heartbeat count and the PLC's connections at the same pace.
class Pulse {
 public:
  void beat(PlcLink& link, bool healthy, StatusBoard* board) {
    const auto now = Clock::now();
    if (now >= next_heartbeat_) {
      next_heartbeat_ = now + std::chrono::milliseconds(250);
      if (healthy) link.heartbeat(), ++beats_;
      if (board) {
        PlcClientInfo clients[StatusSnapshot::kClients];
        board->publish_link(beats_, healthy, clients, link.client_list(clients, StatusSnapshot::kClients));
      }
    }
    if (watchdog_ms_ > 0 && now >= next_watchdog_ && healthy) {
      next_watchdog_ = now + std::chrono::milliseconds(watchdog_ms_ / 3);
      sd_notify_send("WATCHDOG=1");
    }
  }

 private:
  long watchdog_ms_ = sd_watchdog_ms();
  std::uint64_t beats_ = 0;
  Clock::time_point next_heartbeat_ = Clock::now(), next_watchdog_ = Clock::now();
};

int serve(const Options& opt) {
  // init
  AppConfig cfg = opt.config.empty() ? embedded_default_config() : load_config(opt.config);
  if (!opt.log_dir.empty()) cfg.log.dir = opt.log_dir;
  spdlog::info("pipeloc serve: config {}", cfg.path.empty() ? "(embedded default: simulated bin)" : cfg.path);
  for (const auto& line : describe_config(cfg)) spdlog::info("config: {}", line);
  for (const auto& line : cfg.warnings) spdlog::warn("{}", line);
  if (opt.trigger_ms > 0 && cfg.plc.mode != "none")
    throw CLI::ValidationError("--trigger-ms", "triggers LOCATE only with plc.mode \"none\"; plc.mode is \"" +
                                                   cfg.plc.mode + "\" (the PLC triggers)");
  // configure
  const PipeModel model = load_config_model(cfg);
  spdlog::info(
      "model: {}: tube diameter {:.2f} mm, longest extent L {:.1f} mm, {} symmetries, {} near symmetries "
      "(half-turns checked as ambiguities){}",
      model.source, model.tube_diameter_mm, model.extent_mm, model.symmetries.size(),
      model.near_symmetries.size(),
      model.bore_faces_removed > 0
          ? fmt::format("; hollow: {} faces of its bore left out (the camera sees the outside)",
                        model.bore_faces_removed)
          : std::string());
  spdlog::info("model: {}", describe_near_symmetries(model));
  std::unique_ptr<FrameSource> source = open_frame_source(cfg, model);
  spdlog::info("source: {}", source->describe());
  const std::string twin_resolution =
      describe_twin_resolution(model, source->intrinsics().fx, cfg.locate.twin_beyond_resolution_ambiguous);
  if (!twin_resolution.empty()) spdlog::info("model: {}", twin_resolution);
  Service service(cfg, model, std::move(source));
  spdlog::info("timing log: {} (rotated at {} KiB, {} kept)", service.log().path(), cfg.log.max_file_kb,
               cfg.log.keep_files);
  std::unique_ptr<PlcLink> link = open_plc_link(cfg.plc, opt.trigger_ms);
  spdlog::info("plc: {}", link->describe());
  StatusBoard board;
  std::unique_ptr<StatusServer> status;
  if (cfg.status.enabled) {
    StatusInfo info;
    char model_text[256];
    std::snprintf(model_text, sizeof model_text, "%s: tube diameter D %.1f mm, longest extent L %.1f mm",
                  model.source.c_str(), model.tube_diameter_mm, model.extent_mm);
    info.model = std::string(model_text) + "; " + describe_near_symmetries(model) +
                 (twin_resolution.empty() ? "" : "; " + twin_resolution);
    info.source = service.source().describe();
    info.plc = link->describe();
    info.config_path = cfg.path;
    info.config = describe_config(cfg);
    info.budget_ms = cfg.service.budget_ms;
    info.refresh_s = cfg.status.refresh_s;
    info.start_unix_ms = unix_ms_now();
    service.set_status_board(&board);
    status = std::make_unique<StatusServer>(cfg.status, board, std::move(info));
    spdlog::info("status page: {} (also /metrics, /api/status, /overlay.png)", status->url());
  }
  install_signal_handlers();
  CycleRunner runner(service);
  {
    char rest[512];
    std::snprintf(rest, sizeof rest, "\"source\":\"%s\",\"budget_ms\":%.1f,\"plc\":\"%s\"",
                  cfg.source.kind.c_str(), cfg.service.budget_ms, cfg.plc.mode.c_str());
    service.log().event("start", rest);
  }
  // activate
  sd_notify_send("READY=1\nSTATUS=serving");
  spdlog::info("ready");
  Pulse pulse;
  long done = 0;
  while (!g_stop && !runner.failed() && (opt.cycles == 0 || done < opt.cycles)) {
    PlcRequest req;
    if (link->poll(20, runner.wake_fd(), &req)) {
      link->set_busy();
      runner.submit(req);
    }
    Published p;
    while (runner.take_result(&p)) {
      link->publish(p.result, p.ack_id);
      log_result(p);
      ++done;
    }
    pulse.beat(*link, runner.healthy(2000), status ? &board : nullptr);
  }
  // deactivate
  sd_notify_send("STOPPING=1");
  spdlog::info("stopping: {}", g_stop            ? strsignal(g_signal.load())
                               : runner.failed() ? "the cycle thread failed"
                                                 : "cycle count reached");
  runner.stop();
  Published p;
  while (runner.take_result(&p)) {
    link->publish(p.result, p.ack_id);
    log_result(p);
  }
  service.log().event("stop", "");
  spdlog::info("stopped after {} commands", runner.completed());
  return runner.failed() ? 1 : 0;
}

}  // namespace

void add_serve(CLI::App& app) {
  auto opt = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("serve", "Run the service: PLC-triggered cycles on the configured frame source");
  cmd->add_option("--config", opt->config,
                  "TOML config (default: the embedded simulated bin, see config/demo.toml)");
  cmd->add_option("--log-dir", opt->log_dir, "timing log folder (overrides log.dir)");
  cmd->add_option("--cycles", opt->cycles,
                  "stop after this many commands (default: run until SIGTERM/SIGINT)")
      ->check(CLI::Range(0L, 1L << 40));
  cmd->add_option("--trigger-ms", opt->trigger_ms, "plc.mode \"none\": LOCATE every this many ms")
      ->check(CLI::Range(0, 3600000));
  cmd->callback([opt] { exit_status() = serve(*opt); });
}

}  // namespace pipeloc::app
