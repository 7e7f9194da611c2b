#include <spdlog/spdlog.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <memory>

#include "app/commands.hpp"
#include "config/config_file.hpp"
#include "locate/locator.hpp"
#include "model/make_pipe.hpp"
#include "sim/scene.hpp"

namespace pipeloc::app {
namespace {

struct Series {
  const char* name;
  std::vector<double> ms;
};

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::size_t(q * double(v.size() - 1) + 0.5)];
}

}  // namespace

void add_bench(CLI::App& app) {
  struct Options {
    std::string model = "sbend", config;
    int frames = 30, warmup = 3, pipes = 20;
    unsigned seed = 1;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("bench", "Time the localization cycle and its stages on simulated frames");
  cmd->add_option("--model", opt->model, "pipe STL, or a preset: sbend | u | torus");
  cmd->add_option("--frames", opt->frames, "frames timed")->check(CLI::Range(1, 100000));
  cmd->add_option("--warmup", opt->warmup, "frames run first and not timed")->check(CLI::Range(0, 1000));
  cmd->add_option("--pipes", opt->pipes, "pipes per simulated bin")->check(CLI::Range(1, 200));
  cmd->add_option("--seed", opt->seed, "simulator seed");
  cmd->add_option("--config", opt->config, "TOML config ([locate] thresholds)");
  cmd->callback([opt] {
    const LocateConfig cfg = opt->config.empty() ? LocateConfig{} : load_config(opt->config).locate;
    const bool preset = opt->model == "sbend" || opt->model == "u" || opt->model == "torus";
    const PipeModel model = preset ? derive_pipe_model(make_pipe(pipe_preset(opt->model)), opt->model)
                                   : load_pipe_model(opt->model);
    SceneParams params;
    params.pile.pipes = opt->pipes;
    std::mt19937 rng(opt->seed);
    // Frames are made first so that only the localizer is timed.
    const int distinct = std::min(opt->frames + opt->warmup, 20);
    std::vector<SimulatedScene> scenes;
    for (int i = 0; i < distinct; ++i) scenes.push_back(simulate_scene(model, params, rng));
    Locator locator(model, cfg, params.intrinsics);
    for (int i = 0; i < opt->warmup; ++i)
      locator.locate(scenes[std::size_t(i % distinct)].depth_mm, scenes[std::size_t(i % distinct)].camera);
    std::vector<Series> series = {{"cycle", {}}, {"zbuffer", {}},    {"normals", {}}, {"regions", {}},
                                  {"axis*", {}}, {"ridge_icp*", {}}, {"refine*", {}}, {"verify*", {}}};
    int found = 0;
    for (int i = 0; i < opt->frames; ++i) {
      const SimulatedScene& s = scenes[std::size_t((i + opt->warmup) % distinct)];
      const LocateOutput& out = locator.locate(s.depth_mm, s.camera);
      const StageTimes& t = out.times;
      const double v[] = {t.total_ms, t.zbuffer_ms,   t.normals_ms, t.regions_ms,
                          t.axis_ms,  t.ridge_icp_ms, t.refine_ms,  t.verify_ms};
      for (std::size_t k = 0; k < series.size(); ++k) series[k].ms.push_back(v[k]);
      found += int(out.estimates.size());
    }
    std::printf("%-12s %10s %10s %10s   (%d frames of %d %s pipes, %d threads; * = summed over threads)\n",
                "stage", "median_ms", "p95_ms", "max_ms", opt->frames, opt->pipes, opt->model.c_str(),
                cfg.threads);
    for (const auto& s : series)
      std::printf("%-12s %10.1f %10.1f %10.1f\n", s.name, quantile(s.ms, 0.5), quantile(s.ms, 0.95),
                  *std::max_element(s.ms.begin(), s.ms.end()));
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::printf("poses per frame %.1f, peak RSS %.1f MB\n", double(found) / opt->frames,
                usage.ru_maxrss / 1024.0);
  });
}

}  // namespace pipeloc::app
