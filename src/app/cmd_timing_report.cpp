// pipeloc timing-report: what a maintainer reads on a deployed cell. Reads the timing log(s)
// (JSON lines of pipeloc serve), prints p50/p95/p99/max of the cycle and each stage with the
// outcome counts, and writes a histogram PNG of the cycle time with the budget marked.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include "app/commands.hpp"
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

void write_histogram(const std::string& path, const std::vector<double>& cycle_ms, double budget_ms) {
  const int w = 800, h = 400, left = 50, right = 20, top = 20, bottom = 40;
  Image<Rgb> img(w, h, Rgb{255, 255, 255});
  const double hi_data = quantile_of(cycle_ms, 1.0);
  const double span = std::max({hi_data, budget_ms, 1.0}) * 1.05;
  const int bins = 60;
  std::vector<int> count(bins, 0);
  for (double v : cycle_ms) count[std::size_t(std::clamp(int(v / span * bins), 0, bins - 1))]++;
  const int peak = std::max(1, *std::max_element(count.begin(), count.end()));
  const double bw = double(w - left - right) / bins;
  auto x_of = [&](double ms) { return left + ms / span * (w - left - right); };
  for (int b = 0; b < bins; ++b) {
    const int bar = int(double(count[std::size_t(b)]) / peak * (h - top - bottom));
    for (int y = h - bottom - bar; y < h - bottom; ++y)
      for (int x = int(left + b * bw) + 1; x < int(left + (b + 1) * bw); ++x) img.at(x, y) = Rgb{60, 110, 200};
  }
  const Rgb black{0, 0, 0}, red{220, 30, 30}, grey{120, 120, 120};
  draw_line(&img, left, h - bottom, w - right, h - bottom, black);
  draw_line(&img, left, top, left, h - bottom, black);
  // Ticks every "nice" step of milliseconds, labelled.
  const double raw = span / 8, mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
  for (double t = 0; t <= span; t += step) {
    draw_line(&img, x_of(t), h - bottom, x_of(t), h - bottom + 5, black);
    draw_text(&img, int(x_of(t)) - 6, h - bottom + 9, fmt(t), black);
  }
  draw_text(&img, w - right - 30, h - bottom + 24, "ms", black);
  draw_text(&img, 4, top, std::to_string(peak), black);
  // The budget (red) and the p50 / p99 (grey).
  draw_line(&img, x_of(budget_ms), top, x_of(budget_ms), h - bottom, red, 2);
  draw_text(&img, int(x_of(budget_ms)) + 4, top, fmt(budget_ms), red);
  for (double q : {0.5, 0.99}) {
    const double v = quantile_of(cycle_ms, q);
    draw_line(&img, x_of(v), top + 20, x_of(v), h - bottom, grey);
    draw_text(&img, int(x_of(v)) + 3, top + 20 + (q > 0.6 ? 14 : 0), (q > 0.6 ? "p99 " : "p50 ") + fmt(v), grey);
  }
  write_rgb_png(path, img);
}

}  // namespace

void add_timing_report(CLI::App& app) {
  struct Options {
    std::vector<std::string> logs;
    std::string png;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("timing-report", "Summarize pipeloc serve timing logs; histogram PNG of the cycle");
  cmd->add_option("logs", opt->logs, "timing.jsonl files (rotated ones too)")->required();
  cmd->add_option("--png", opt->png, "histogram PNG to write (default: beside the first log)");
  cmd->callback([opt] {
    static const char* const kStages[] = {"cycle_ms",  "grab_ms",      "frame_age_ms", "zbuffer_ms", "normals_ms",
                                          "regions_ms", "axis_ms",     "ridge_icp_ms", "refine_ms",  "verify_ms"};
    std::map<std::string, std::vector<double>> series;
    std::map<std::string, int> outcomes;
    int cycles = 0, cut = 0, malformed = 0;
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
        if (j.value("event", "") != "cycle" || j.value("cmd", 0) != 1) continue;
        ++cycles;
        for (const char* k : kStages) series[k].push_back(j.value(k, 0.0));
        outcomes[j.value("status", "?") + (j.value("error", "none") == "none" ? "" : " " + j.value("error", ""))]++;
        cut += j.value("budget_exhausted", false);
        budget_ms = j.value("budget_ms", budget_ms);
      }
    }
    if (cycles == 0) throw IoError("timing log: no LOCATE cycles in " + opt->logs.front());
    std::printf("%d LOCATE cycles, budget %.0f ms, cut short by the budget %d (%.1f %%)%s\n", cycles, budget_ms, cut,
                100.0 * cut / cycles, malformed ? (", " + std::to_string(malformed) + " unreadable lines").c_str() : "");
    std::printf("%-14s %9s %9s %9s %9s\n", "stage", "p50_ms", "p95_ms", "p99_ms", "max_ms");
    for (const char* k : kStages) {
      const auto& v = series[k];
      std::printf("%-14s %9.1f %9.1f %9.1f %9.1f\n", k, quantile_of(v, 0.5), quantile_of(v, 0.95),
                  quantile_of(v, 0.99), quantile_of(v, 1.0));
    }
    std::printf("outcomes:");
    for (const auto& [name, n] : outcomes) std::printf("  %s %d", name.c_str(), n);
    std::printf("\n");
    const std::string png = opt->png.empty() ? opt->logs.front() + ".png" : opt->png;
    write_histogram(png, series["cycle_ms"], budget_ms);
    std::printf("histogram of cycle_ms: %s\n", png.c_str());
  });
}

}  // namespace pipeloc::app
