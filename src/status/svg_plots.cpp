#include "status/svg_plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace pipeloc {
namespace {

constexpr int kWidth = 560, kHeight = 260, kLeft = 56, kRight = 16, kTop = 16, kBottom = 44;
constexpr int kPlotW = kWidth - kLeft - kRight, kPlotH = kHeight - kTop - kBottom;

std::string num(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.1f", v);
  return s;
}

std::string tick_label(double v) {
  char s[32];
  std::snprintf(s, sizeof s, std::abs(v - std::round(v)) < 1e-6 ? "%.0f" : "%.1f", v);
  return s;
}

// About n "nice" steps (1, 2, 5 x 10^k) over span.
double nice_step(double span, int n) {
  const double raw = std::max(span, 1e-9) / n, mag = std::pow(10.0, std::floor(std::log10(raw)));
  return raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
}

const char* outcome_colour(reg::Status s) {
  return s == reg::Status::done_ok ? "#2a9d40" : s == reg::Status::done_none ? "#888888" : "#d62020";
}

std::string open_svg(const char* title) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(kWidth) + "\" height=\"" +
         std::to_string(kHeight) + "\" role=\"img\" aria-label=\"" + title +
         "\" style=\"font:11px sans-serif;background:#fff\">";
}

std::string line(double x0, double y0, double x1, double y1, const char* colour, double width = 1,
                 const char* dash = nullptr) {
  return "<line x1=\"" + num(x0) + "\" y1=\"" + num(y0) + "\" x2=\"" + num(x1) + "\" y2=\"" + num(y1) +
         "\" stroke=\"" + colour + "\" stroke-width=\"" + num(width) + "\"" +
         (dash ? std::string(" stroke-dasharray=\"") + dash + "\"" : "") + "/>";
}

std::string text(double x, double y, const std::string& s, const char* anchor = "middle",
                 const char* colour = "#000", double rotate = 0) {
  std::string t = "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\" text-anchor=\"" + anchor + "\" fill=\"" +
                  colour + "\"";
  if (rotate != 0) t += " transform=\"rotate(" + num(rotate) + " " + num(x) + " " + num(y) + ")\"";
  return t + ">" + s + "</text>";
}

std::string axes(const std::string& x_label, const std::string& y_label) {
  const double base = kTop + kPlotH;
  return line(kLeft, base, kLeft + kPlotW, base, "#000") + line(kLeft, kTop, kLeft, base, "#000") +
         text(kLeft + kPlotW / 2.0, kHeight - 6, x_label) +
         text(14, kTop + kPlotH / 2.0, y_label, "middle", "#000", -90);
}

std::string no_data() {
  return text(kLeft + kPlotW / 2.0, kTop + kPlotH / 2.0, "no LOCATE yet", "middle", "#888");
}

double quantile(std::vector<float> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::size_t(q * double(v.size() - 1) + 0.5)];
}

}  // namespace

std::string svg_cycle_histogram(const std::vector<CycleSample>& samples, double budget_ms) {
  std::string svg = open_svg("histogram of the LOCATE cycle time");
  svg += axes("cycle time, trigger to result [ms]", "LOCATE cycles");
  if (samples.empty()) return svg + no_data() + "</svg>";
  std::vector<float> ms;
  for (const CycleSample& c : samples) ms.push_back(c.cycle_ms);
  const double span = std::max(double(*std::max_element(ms.begin(), ms.end())), budget_ms) * 1.05;
  const double bin_ms = nice_step(span, 40);
  const int bins = int(std::ceil(span / bin_ms));
  std::vector<int> count(std::size_t(bins), 0);
  for (float v : ms) ++count[std::size_t(std::clamp(int(v / bin_ms), 0, bins - 1))];
  const int peak = std::max(1, *std::max_element(count.begin(), count.end()));
  const double full = bins * bin_ms, base = kTop + kPlotH;
  auto x_of = [&](double v) { return kLeft + v / full * kPlotW; };
  auto y_of = [&](double n) { return base - n / peak * kPlotH; };
  for (int b = 0; b < bins; ++b) {
    if (!count[std::size_t(b)]) continue;
    svg += "<rect x=\"" + num(x_of(b * bin_ms) + 0.5) + "\" y=\"" + num(y_of(count[std::size_t(b)])) +
           "\" width=\"" + num(std::max(1.0, x_of(bin_ms) - kLeft - 1)) + "\" height=\"" +
           num(base - y_of(count[std::size_t(b)])) + "\" fill=\"#3c6ec8\"/>";
  }
  const double xstep = nice_step(full, 8);
  for (double t = 0; t <= full + 1e-9; t += xstep)
    svg += line(x_of(t), base, x_of(t), base + 4, "#000") + text(x_of(t), base + 16, tick_label(t));
  const double ystep = std::max(1.0, nice_step(peak, 4));
  for (double n = 0; n <= peak + 1e-9; n += ystep)
    svg +=
        line(kLeft - 4, y_of(n), kLeft, y_of(n), "#000") + text(kLeft - 6, y_of(n) + 4, tick_label(n), "end");
  svg += line(x_of(budget_ms), kTop, x_of(budget_ms), base, "#d62020", 2) +
         text(x_of(budget_ms) - 4, kTop + 10, "budget " + tick_label(budget_ms) + " ms", "end", "#d62020");
  int row = 0;
  for (double q : {0.5, 0.95}) {
    const double v = quantile(ms, q);
    svg += line(x_of(v), kTop + 14, x_of(v), base, "#555", 1, "4 3") +
           text(x_of(v) + 4, kTop + 26 + 13 * row++, (q == 0.5 ? "p50 " : "p95 ") + num(v) + " ms", "start",
                "#555");
  }
  return svg + "</svg>";
}

std::string svg_cycle_over_time(const std::vector<CycleSample>& samples, double budget_ms,
                                double now_unix_ms) {
  std::string svg = open_svg("LOCATE cycle time over time");
  if (samples.empty()) return svg + axes("time before now [s]", "cycle time [ms]") + no_data() + "</svg>";
  const double oldest_s = std::max(1.0, (now_unix_ms - samples.front().trigger_unix_ms) / 1000);
  const bool minutes = oldest_s > 300;
  const double unit_s = minutes ? 60 : 1, span_t = oldest_s / unit_s * 1.02;
  svg += axes(minutes ? "time before now [min]" : "time before now [s]", "cycle time [ms]");
  double peak = budget_ms;
  for (const CycleSample& c : samples) peak = std::max(peak, double(c.cycle_ms));
  const double span_ms = peak * 1.08, base = kTop + kPlotH;
  auto x_of = [&](double unix_ms) {
    return kLeft + kPlotW - (now_unix_ms - unix_ms) / 1000 / unit_s / span_t * kPlotW;
  };
  auto y_of = [&](double ms) { return base - ms / span_ms * kPlotH; };
  const double xstep = nice_step(span_t, 6);
  for (double t = 0; t <= span_t + 1e-9; t += xstep) {
    const double x = kLeft + kPlotW - t / span_t * kPlotW;
    svg += line(x, base, x, base + 4, "#000") + text(x, base + 16, tick_label(t));
  }
  const double ystep = nice_step(span_ms, 5);
  for (double v = 0; v <= span_ms + 1e-9; v += ystep)
    svg +=
        line(kLeft - 4, y_of(v), kLeft, y_of(v), "#000") + text(kLeft - 6, y_of(v) + 4, tick_label(v), "end");
  svg += line(kLeft, y_of(budget_ms), kLeft + kPlotW, y_of(budget_ms), "#d62020", 1, "6 3") +
         text(kLeft + 4, y_of(budget_ms) - 4, "budget " + tick_label(budget_ms) + " ms", "start", "#d62020");
  std::string path;
  for (const CycleSample& c : samples) {
    path += (path.empty() ? "M" : " L") + num(x_of(c.trigger_unix_ms)) + " " + num(y_of(c.cycle_ms));
  }
  svg += "<path d=\"" + path + "\" fill=\"none\" stroke=\"#bbb\" stroke-width=\"1\"/>";
  for (const CycleSample& c : samples)
    svg += "<circle cx=\"" + num(x_of(c.trigger_unix_ms)) + "\" cy=\"" + num(y_of(c.cycle_ms)) +
           "\" r=\"2.5\" fill=\"" + outcome_colour(c.status) + "\"/>";
  int x = kLeft + kPlotW - 230;
  for (reg::Status s : {reg::Status::done_ok, reg::Status::done_none, reg::Status::error}) {
    svg += "<circle cx=\"" + num(x) + "\" cy=\"" + num(kTop + 4) + "\" r=\"3.5\" fill=\"" +
           outcome_colour(s) + "\"/>" + text(x + 6, kTop + 8, status_name(s), "start");
    x += 80;
  }
  return svg + "</svg>";
}

}  // namespace pipeloc
