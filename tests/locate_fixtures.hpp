// Helpers of the localizer's tests: preset models, simulated frames, synthetic Z-buffers.
#pragma once

#include <algorithm>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "locate/locator.hpp"
#include "model/make_pipe.hpp"
#include "score/mssd.hpp"
#include "sim/scene.hpp"

namespace pipeloc {

inline const PipeModel& preset_model(const std::string& name) {
  static std::map<std::string, PipeModel> models;
  auto it = models.find(name);
  if (it == models.end())
    it = models.emplace(name, derive_pipe_model(make_pipe(pipe_preset(name)), name)).first;
  return it->second;
}

// A pipe made along a centreline path ("S40,B90r25,..." as make-pipe takes it) with a tube of d mm.
inline PipeModel pipe_of(const std::string& path, double d, const std::string& name = "") {
  PipeSpec spec;
  spec.diameter_mm = d;
  spec.segments = parse_centreline(path);
  return derive_pipe_model(make_pipe(spec), name.empty() ? path : name);
}

// A 90-degree elbow fitting as a real pipe's STL models it: the outside and, facing in, its bore.
inline Mesh hollow_elbow(double outer_mm, double wall_mm) {
  PipeSpec spec;
  spec.segments = parse_centreline("S20,B90r45,S20");
  spec.diameter_mm = outer_mm;
  Mesh mesh = make_pipe(spec);
  spec.diameter_mm = outer_mm - 2 * wall_mm;
  const Mesh bore = make_pipe(spec);
  const int base = int(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), bore.vertices.begin(), bore.vertices.end());
  for (const auto& t : bore.faces) mesh.faces.push_back({base + t[0], base + t[2], base + t[1]});  // facing in
  return mesh;
}

inline double pose_error(const PipeModel& m, const Pose& a, const Pose& b) {
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.mesh.vertices) v.push_back(p.cast<double>());
  return mssd(v, a, b, m.symmetries, 1e9);
}

// The same, a straight tube's turns about its own axis counted as symmetries (as the scorer does).
inline double pose_error_with_turns(const PipeModel& m, const Pose& a, const Pose& b) {
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.mesh.vertices) v.push_back(p.cast<double>());
  return mssd(v, a, b, with_tube_turns(v, m.symmetries), 1e9);
}

// The least pose_error of `pose` against the pipes of a simulated scene.
inline double nearest_pipe_error(const PipeModel& m, const Pose& pose, const SimulatedScene& s) {
  double best = 1e9;
  for (std::size_t g = 0; g < s.model_to_world.size(); ++g) best = std::min(best, pose_error(m, pose, s.model_to_cam(g)));
  return best;
}

// How well a localizer places a scene's top pipes: how many there are, how many an estimate lies
// within 5 mm of, and the error summed over those within 10 mm (pose_error_with_turns).
struct TopPipesPlaced {
  int top = 0, within_5 = 0, within_10 = 0;
  double error_sum = 0;
  double mean_error() const { return error_sum / std::max(1, within_10); }
};

inline void place_top_pipes(const PipeModel& model, const SimulatedScene& s, const LocateConfig& cfg,
                            TopPipesPlaced* placed) {
  Locator loc(model, cfg, s.camera.intrinsics);
  const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
  for (std::size_t g = 0; g < s.model_to_world.size(); ++g) {
    if (!s.info[g].top) continue;
    ++placed->top;
    double best = 1e9;
    for (const PipeEstimate& e : out.estimates)
      best = std::min(best, pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(g)));
    placed->within_5 += best < 5;
    if (best < 10) placed->error_sum += best, ++placed->within_10;
  }
}

// Fills a Z-buffer with z = f(x, y) on a 1 mm grid.
template <typename F>
ZBuffer synthetic_zbuffer(int size, F f) {
  ZBuffer zb;
  reserve_zbuffer(&zb, size, 1.0);
  zb.width = zb.height = size;
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) zb.z.at(i, j) = f(double(i), double(j));
  return zb;
}

// A frame of one pipe lying alone in the bin, with the sensor model's noise.
struct OnePipe {
  SimulatedScene scene;
  LocateConfig cfg;
};

inline OnePipe one_pipe(const std::string& preset, unsigned seed) {
  std::mt19937 rng(seed);
  SceneParams p;
  p.pile.pipes = 1;
  return {simulate_scene(preset_model(preset), p, rng), LocateConfig{}};
}

inline SimulatedScene pile_of(const PipeModel& model, int pipes, unsigned seed) {
  std::mt19937 rng(seed);
  SceneParams p;
  p.pile.pipes = pipes;
  return simulate_scene(model, p, rng);
}

// A thin short elbow (8.4 mm tube, 25 mm long, as 04-elbow of the zoo) ...
inline PipeModel thin_elbow() { return pipe_of("S6.8,B-45r16.4,S3.3", 8.4, "thin elbow"); }

// ... and a pile of 25 of them under the stereo sensor 0.63-0.73 m up, tilted up to 10 degrees.
inline SimulatedScene thin_elbow_pile(const PipeModel& model, unsigned seed) {
  std::mt19937 rng(seed);
  SceneParams p;
  p.pile.pipes = 25;
  p.camera_height_min_mm = 630, p.camera_height_max_mm = 730;
  p.max_tilt_deg = 10;
  p.sensor = sensor_model("stereo");
  return simulate_scene(model, p, rng);
}

// `pipes` of them under the stereo sensor looking straight down from min_mm-max_mm above the floor.
inline SimulatedScene pipes_below_stereo(const PipeModel& model, int pipes, double min_mm, double max_mm,
                                         std::mt19937& rng) {
  SceneParams p;
  p.pile.pipes = pipes;
  p.camera_height_min_mm = min_mm, p.camera_height_max_mm = max_mm;
  p.max_tilt_deg = 0;
  p.sensor = sensor_model("stereo");
  return simulate_scene(model, p, rng);
}

// A straight model lying with its long axis along the world direction yaw_deg (0: X), its middle
// over (x, y) and its axis axis_z_mm above the floor.
inline Pose lying_straight(const PipeModel& model, double yaw_deg, double x, double y, double axis_z_mm) {
  const Eigen::Matrix3d axes = principal_axes(model.surface.points, model.centroid);
  Eigen::Matrix3d along_x;  // the model's long axis along world X
  along_x.row(0) = axes.col(2).transpose();
  along_x.row(1) = axes.col(1).transpose();
  along_x.row(2) = along_x.row(0).cross(along_x.row(1));
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix() * along_x;
  p.translation() = Eigen::Vector3d(x, y, axis_z_mm) - p.linear() * model.centroid.cast<double>();
  return p;
}

// Pipes at the given poses, seen through the sensor model; the camera and the noise drawn from seed.
inline SimulatedScene scene_of(const PipeModel& model, const std::vector<Pose>& poses, unsigned seed) {
  std::mt19937 rng(seed);
  return render_scene(model, poses, SceneParams{}, rng);
}

}  // namespace pipeloc
