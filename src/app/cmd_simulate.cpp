#include <spdlog/spdlog.h>

#include <chrono>

#include "app/commands.hpp"
#include "model/pipe_model.hpp"
#include "sim/dataset_writer.hpp"

namespace pipeloc::app {

void add_simulate(CLI::App& app) {
  struct Options {
    std::string model;
    SimulateRequest req;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("simulate", "Simulate a bin of pipes seen by a Kinect-class sensor (BOP layout)");
  cmd->add_option("--model", opt->model, "pipe STL (mm)")->required();
  cmd->add_option("--images", opt->req.images, "frames to simulate, each a new pile")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", opt->req.seed, "random seed (same seed, same data)");
  cmd->add_option("--out", opt->req.out_dir, "dataset directory to write")->required();
  cmd->add_option("--tilt-deg", opt->req.scene.max_tilt_deg,
                  "camera tilt from vertical, drawn in [0, T] degrees")
      ->check(CLI::Range(0.0, 45.0));
  cmd->add_option("--pipes", opt->req.scene.pile.pipes, "pipes dropped into the bin")
      ->check(CLI::Range(1, 200));
  cmd->add_option("--scene-id", opt->req.scene_id, "BOP scene id")->check(CLI::Range(0, 999999));
  cmd->add_option("--obj-id", opt->req.obj_id, "BOP object id")->check(CLI::Range(1, 999999));
  cmd->callback([opt] {
    const PipeModel model = load_pipe_model(opt->model);
    const auto t0 = std::chrono::steady_clock::now();
    write_simulated_dataset(model, opt->req);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    spdlog::info("simulated {} images of {} pipes into {} in {:.2f} s ({:.0f} ms/image)", opt->req.images,
                 opt->req.scene.pile.pipes, opt->req.out_dir, s, 1e3 * s / opt->req.images);
  });
}

}  // namespace pipeloc::app
