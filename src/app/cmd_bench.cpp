#include <spdlog/spdlog.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>

#include "app/commands.hpp"
#include "config/config_file.hpp"
#include "io/bop.hpp"
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

// One frame to time: which locator, what it sees.
struct BenchFrame {
  int locator = 0;
  const Image<float>* depth;
  const CameraInfo* camera;
};

}  // namespace

void add_bench(CLI::App& app) {
  struct Options {
    std::string model = "sbend", config, dataset;
    int frames = 30, warmup = 3, pipes = 20, rounds = 3;
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
  cmd->add_option("--dataset", opt->dataset,
                  "time the frames of a BOP dataset's targets instead (recorded or simulated): each once "
                  "untimed, then --rounds times");
  cmd->add_option("--rounds", opt->rounds, "with --dataset: timed passes over its frames")
      ->check(CLI::Range(1, 1000));
  cmd->callback([opt, cmd] {
    // An option the chosen mode does not use is refused: the run would not be what was asked for.
    for (const char* o : {"--model", "--frames", "--warmup", "--pipes", "--seed"})
      if (!opt->dataset.empty() && cmd->count(o))
        throw CLI::ValidationError(
            o,
            "simulated frames only; with --dataset the dataset's frames and models are "
            "timed (--rounds passes)");
    if (opt->dataset.empty() && cmd->count("--rounds"))
      throw CLI::ValidationError("--rounds",
                                 "with --dataset only; simulated frames are timed --frames times");
    const LocateConfig cfg = opt->config.empty() ? LocateConfig{} : load_config(opt->config).locate;
    std::vector<std::unique_ptr<PipeModel>> models;
    std::vector<std::unique_ptr<Locator>> locators;
    std::vector<SimulatedScene> scenes;
    std::vector<TargetFrame> recorded;
    std::vector<BenchFrame> warmup, timed;
    std::string what;
    if (opt->dataset.empty()) {
      const bool preset = opt->model == "sbend" || opt->model == "u" || opt->model == "torus";
      models.push_back(std::make_unique<PipeModel>(
          preset ? derive_pipe_model(make_pipe(pipe_preset(opt->model)), opt->model)
                 : load_pipe_model(opt->model)));
      SceneParams params;
      params.pile.pipes = opt->pipes;
      std::mt19937 rng(opt->seed);
      // Frames are made first so that only the localizer is timed.
      const int distinct = std::min(opt->frames + opt->warmup, 20);
      for (int i = 0; i < distinct; ++i) scenes.push_back(simulate_scene(*models[0], params, rng));
      locators.push_back(std::make_unique<Locator>(*models[0], cfg, params.intrinsics));
      const auto frame = [&](int i) {
        const SimulatedScene& s = scenes[std::size_t(i % distinct)];
        return BenchFrame{0, &s.depth_mm, &s.camera};
      };
      for (int i = 0; i < opt->warmup; ++i) warmup.push_back(frame(i));
      for (int i = 0; i < opt->frames; ++i) timed.push_back(frame(i + opt->warmup));
      what = fmt::format("{} frames of {} {} pipes", opt->frames, opt->pipes, opt->model);
    } else {
      const auto targets = read_targets(opt->dataset + "/test_targets_bop19.json");
      std::map<int, std::map<int, CameraInfo>> cameras;
      std::map<int, int> locator_of;  // obj_id -> index
      recorded.reserve(targets.size());
      for (const auto& t : targets) {
        recorded.push_back(read_target_frame(opt->dataset, t, &cameras));
        if (!locator_of.count(t.obj_id)) {
          locator_of[t.obj_id] = int(locators.size());
          models.push_back(std::make_unique<PipeModel>(load_pipe_model(model_path(opt->dataset, t.obj_id))));
          locators.push_back(
              std::make_unique<Locator>(*models.back(), cfg, recorded.back().camera.intrinsics));
        }
        const BenchFrame f{locator_of[t.obj_id], &recorded.back().depth_mm, &recorded.back().camera};
        warmup.push_back(f);
      }
      for (int r = 0; r < opt->rounds; ++r) timed.insert(timed.end(), warmup.begin(), warmup.end());
      what =
          fmt::format("{} rounds over the {} target frames of {}", opt->rounds, warmup.size(), opt->dataset);
    }
    for (const BenchFrame& f : warmup) locators[std::size_t(f.locator)]->locate(*f.depth, *f.camera);
    // to_pick: up to the pick (what the PLC waits for); again: the second searches after it.
    std::vector<Series> series = {{"cycle", {}},   {"to_pick", {}}, {"again", {}}, {"zbuffer", {}},
                                  {"normals", {}}, {"regions", {}}, {"axis*", {}}, {"ridge_icp*", {}},
                                  {"refine*", {}}, {"verify*", {}}};
    int found = 0;
    for (const BenchFrame& f : timed) {
      const LocateOutput& out = locators[std::size_t(f.locator)]->locate(*f.depth, *f.camera);
      const StageTimes& t = out.times;
      const double v[] = {
          t.total_ms, t.total_ms - t.again_ms, t.again_ms,  t.zbuffer_ms, t.normals_ms, t.regions_ms,
          t.axis_ms,  t.ridge_icp_ms,          t.refine_ms, t.verify_ms};
      for (std::size_t k = 0; k < series.size(); ++k) series[k].ms.push_back(v[k]);
      found += int(out.estimates.size());
    }
    std::printf("%-12s %10s %10s %10s   (%s, %d threads; * = summed over threads)\n", "stage", "median_ms",
                "p95_ms", "max_ms", what.c_str(), cfg.threads);
    for (const auto& s : series)
      std::printf("%-12s %10.1f %10.1f %10.1f\n", s.name, quantile(s.ms, 0.5), quantile(s.ms, 0.95),
                  *std::max_element(s.ms.begin(), s.ms.end()));
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::printf("poses per frame %.1f, peak RSS %.1f MB\n", double(found) / double(timed.size()),
                usage.ru_maxrss / 1024.0);
  });
}

}  // namespace pipeloc::app
