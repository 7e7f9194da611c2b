// pipeloc record: writes what the configured frame source delivers as a BOP dataset (depth PNGs,
// scene_camera.json, the model, test targets, a shaded preview of each frame), so an integrator
// can collect real frames and evaluate offline with eval-bop and the overlays.
#include <spdlog/spdlog.h>

#include <filesystem>

#include "app/commands.hpp"
#include "io/bop.hpp"
#include "io/png.hpp"
#include "model/stl.hpp"
#include "render/overlay.hpp"
#include "service/service.hpp"
#include "sim/dataset_writer.hpp"
#include "sim/sensor.hpp"

namespace pipeloc::app {

void add_record(CLI::App& app) {
  struct Options {
    std::string config, out;
    int frames = 10, period_ms = 0;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("record", "Write frames of the configured source as a BOP dataset");
  cmd->add_option("--config", opt->config, "TOML config ([source], [model]); default: the simulated bin");
  cmd->add_option("--frames", opt->frames, "frames to record")->check(CLI::Range(1, 100000));
  cmd->add_option("--period-ms", opt->period_ms, "pause between frames")->check(CLI::Range(0, 3600000));
  cmd->add_option("--out", opt->out, "dataset folder to write")->required();
  cmd->callback([opt] {
    const AppConfig cfg = opt->config.empty() ? embedded_default_config() : load_config(opt->config);
    for (const auto& line : cfg.warnings) spdlog::warn("{}", line);
    const PipeModel model = load_config_model(cfg);
    std::unique_ptr<FrameSource> source = open_frame_source(cfg, model);
    spdlog::info("record: {}", source->describe());
    const std::string scene = scene_dir(opt->out, 1);
    std::error_code ec;
    std::filesystem::create_directories(scene + "/depth", ec);
    std::filesystem::create_directories(opt->out + "/models", ec);
    if (ec) throw IoError("cannot create '" + opt->out + "': " + ec.message());
    write_stl(model_path(opt->out, 1), model.mesh);
    write_json(opt->out + "/models/models_info.json", {{"1", model_info_json(model, model.source)}});

    Frame frame;
    frame.depth_mm.resize(source->intrinsics().width, source->intrinsics().height, 0.0f);
    Json cameras = Json::object(), targets = Json::array();
    int written = 0, failed = 0;
    for (int i = 0; written < opt->frames; ++i) {
      const auto now = Clock::now();
      GrabStatus st = source->grab(now, now + std::chrono::seconds(2), &frame);
      if (st == GrabStatus::ok) st = check_frame(frame.depth_mm, source->intrinsics());
      if (st != GrabStatus::ok) {
        spdlog::warn("record: frame {}: {}", i, grab_status_name(st));
        if (++failed > 3 * opt->frames + 10) throw SourceError("record: the source keeps failing; stopped");
        continue;
      }
      write_depth_png(depth_path(opt->out, 1, written),
                      to_raw_depth(frame.depth_mm, frame.camera.depth_scale));
      char name[32];
      std::snprintf(name, sizeof name, "/preview_%06d.png", written);
      write_rgb_png(scene + name, shade_depth(frame.depth_mm));
      cameras[std::to_string(written)] = camera_to_json(frame.camera);
      targets.push_back({{"scene_id", 1}, {"im_id", written}, {"obj_id", 1}, {"inst_count", 1}});
      ++written;
      if (opt->period_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(opt->period_ms));
    }
    write_json(scene + "/scene_camera.json", cameras);
    write_json(opt->out + "/test_targets_bop19.json", targets, -1);
    std::printf("record: %d frames from %s written to %s\n", written, source->kind(), opt->out.c_str());
  });
}

}  // namespace pipeloc::app
