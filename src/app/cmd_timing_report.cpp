// pipeloc timing-report: what a maintainer reads on a deployed cell. Reads the timing log(s)
// (JSON lines of pipeloc serve), prints the cycles' time range, p50/p95/p99/max of the cycle and
// of each stage over the cycles it ran in, the cycle time per outcome, and writes a PNG: a
// histogram of the cycle time with the budget marked, and the cycle time over time.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <type_traits>

#include "app/commands.hpp"
#include "core/clock.hpp"
#include "io/json_file.hpp"
#include "io/png.hpp"
#include "render/overlay.hpp"
#include "render/text.hpp"

namespace pipeloc::app {
namespace {

double quantile_of(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::size_t(q * double(v.size() - 1) + 0.5)];
}

std::string fmt(double v) {
  char s[32];
  std::snprintf(s, sizeof s, v < 10 ? "%.1f" : "%.0f", v);
  return s;
}


// A field of a timing-log line: absent -> fallback; present with another type -> an IoError naming
// the file, the line and the field (a hand-edited or foreign log, not a raw json exception).
template <typename T>
T field(const Json& j, const char* key, T fallback, const std::string& path, int line) {
  const auto it = j.find(key);
  if (it == j.end()) return fallback;
  const bool ok = std::is_same_v<T, bool>          ? it->is_boolean()
                  : std::is_same_v<T, std::string> ? it->is_string()
                                                   : it->is_number();
  if (!ok)
    throw IoError("timing log '" + path + "': line " + std::to_string(line) + ": field \"" + key +
                  "\": expected " +
                  (std::is_same_v<T, bool>          ? "true or false"
                   : std::is_same_v<T, std::string> ? "a string"
                                                    : "a number") +
                  ", got " + it->dump());
  return it->template get<T>();
}

struct Cycle {
  double trigger_unix_ms, cycle_ms;
  std::string outcome;
};

Rgb outcome_color(const std::string& outcome) {
  if (outcome.rfind("DONE_OK", 0) == 0) return {40, 160, 60};
  if (outcome.rfind("DONE_NONE", 0) == 0) return {120, 120, 120};
  return {220, 30, 30};
}

// Ticks every "nice" step below `span`, about `n` of them.
double nice_step(double span, int n) {
  const double raw = span / n, mag = std::pow(10.0, std::floor(std::log10(raw)));
  return raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
}

// Top panel: histogram of the cycle time, the budget (red), p50 / p95 / p99 (grey).
void draw_histogram(Image<Rgb>* img, int top, int h, const std::vector<double>& cycle_ms, double budget_ms,
                    double span) {
  const int w = img->width, left = 50, right = 20, bottom = 40;
  const int bins = 60;
  std::vector<int> count(bins, 0);
  for (double v : cycle_ms) count[std::size_t(std::clamp(int(v / span * bins), 0, bins - 1))]++;
  const int peak = std::max(1, *std::max_element(count.begin(), count.end()));
  const double bw = double(w - left - right) / bins;
  auto x_of = [&](double ms) { return left + ms / span * (w - left - right); };
  const int base = top + h - bottom;
  for (int b = 0; b < bins; ++b) {
    const int bar = int(double(count[std::size_t(b)]) / peak * (h - bottom - 20));
    for (int y = base - bar; y < base; ++y)
      for (int x = int(left + b * bw) + 1; x < int(left + (b + 1) * bw); ++x)
        img->at(x, y) = Rgb{60, 110, 200};
  }
  const Rgb black{0, 0, 0}, red{220, 30, 30}, grey{120, 120, 120};
  draw_line(img, left, base, w - right, base, black);
  draw_line(img, left, top, left, base, black);
  const double step = nice_step(span, 8);
  for (double t = 0; t <= span; t += step) {
    draw_line(img, x_of(t), base, x_of(t), base + 5, black);
    draw_text(img, int(x_of(t)) - 6, base + 9, fmt(t), black);
  }
  draw_text(img, w - right - 150, base + 24, "CYCLE TIME ms", black);
  draw_text(img, 4, top, std::to_string(peak), black);
  draw_text(img, 4, top + 14, "CYCLES", black, 1);
  draw_line(img, x_of(budget_ms), top, x_of(budget_ms), base, red, 2);
  draw_text(img, int(x_of(budget_ms)) + 4, top, "BUDGET " + fmt(budget_ms), red);
  int row = 0;
  for (double q : {0.5, 0.95, 0.99}) {
    const double v = quantile_of(cycle_ms, q);
    draw_line(img, x_of(v), top + 20, x_of(v), base, grey);
    draw_text(img, int(x_of(v)) + 3, top + 20 + 14 * row++,
              (q == 0.5    ? "P50 "
               : q == 0.95 ? "P95 "
                           : "P99 ") +
                  fmt(v),
              grey);
  }
}

// Bottom panel: each cycle's time against when it was triggered, coloured by outcome, so that
// stalls show where they happened.
void draw_over_time(Image<Rgb>* img, int top, int h, const std::vector<Cycle>& cycles, double budget_ms,
                    double span) {
  const int w = img->width, left = 50, right = 20, bottom = 40;
  const Rgb black{0, 0, 0}, red{220, 30, 30};
  const int base = top + h - bottom;
  double t0 = cycles.front().trigger_unix_ms, t1 = t0;
  for (const Cycle& c : cycles) t0 = std::min(t0, c.trigger_unix_ms), t1 = std::max(t1, c.trigger_unix_ms);
  const double dur_s = std::max(1.0, (t1 - t0) / 1000);
  const bool minutes = dur_s > 300;
  const double unit = minutes ? 60 : 1, dur = dur_s / unit;
  auto x_of = [&](double unix_ms) { return left + (unix_ms - t0) / 1000 / unit / dur * (w - left - right); };
  auto y_of = [&](double ms) { return base - std::min(ms, span) / span * (h - bottom - 10); };
  draw_line(img, left, base, w - right, base, black);
  draw_line(img, left, top, left, base, black);
  const double ystep = nice_step(span, 5);
  for (double v = 0; v <= span; v += ystep) {
    draw_line(img, left - 5, y_of(v), left, y_of(v), black);
    draw_text(img, 4, int(y_of(v)) - 5, fmt(v), black);
  }
  const double xstep = nice_step(dur, 8);
  for (double t = 0; t <= dur; t += xstep) {
    const double x = left + t / dur * (w - left - right);
    draw_line(img, x, base, x, base + 5, black);
    draw_text(img, int(x) - 6, base + 9, fmt(t), black);
  }
  draw_text(img, w - right - 250, base + 24,
            minutes ? "MINUTES SINCE THE FIRST CYCLE" : "SECONDS SINCE THE FIRST CYCLE", black);
  draw_line(img, left, y_of(budget_ms), w - right, y_of(budget_ms), red, 1);
  for (const Cycle& c : cycles)
    draw_dot(img, x_of(c.trigger_unix_ms), y_of(c.cycle_ms), 1, outcome_color(c.outcome));
  int x = left + 10;
  for (const char* name : {"DONE_OK", "DONE_NONE", "ERROR"}) {
    draw_dot(img, x, top + 4, 2, outcome_color(name));
    draw_text(img, x + 6, top, name, black, 1);
    x += 80;
  }
  draw_text(img, x, top, "CYCLE TIME ms OVER TIME (RED: BUDGET)", black, 1);
}

void write_report_png(const std::string& path, const std::vector<Cycle>& cycles,
                      const std::vector<double>& cycle_ms, double budget_ms, const std::string& title) {
  Image<Rgb> img(800, 720, Rgb{255, 255, 255});
  draw_text(&img, 10, 8, title, Rgb{0, 0, 0});
  const double span = std::max({quantile_of(cycle_ms, 1.0), budget_ms, 1.0}) * 1.05;
  draw_histogram(&img, 40, 340, cycle_ms, budget_ms, span);
  draw_over_time(&img, 390, 320, cycles, budget_ms, span);
  write_rgb_png(path, img);
}

}  // namespace

void add_timing_report(CLI::App& app) {
  struct Options {
    std::vector<std::string> logs;
    std::string png;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("timing-report", "Summarize pipeloc serve timing logs; histogram PNG of the cycle");
  cmd->add_option("logs", opt->logs, "timing.jsonl files (rotated ones too)")->required();
  cmd->add_option("--png", opt->png, "histogram PNG to write (default: beside the first log)");
  cmd->callback([opt] {
    // again_ms: the second searches, after the result (not in cycle_ms).
    static const char* const kStages[] = {"cycle_ms",   "grab_ms",    "frame_age_ms", "zbuffer_ms",
                                          "normals_ms", "regions_ms", "axis_ms",      "ridge_icp_ms",
                                          "refine_ms",  "verify_ms",  "again_ms"};
    std::map<std::string, std::vector<double>> series;  // a stage's times where it ran (> 0)
    std::map<std::string, std::vector<double>> by_outcome;
    std::vector<Cycle> all;
    int cycles = 0, cut = 0, malformed = 0, picked = 0, took_nothing = 0;
    double budget_ms = 0;
    for (const std::string& path : opt->logs) {
      std::ifstream in(path);
      if (!in) throw IoError("timing log '" + path + "': cannot open");
      std::string line;
      int n = 0;
      while (std::getline(in, line)) {
        ++n;
        Json j;
        try {
          j = Json::parse(line);
        } catch (const Json::exception&) {
          ++malformed;  // e.g. a line cut by a power loss
          continue;
        }
        if (!j.is_object()) {
          ++malformed;
          continue;
        }
        if (field<std::string>(j, "event", "", path, n) != "cycle" ||
            field<double>(j, "cmd", 0, path, n) != 1)
          continue;
        if (!j.contains("cycle_ms") || !j.contains("trigger_unix_ms"))
          throw IoError("timing log '" + path + "': line " + std::to_string(n) +
                        ": a cycle without field \"" +
                        (j.contains("cycle_ms") ? "trigger_unix_ms" : "cycle_ms") + "\"");
        ++cycles;
        for (const char* k : kStages)
          if (const double v = field<double>(j, k, 0.0, path, n); v > 0 || std::string(k) == "cycle_ms")
            series[k].push_back(v);
        const std::string error = field<std::string>(j, "error", "none", path, n);
        const std::string outcome =
            field<std::string>(j, "status", "?", path, n) + (error == "none" ? "" : " " + error);
        const double cycle_ms = field<double>(j, "cycle_ms", 0.0, path, n);
        by_outcome[outcome].push_back(cycle_ms);
        all.push_back({field<double>(j, "trigger_unix_ms", 0.0, path, n), cycle_ms, outcome});
        cut += field<bool>(j, "budget_exhausted", false, path, n);
        picked += outcome == "DONE_OK";
        took_nothing += field<bool>(j, "last_pick_took_nothing", false, path, n);
        budget_ms = field<double>(j, "budget_ms", budget_ms, path, n);
      }
    }
    if (cycles == 0) throw IoError("timing log: no LOCATE cycles in " + opt->logs.front());
    double t0 = all.front().trigger_unix_ms, t1 = t0;
    for (const Cycle& c : all) t0 = std::min(t0, c.trigger_unix_ms), t1 = std::max(t1, c.trigger_unix_ms);
    std::printf(
        "%d LOCATE cycles from %s to %s UTC, budget %.0f ms, cut short by the budget %d (%.1f %%)%s\n",
        cycles, utc_text(t0).c_str(), utc_text(t1).c_str(), budget_ms, cut, 100.0 * cut / cycles,
        malformed ? (", " + std::to_string(malformed) + " unreadable lines").c_str() : "");
    std::printf(
        "picks: %d LOCATEs handed out a pose; %d picks took nothing (the next LOCATE read the bin as before "
        "there: a wrong pose or a failed grip; their frames in the log folder's took-nothing/)\n",
        picked, took_nothing);
    std::printf("%-14s %7s %9s %9s %9s %9s\n", "stage", "cycles", "p50_ms", "p95_ms", "p99_ms", "max_ms");
    for (const char* k : kStages) {
      const auto& v = series[k];
      if (v.empty()) {
        std::printf("%-14s %7d %9s %9s %9s %9s\n", k, 0, "-", "-", "-", "-");
        continue;
      }
      std::printf("%-14s %7zu %9.1f %9.1f %9.1f %9.1f\n", k, v.size(), quantile_of(v, 0.5),
                  quantile_of(v, 0.95), quantile_of(v, 0.99), quantile_of(v, 1.0));
    }
    std::printf("(a stage counts only the cycles it ran in)\n%-24s %7s %9s %9s %9s\n", "outcome", "cycles",
                "p50_ms", "p95_ms", "max_ms");
    for (const auto& [name, v] : by_outcome)
      std::printf("%-24s %7zu %9.1f %9.1f %9.1f\n", name.c_str(), v.size(), quantile_of(v, 0.5),
                  quantile_of(v, 0.95), quantile_of(v, 1.0));
    const std::string png = opt->png.empty() ? opt->logs.front() + ".png" : opt->png;
    char title[160];
    std::snprintf(title, sizeof title, "PIPELOC CYCLE TIME: %d LOCATE CYCLES, %s TO %s UTC", cycles,
                  utc_text(t0).c_str(), utc_text(t1).c_str() + 11);
    write_report_png(png, all, series["cycle_ms"], budget_ms, title);
    std::printf("cycle time histogram and cycle time over time: %s\n", png.c_str());
  });
}

}  // namespace pipeloc::app
