#include <spdlog/spdlog.h>

#include <chrono>
#include <stdexcept>

#include "app/commands.hpp"
#include "model/pipe_model.hpp"
#include "sim/dataset_writer.hpp"

namespace pipeloc::app {

void add_simulate(CLI::App& app) {
  struct Options {
    std::string model, sensor = "kinect";
    std::vector<double> camera_height_mm;
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
  cmd->add_option("--camera-height-mm", opt->camera_height_mm,
                  "camera height above the bin floor, drawn in [MIN, MAX] mm (default 980 1080)")
      ->expected(2)
      ->check(CLI::Range(200.0, 3000.0));
  cmd->add_option("--sensor", opt->sensor,
                  "kinect (structured light) or stereo (active stereo, RealSense D4xx class)")
      ->check(CLI::IsMember({"kinect", "stereo"}));
  cmd->add_option("--pipes", opt->req.scene.pile.pipes, "pipes dropped into the bin")
      ->check(CLI::Range(1, 200));
  cmd->add_option("--scene-id", opt->req.scene_id, "BOP scene id")->check(CLI::Range(0, 999999));
  cmd->add_option("--obj-id", opt->req.obj_id, "BOP object id")->check(CLI::Range(1, 999999));
  cmd->callback([opt] {
    const PipeModel model = load_pipe_model(opt->model);
    SceneParams& scene = opt->req.scene;
    if (!opt->camera_height_mm.empty()) {
      if (opt->camera_height_mm[0] > opt->camera_height_mm[1])
        throw std::invalid_argument("simulate --camera-height-mm: expected MIN <= MAX");
      scene.camera_height_min_mm = opt->camera_height_mm[0];
      scene.camera_height_max_mm = opt->camera_height_mm[1];
    }
    scene.sensor = sensor_model(opt->sensor);
    scene.pile.bin = bin_for_pile(model, scene.pile);
    const PileSize size = pile_size(model, scene.pile);
    spdlog::info(
        "bin {:.0f} x {:.0f} mm (pipe {:.0f} mm long, {:.0f} mm thick lying; pile {:.0f} mm high on "
        "average), {} "
        "sensor, camera {:.0f}-{:.0f} mm above the floor",
        scene.pile.bin.inner_x_mm, scene.pile.bin.inner_y_mm, size.length_mm, size.thickness_mm,
        size.mean_height_mm, opt->sensor, scene.camera_height_min_mm, scene.camera_height_max_mm);
    const auto t0 = std::chrono::steady_clock::now();
    write_simulated_dataset(model, opt->req);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    spdlog::info("simulated {} images of {} pipes into {} in {:.2f} s ({:.0f} ms/image)", opt->req.images,
                 opt->req.scene.pile.pipes, opt->req.out_dir, s, 1e3 * s / opt->req.images);
  });
}

}  // namespace pipeloc::app
