#include "status/status_json.hpp"

#include <nlohmann/json.hpp>

#include "status/status_page.hpp"

namespace pipeloc {
namespace {

using Json = nlohmann::json;

Json row_json(const StatusRow& r) {
  return {{"trigger_unix_ms", r.trigger_unix_ms},
          {"req_id", r.req_id},
          {"command", command_name(r.command)},
          {"status", status_name(r.status)},
          {"error_code", int(r.error)},
          {"error", error_name(r.error)},
          {"frame_check", r.frame_check},
          {"count", r.count},
          {"index", r.index},
          {"score", r.score},
          {"cycle_ms", r.cycle_ms},
          {"frame_age_ms", r.frame_age_ms},
          {"budget_ms", r.budget_ms},
          {"budget_exhausted", r.budget_exhausted},
          {"candidates", r.candidates},
          {"estimates", r.accepted},
          {"cycle", r.cycle},
          {"frame", r.frame_sequence}};
}

}  // namespace

std::string render_status_json(const StatusView& v, const StatusInfo& info) {
  const StatusSnapshot& s = v.s;
  Json j;
  j["now_unix_ms"] = v.now_unix_ms;
  j["start_unix_ms"] = info.start_unix_ms;
  j["healthy"] = s.healthy;
  j["model"] = info.model;
  j["source"] = info.source;
  j["plc"] = info.plc;
  j["budget_ms"] = info.budget_ms;
  j["config_file"] = info.config_path;
  j["config"] = info.config;
  Json counts = {{"locate", s.commands_by_type[0]},
                 {"next", s.commands_by_type[1]},
                 {"clear_error", s.commands_by_type[2]},
                 {"other", s.commands_by_type[3]}};
  j["commands"] = counts;
  j["locate_by_status"] = Json::object();
  for (reg::Status st : {reg::Status::done_ok, reg::Status::done_none, reg::Status::error})
    j["locate_by_status"][status_name(st)] = s.locate_by_status[std::size_t(st)];
  j["errors"] = Json::object();
  for (int code = 1; code < 7; ++code) j["errors"][error_name(reg::Error(code))] = s.errors_by_code[code];
  j["picks"] = s.picks;
  j["picks_took_nothing"] = s.picks_took_nothing;
  j["budget_exhausted"] = s.budget_exhausted;
  j["heartbeats"] = s.heartbeats;
  j["last_locate"] = s.has_locate ? row_json(s.last_locate) : Json(nullptr);
  j["poses"] = Json::array();
  for (int i = 0; i < s.pose_count; ++i) {
    const StatusPose& p = s.poses[i];
    j["poses"].push_back({{"index", i},
                          {"xyz_mm", p.robot.xyz_mm},
                          {"rxyz_deg", p.robot.rxyz_deg},
                          {"wxyz", p.robot.wxyz},
                          {"score", p.score},
                          {"camera_xyz_mm", p.cam_xyz_mm}});
  }
  j["recent"] = Json::array();
  for (int k = 0; k < s.recent_count; ++k)
    j["recent"].push_back(
        row_json(s.recent[(s.recent_next - 1 - k + 2 * StatusSnapshot::kRecent) % StatusSnapshot::kRecent]));
  Json cycle_ms = Json::array(), trigger = Json::array();
  for (const CycleSample& c : v.history) cycle_ms.push_back(c.cycle_ms), trigger.push_back(c.trigger_unix_ms);
  j["history"] = {{"cycle_ms", cycle_ms}, {"trigger_unix_ms", trigger}};
  j["cycle_ms_p50"] = quantile_ms(v.history.data(), int(v.history.size()), 0.5);
  j["cycle_ms_p95"] = quantile_ms(v.history.data(), int(v.history.size()), 0.95);
  j["clients"] = Json::array();
  for (int i = 0; i < s.client_count; ++i) {
    const PlcClientInfo& c = s.clients[i];
    j["clients"].push_back(
        {{"address", c.ip},
         {"plc", c.plc},
         {"requests", c.requests},
         {"connected_ms", ms_between(c.connected, v.now)},
         {"last_request_age_ms", c.requests ? Json(ms_between(c.last_request, v.now)) : Json(nullptr)}});
  }
  j["overlay_cycle"] = s.overlay_cycle;
  return j.dump(1) + "\n";
}

}  // namespace pipeloc
