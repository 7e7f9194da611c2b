#include "status/status_page.hpp"
#include "core/clock.hpp"

#include <cstdio>
#include <ctime>

#include "status/svg_plots.hpp"

namespace pipeloc {
namespace {

const char* kStyle =
    "body{font:14px sans-serif;margin:16px;color:#111}h1{font-size:20px;margin:0 0 4px}"
    "h2{font-size:16px;margin:18px 0 6px}table{border-collapse:collapse}"
    "td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}th{background:#eee}"
    "td.l,th.l{text-align:left}.row{display:flex;flex-wrap:wrap;gap:24px;align-items:flex-start}"
    ".ok{color:#2a9d40;font-weight:bold}.bad{color:#d62020;font-weight:bold}.note{color:#555;font-size:12px}"
    "pre{background:#f6f6f6;padding:8px;font-size:12px;max-height:360px;overflow:auto}";

std::string fmt(const char* f, double v) {
  char s[64];
  std::snprintf(s, sizeof s, f, v);
  return s;
}

std::string duration_text(double s) {
  if (s < 120) return fmt("%.0f s", s);
  if (s < 7200) return fmt("%.0f min", s / 60);
  return fmt("%.1f h", s / 3600);
}

std::string cell(const std::string& v, bool left = false) {
  return left ? "<td class=\"l\">" + v + "</td>" : "<td>" + v + "</td>";
}
std::string head(const std::string& v, bool left = false) {
  return left ? "<th class=\"l\">" + v + "</th>" : "<th>" + v + "</th>";
}

std::string status_cell(reg::Status s) {
  const char* cls = s == reg::Status::done_ok ? "ok" : s == reg::Status::error ? "bad" : "";
  return std::string("<td class=\"l ") + cls + "\">" + status_name(s) + "</td>";
}

std::string error_text(reg::Error e, const char* frame_check) {
  if (e == reg::Error::none) return "-";
  std::string t = std::to_string(int(e)) + " " + error_name(e);
  if (frame_check && *frame_check) t += ": " + html_escape(frame_check);
  return t;
}

std::string header(const StatusView& v, const StatusInfo& info) {
  const StatusSnapshot& s = v.s;
  std::string h = "<h1>pipeloc status</h1><p>";
  h += s.healthy ? "<span class=\"ok\">HEALTHY</span>"
                 : "<span class=\"bad\">NOT HEALTHY (a command runs over its budget + 2 s, or the cycle "
                   "thread stopped)</span>";
  h += " &middot; up " + duration_text((v.now_unix_ms - info.start_unix_ms) / 1000) + " &middot; page of " +
       utc_text(v.now_unix_ms) + " UTC, reloads every " + std::to_string(info.refresh_s) + " s</p>";
  h += "<table>";
  auto kv = [&](const char* k, const std::string& val) {
    h += "<tr>" + head(k, true) + cell(html_escape(val), true) + "</tr>";
  };
  kv("pipe model", info.model);
  kv("frame source", info.source);
  kv("PLC link", info.plc);
  kv("cycle budget", fmt("%.0f ms (service.budget_ms)", info.budget_ms));
  kv("config file", info.config_path.empty() ? "(embedded default)" : info.config_path);
  return h + "</table>";
}

std::string overlay_section(const StatusSnapshot& s) {
  std::string h = "<section><h2>Latest overlay</h2>";
  if (s.overlay_cycle == 0)
    return h +
           "<p class=\"note\">No overlay yet: one is drawn after each LOCATE "
           "(status.overlay_every).</p></section>";
  const std::string c = std::to_string(s.overlay_cycle);
  h += "<img id=\"overlay\" src=\"/overlay.png?cycle=" + c + "\" alt=\"overlay of LOCATE cycle " + c +
       "\" onload=\"this.dataset.loadedWidth=this.naturalWidth\">";
  h += "<p class=\"note\">LOCATE cycle " + c + ", drawn " + utc_text(s.overlay_unix_ms) +
       " UTC. Depth in grey; coloured: what the localizer found (legend in the corner); "
       "red outline and cross: the pose handed to the PLC.</p></section>";
  return h;
}

std::string last_locate_section(const StatusSnapshot& s) {
  std::string h = "<section><h2>Last LOCATE</h2>";
  if (!s.has_locate) return h + "<p class=\"note\">No LOCATE yet.</p></section>";
  const StatusRow& r = s.last_locate;
  h += "<table><tr>" + head("cycle") + head("REQ_ID") + head("at (UTC)", true) + head("STATUS", true) +
       head("ERROR", true) + head("cycle ms") + head("frame age ms") + head("candidates") +
       head("estimates") + head("poses handed out") + "</tr><tr>" + cell(std::to_string(r.cycle)) +
       cell(std::to_string(r.req_id)) + cell(utc_text(r.trigger_unix_ms), true) + status_cell(r.status) +
       cell(error_text(r.error, r.frame_check), true) + cell(fmt("%.1f", r.cycle_ms)) +
       cell(fmt("%.1f", r.frame_age_ms)) + cell(std::to_string(r.candidates)) +
       cell(std::to_string(r.accepted)) + cell(std::to_string(r.count)) + "</tr></table>";
  if (r.budget_exhausted)
    h += "<p class=\"bad\">The budget cut this cycle short: poses confirmed until then were handed out.</p>";
  h += "<h2>Its poses, best first (what NEXT presents)</h2>";
  if (s.pose_count == 0) return h + "<p class=\"note\">No pickable pose.</p></section>";
  h += "<table><tr>" + head("INDEX") + head("X mm") + head("Y mm") + head("Z mm") + head("RX deg") +
       head("RY deg") + head("RZ deg") + head("SCORE") + head("camera x, y, z mm") + "</tr>";
  for (int i = 0; i < s.pose_count; ++i) {
    const StatusPose& p = s.poses[i];
    h += "<tr>" + cell(std::to_string(i));
    for (double v : p.robot.xyz_mm) h += cell(fmt("%.1f", v));
    for (double v : p.robot.rxyz_deg) h += cell(fmt("%.1f", v));
    h += cell(fmt("%.3f", p.score)) +
         cell(fmt("%.1f", p.cam_xyz_mm[0]) + ", " + fmt("%.1f", p.cam_xyz_mm[1]) + ", " +
              fmt("%.1f", p.cam_xyz_mm[2])) +
         "</tr>";
  }
  h += "</table>";
  if (r.count > s.pose_count)
    h += "<p class=\"note\">and " + std::to_string(r.count - s.pose_count) + " more</p>";
  h += "<p class=\"note\">X..RZ as the PLC reads them: robot frame (plc.robot_from_camera; the camera's when "
       "none), grasp offset applied, angles in plc.euler's convention.</p>";
  return h + "</section>";
}

std::string plots_section(const StatusView& v, const StatusInfo& info) {
  const int n = int(v.history.size());
  std::string h = "<h2>LOCATE cycle time (last " + std::to_string(n) + " of " +
                  std::to_string(v.s.cycle_count) + " cycles)</h2><div class=\"row\"><figure>";
  h += svg_cycle_histogram(v.history, info.budget_ms);
  h += "<figcaption class=\"note\">How many cycles took how long; red: the budget, dashed: median and "
       "p95.</figcaption></figure><figure>";
  h += svg_cycle_over_time(v.history, info.budget_ms, v.now_unix_ms);
  h += "<figcaption class=\"note\">Each cycle at its trigger time; colour: the STATUS it ended "
       "with.</figcaption></figure></div>";
  return h;
}

std::string counts_section(const StatusSnapshot& s) {
  std::string h = "<h2>Counts since start</h2><div class=\"row\"><table><tr>" + head("LOCATE cycles", true) +
                  head("") + "</tr>";
  for (reg::Status st : {reg::Status::done_ok, reg::Status::done_none, reg::Status::error})
    h += "<tr>" + cell(status_name(st), true) + cell(std::to_string(s.locate_by_status[std::size_t(st)])) +
         "</tr>";
  h += "<tr>" + cell("cut short by the budget", true) + cell(std::to_string(s.budget_exhausted)) +
       "</tr></table>";
  h += "<table><tr>" + head("ERROR code (all commands)", true) + head("") + "</tr>";
  for (int code = 1; code < 7; ++code)
    h += "<tr>" + cell(std::to_string(code) + " " + error_name(reg::Error(code)), true) +
         cell(std::to_string(s.errors_by_code[code])) + "</tr>";
  h += "</table><table><tr>" + head("other", true) + head("") + "</tr>";
  h += "<tr>" + cell("poses handed out (DONE_OK)", true) + cell(std::to_string(s.picks)) + "</tr>";
  h += "<tr>" + cell("picks that took nothing (log folder, took-nothing/)", true) +
       cell(std::to_string(s.picks_took_nothing)) + "</tr>";
  h += "<tr>" + cell("NEXT commands", true) + cell(std::to_string(s.commands_by_type[1])) + "</tr>";
  h += "<tr>" + cell("CLEAR_ERROR commands", true) + cell(std::to_string(s.commands_by_type[2])) + "</tr>";
  h += "<tr>" + cell("HEARTBEAT increments", true) + cell(std::to_string(s.heartbeats)) +
       "</tr></table></div>";
  return h;
}

std::string recent_section(const StatusSnapshot& s) {
  std::string h = "<h2>Last results, newest first</h2>";
  if (s.recent_count == 0) return h + "<p class=\"note\">No command yet.</p>";
  h += "<table><tr>" + head("at (UTC)", true) + head("REQ_ID") + head("CMD", true) + head("STATUS", true) +
       head("ERROR", true) + head("poses") + head("INDEX") + head("SCORE") + head("cycle ms") +
       head("frame age ms") + "</tr>";
  for (int k = 0; k < s.recent_count; ++k) {
    const int i = (s.recent_next - 1 - k + 2 * StatusSnapshot::kRecent) % StatusSnapshot::kRecent;
    const StatusRow& r = s.recent[i];
    const bool locate = r.command == std::uint16_t(reg::Command::locate);
    h += "<tr>" + cell(utc_text(r.trigger_unix_ms), true) + cell(std::to_string(r.req_id)) +
         cell(command_name(r.command), true) + status_cell(r.status) +
         cell(error_text(r.error, r.frame_check), true) + cell(std::to_string(r.count)) +
         cell(r.status == reg::Status::done_ok ? std::to_string(r.index) : "-") +
         cell(r.status == reg::Status::done_ok ? fmt("%.3f", r.score) : "-") + cell(fmt("%.1f", r.cycle_ms)) +
         cell(locate ? fmt("%.1f", r.frame_age_ms) : "-") + "</tr>";
  }
  return h + "</table>";
}

std::string clients_section(const StatusView& v) {
  const StatusSnapshot& s = v.s;
  std::string h = "<h2>PLC clients connected (" + std::to_string(s.client_count) + ")</h2>";
  if (s.client_count == 0) return h + "<p class=\"note\">None.</p>";
  h += "<table><tr>" + head("address", true) + head("role", true) + head("connected for") + head("requests") +
       head("last request") + "</tr>";
  for (int i = 0; i < s.client_count; ++i) {
    const PlcClientInfo& c = s.clients[i];
    h += "<tr>" + cell(html_escape(c.ip), true) +
         cell(c.plc ? "PLC (plc.plc_addresses)" : "other client", true) +
         cell(duration_text(ms_between(c.connected, v.now) / 1000)) + cell(std::to_string(c.requests)) +
         cell(c.requests ? fmt("%.1f s ago", ms_between(c.last_request, v.now) / 1000) : "none yet") +
         "</tr>";
  }
  return h + "</table>";
}

std::string config_section(const StatusInfo& info) {
  std::string h = "<h2>Config in effect</h2><pre>";
  for (const std::string& line : info.config) h += html_escape(line) + "\n";
  return h + "</pre>";
}

}  // namespace

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

const char* command_name(std::uint16_t command) {
  switch (command) {
    case std::uint16_t(reg::Command::locate):
      return "1 LOCATE";
    case std::uint16_t(reg::Command::next):
      return "2 NEXT";
    case std::uint16_t(reg::Command::clear_error):
      return "3 CLEAR_ERROR";
    default:
      return "unknown";
  }
}

std::string render_status_page(const StatusView& view, const StatusInfo& info) {
  std::string h =
      "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><meta http-equiv=\"refresh\" "
      "content=\"" +
      std::to_string(info.refresh_s) + "\"><title>pipeloc status</title><style>" + kStyle +
      "</style></head><body>";
  h += header(view, info);
  h += "<div class=\"row\">" + overlay_section(view.s) + last_locate_section(view.s) + "</div>";
  h += plots_section(view, info);
  h += counts_section(view.s);
  h += recent_section(view.s);
  h += clients_section(view);
  h += config_section(info);
  h += "<p class=\"note\">Also here: <a href=\"/metrics\">/metrics</a> (Prometheus), <a "
       "href=\"/api/status\">/api/status</a> "
       "(JSON), <a href=\"/overlay.png\">/overlay.png</a>. Registers and codes: "
       "firmware-host/REGISTERS.md.</p>";
  return h + "</body></html>\n";
}

}  // namespace pipeloc
