#include "status/metrics_text.hpp"

#include <cstdio>

namespace pipeloc {
namespace {

class Exposition {
 public:
  void family(const char* name, const char* type, const char* help) {
    out_ += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
  }
  void sample(const std::string& name, double value, const std::string& labels = "") {
    char v[64];
    std::snprintf(v, sizeof v, "%.10g", value);
    out_ += name + (labels.empty() ? "" : "{" + labels + "}") + " " + v + "\n";
  }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

std::string label(const char* key, const std::string& value) {
  return std::string(key) + "=\"" + value + "\"";
}

}  // namespace

std::string render_metrics(const StatusView& view, const StatusInfo& info) {
  const StatusSnapshot& s = view.s;
  Exposition e;
  e.family("pipeloc_cycle_seconds", "histogram", "LOCATE cycle time, PLC trigger to result (CYCLE_MS).");
  std::uint64_t below = 0;
  for (int b = 0; b < StatusSnapshot::kBuckets; ++b) {
    below += s.cycle_buckets[b];
    char le[32];
    std::snprintf(le, sizeof le, "%g", StatusSnapshot::kBucketLeS[b]);
    e.sample("pipeloc_cycle_seconds_bucket", double(below), label("le", le));
  }
  e.sample("pipeloc_cycle_seconds_bucket", double(below + s.cycle_buckets[StatusSnapshot::kBuckets]),
           label("le", "+Inf"));
  e.sample("pipeloc_cycle_seconds_sum", s.cycle_sum_s);
  e.sample("pipeloc_cycle_seconds_count", double(s.cycle_count));

  e.family("pipeloc_commands_total", "counter", "PLC commands run, by CMD.");
  const char* const commands[] = {"locate", "next", "clear_error", "other"};
  for (int i = 0; i < 4; ++i)
    e.sample("pipeloc_commands_total", double(s.commands_by_type[i]), label("command", commands[i]));

  e.family("pipeloc_cycles_total", "counter", "LOCATE cycles by the STATUS they ended with.");
  for (reg::Status st : {reg::Status::done_ok, reg::Status::done_none, reg::Status::error})
    e.sample("pipeloc_cycles_total", double(s.locate_by_status[std::size_t(st)]),
             label("status", status_name(st)));

  e.family("pipeloc_errors_total", "counter",
           "Results with an ERROR code, every command (firmware-host/REGISTERS.md).");
  for (int code = 1; code < 7; ++code)
    e.sample("pipeloc_errors_total", double(s.errors_by_code[code]),
             label("code", std::to_string(code)) + "," + label("error", error_name(reg::Error(code))));

  e.family("pipeloc_picks_total", "counter", "Poses handed to the PLC (DONE_OK after LOCATE or NEXT).");
  e.sample("pipeloc_picks_total", double(s.picks));
  e.family("pipeloc_picks_took_nothing_total", "counter",
           "Picks after which the bin read as before where the pose lay: a wrong pose or a failed grip "
           "(frames in the log folder's took-nothing/).");
  e.sample("pipeloc_picks_took_nothing_total", double(s.picks_took_nothing));
  e.family("pipeloc_budget_exhausted_total", "counter", "LOCATE cycles the budget cut short.");
  e.sample("pipeloc_budget_exhausted_total", double(s.budget_exhausted));
  e.family("pipeloc_heartbeats_total", "counter",
           "HEARTBEAT register increments (every 250 ms while healthy).");
  e.sample("pipeloc_heartbeats_total", double(s.heartbeats));
  e.family("pipeloc_healthy", "gauge", "1 while the cycle thread is healthy (no command over budget + 2 s).");
  e.sample("pipeloc_healthy", s.healthy ? 1 : 0);
  e.family("pipeloc_plc_clients", "gauge",
           "Modbus TCP connections open now (client mode: 1 while the PLC is reached).");
  e.sample("pipeloc_plc_clients", s.client_count);
  e.family("pipeloc_frame_age_seconds", "gauge",
           "Age of the frame the last LOCATE used, at its result (FRAME_AGE_MS).");
  e.sample("pipeloc_frame_age_seconds", s.has_locate ? s.last_locate.frame_age_ms / 1000 : 0);
  e.family("pipeloc_last_cycle_seconds", "gauge", "Cycle time of the last LOCATE.");
  e.sample("pipeloc_last_cycle_seconds", s.has_locate ? s.last_locate.cycle_ms / 1000 : 0);
  e.family("pipeloc_last_locate_timestamp_seconds", "gauge",
           "Unix time of the last LOCATE's trigger (0: none yet).");
  e.sample("pipeloc_last_locate_timestamp_seconds", s.has_locate ? s.last_locate.trigger_unix_ms / 1000 : 0);
  e.family("pipeloc_poses", "gauge", "Pickable poses the last LOCATE handed out (COUNT).");
  e.sample("pipeloc_poses", s.has_locate ? s.last_locate.count : 0);
  e.family("pipeloc_budget_seconds", "gauge", "The configured cycle budget (service.budget_ms).");
  e.sample("pipeloc_budget_seconds", info.budget_ms / 1000);
  e.family("pipeloc_start_time_seconds", "gauge", "Unix time the service started.");
  e.sample("pipeloc_start_time_seconds", info.start_unix_ms / 1000);
  return e.take();
}

}  // namespace pipeloc
