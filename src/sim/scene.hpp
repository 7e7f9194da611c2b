// One simulated frame: a pile in a bin seen by the sensor model, with its ground truth.
#pragma once

#include <random>
#include <vector>

#include "io/bop.hpp"
#include "sim/pile.hpp"
#include "sim/sensor.hpp"

namespace pipeloc {

struct SceneParams {
  PileParams pile;
  SensorModel sensor;
  Intrinsics intrinsics;
  double camera_height_min_mm = 980, camera_height_max_mm = 1080;  // above the bin floor
  double max_tilt_deg = 0;       // camera tilt from vertical, drawn in [0, max]
  double camera_offset_mm = 25;  // camera drawn this far off the bin centre at most
};

struct SimulatedScene {
  CameraInfo camera;                 // world_to_cam always set
  std::vector<Pose> model_to_world;  // one per pipe
  Image<float> depth_mm;             // what the sensor reports (0 = no reading)
  DepthTarget clean;                 // noise-free render: depth, label, normal
  std::vector<GtInfo> info;          // one per pipe

  Pose model_to_cam(std::size_t i) const { return *camera.world_to_cam * model_to_world[i]; }
};

// A camera height_mm above the bin floor, tilted from vertical towards the azimuth, looking down at
// look_at on the floor (world_to_cam); its x axis along the world's x as far as possible.
Pose camera_pose(double height_mm, double tilt_rad, double azimuth_rad, const Eigen::Vector3d& look_at);

// A camera above the bin looking down at its centre (world_to_cam), within params' ranges.
Pose draw_camera(const SceneParams& params, std::mt19937& rng);

// Whether a point in front of the camera (camera frame, mm) falls inside both the camera's image
// and its projector's (or second camera's), which lies sensor.baseline_mm along +x: the sensor
// reads only there, were nothing in front.
bool camera_and_projector_see(const SceneParams& params, const Eigen::Vector3d& p_cam);

// The lowest camera height, at least params' least, from which every camera draw_camera may draw
// (any tilt up to the most, any azimuth, any offset) sees the bin's whole rim, and so all of the
// bin inside it, with its camera and its projector: where an integrator would mount the sensor for
// this bin. (At most 5 m.)
double lowest_camera_seeing_bin(const SceneParams& params);

// Clean renders of bin and pipes from the camera and from the projector beside it (labels:
// pipe i = i, the bin = the number of pipes).
void render_views(const PipeModel& model, const std::vector<Pose>& model_to_world, const Pose& world_to_cam,
                  const SceneParams& params, DepthTarget* camera, DepthTarget* projector);

// Draws a camera and renders the given pile through the sensor model.
SimulatedScene render_scene(const PipeModel& model, std::vector<Pose> model_to_world,
                            const SceneParams& params, std::mt19937& rng);

// A new pile and a frame of it.
SimulatedScene simulate_scene(const PipeModel& model, const SceneParams& params, std::mt19937& rng);

// Visibility figures of DESIGN.md's scoring: silhouettes of each pipe alone vs. the full scene.
std::vector<GtInfo> visibility_info(const PipeModel& model, const SimulatedScene& scene);

}  // namespace pipeloc
