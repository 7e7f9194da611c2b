// pipeloc plot-budget: the curve of tools/budget-sweep. Reads its table (budget_ms, recall_5mm,
// pick_rate, pick_correct_5mm, wrong_picks, ...) and draws recall@5 mm, pick rate and
// pick-correct@5 mm against the budget on a log axis, each budget ticked, wrong picks in red.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "app/commands.hpp"
#include "io/json_file.hpp"
#include "io/png.hpp"
#include "render/overlay.hpp"
#include "render/text.hpp"

namespace pipeloc::app {
namespace {

using Row = std::map<std::string, double>;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, ',')) out.push_back(cell);
  return out;
}

std::vector<Row> read_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("budget table '" + path + "': cannot open");
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line);
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line);
    if (cells.size() != header.size())
      throw IoError("budget table '" + path + "': a row with " + std::to_string(cells.size()) +
                    " cells, header has " + std::to_string(header.size()));
    Row r;
    for (std::size_t i = 0; i < cells.size(); ++i) r[header[i]] = std::atof(cells[i].c_str());
    rows.push_back(r);
  }
  for (const char* key : {"budget_ms", "recall_5mm", "pick_rate", "pick_correct_5mm", "wrong_picks"})
    if (rows.empty() || !rows.front().count(key))
      throw IoError("budget table '" + path + "': expected rows with a '" + key + "' column");
  std::sort(rows.begin(), rows.end(),
            [](const Row& a, const Row& b) { return a.at("budget_ms") < b.at("budget_ms"); });
  return rows;
}

std::string fmt(double v, const char* f) {
  char s[32];
  std::snprintf(s, sizeof s, f, v);
  return s;
}

void draw_curves(const std::vector<Row>& rows, const std::string& title, const std::string& png) {
  Image<Rgb> img(900, 560, Rgb{255, 255, 255});
  const Rgb black{0, 0, 0}, grey{200, 200, 200}, red{220, 30, 30};
  const int left = 70, right = 30, top = 60, bottom = 80;
  const int w = img.width - left - right, h = img.height - top - bottom, base = top + h;
  const double b0 = std::log(rows.front().at("budget_ms")), b1 = std::log(rows.back().at("budget_ms"));
  const double pad = std::max(0.05 * (b1 - b0), 0.1);
  auto x_of = [&](double ms) { return left + (std::log(ms) - b0 + pad) / (b1 - b0 + 2 * pad) * w; };
  auto y_of = [&](double share) { return base - share * h; };
  draw_text(&img, 10, 8, title, black);
  for (int i = 0; i <= 10; ++i) {  // shares, grid every 0.1
    const double v = i / 10.0;
    draw_line(&img, left, y_of(v), left + w, y_of(v), i % 5 ? Rgb{235, 235, 235} : grey);
    draw_text(&img, 12, int(y_of(v)) - 5, fmt(v, "%.1f"), black);
  }
  for (const Row& r : rows) {  // each budget swept is a tick
    const double x = x_of(r.at("budget_ms"));
    draw_line(&img, x, top, x, base, Rgb{235, 235, 235});
    draw_line(&img, x, base, x, base + 5, black);
    draw_text(&img, int(x) - 8, base + 9, fmt(r.at("budget_ms"), "%g"), black);
    if (const double wrong = r.at("wrong_picks"); wrong > 0)
      draw_text(&img, int(x) - 8, top - 16, fmt(wrong, "%.0f") + " WRONG", red, 1);
  }
  draw_line(&img, left, base, left + w, base, black);
  draw_line(&img, left, top, left, base, black);
  draw_text(&img, left + w / 2 - 150, base + 30, "BUDGET ms (LOG SCALE)", black);
  draw_text(&img, 12, top - 30, "SHARE", black);
  struct Series {
    const char* key;
    const char* label;
    Rgb color;
  };
  const Series series[] = {{"recall_5mm", "TOP RECALL AT 5 mm", {40, 90, 200}},
                           {"pick_rate", "PICK RATE", {30, 150, 60}},
                           {"pick_correct_5mm", "PICK-CORRECT AT 5 mm", {150, 150, 150}}};
  int legend_x = left + 10;
  for (const Series& s : series) {
    for (std::size_t i = 0; i < rows.size(); ++i) {  // NaN (pick-correct without a pick): no point
      const double x = x_of(rows[i].at("budget_ms")), y = y_of(rows[i].at(s.key));
      if (std::isnan(y)) continue;
      if (i > 0 && !std::isnan(rows[i - 1].at(s.key)))
        draw_line(&img, x_of(rows[i - 1].at("budget_ms")), y_of(rows[i - 1].at(s.key)), x, y, s.color, 2);
      draw_dot(&img, x, y, 4, s.color);
    }
    draw_dot(&img, legend_x, base + 58, 4, s.color);
    draw_text(&img, legend_x + 10, base + 53, s.label, black);
    legend_x += 10 + 8 * int(std::string(s.label).size()) + 30;
  }
  for (const Row& r : rows)  // the figures beside the points that matter most
    draw_text(&img, int(x_of(r.at("budget_ms"))) + 6, int(y_of(r.at("recall_5mm"))) + 6,
              fmt(r.at("recall_5mm"), "%.2f"), Rgb{40, 90, 200}, 1);
  write_rgb_png(png, img);
}

}  // namespace

void add_plot_budget(CLI::App& app) {
  struct Options {
    std::string table, png, title = "BUDGET SWEEP";
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("plot-budget",
                                 "Plot recall@5 and pick rate against the budget (tools/budget-sweep)");
  cmd->add_option("--table", opt->table, "budget-sweep.csv of tools/budget-sweep")->required();
  cmd->add_option("--png", opt->png, "PNG to write")->required();
  cmd->add_option("--title", opt->title, "title above the plot");
  cmd->callback([opt] { draw_curves(read_table(opt->table), opt->title, opt->png); });
}

}  // namespace pipeloc::app
