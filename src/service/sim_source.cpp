#include "service/sim_source.hpp"

#include <cstdio>

#include "score/mssd.hpp"
#include "sim/pile.hpp"

namespace pipeloc {
namespace {
// A pick takes the pipe the pose was computed for when it is within the scorer's looser bound.
constexpr double kPickMatchMm = 10.0;
// Surface points a pipe's share in view is counted on (about 2 % apart in the share).
constexpr std::size_t kInViewPoints = 500;

// The camera's height above the bin floor (the world's z of its centre).
double camera_height_mm(const Pose& world_to_cam) { return world_to_cam.inverse().translation().z(); }
}  // namespace

SimSource::SimSource(const PipeModel& model, const SimSourceConfig& cfg)
    : model_(model), cfg_(cfg), rng_(std::uint32_t(cfg.seed)) {
  params_.pile.pipes = cfg.pipes;
  params_.max_tilt_deg = cfg.tilt_deg;
  params_.camera_height_min_mm = cfg.camera_height_min_mm;
  params_.camera_height_max_mm = cfg.camera_height_max_mm;
  params_.sensor = sensor_model(cfg.sensor);
  params_.pile.bin = bin_for_pile(model, params_.pile);
  // A bin grown for a big pile may reach beyond the view: mounted where it sees the whole bin.
  if (cfg.camera_sees_bin) {
    const double raise = lowest_camera_seeing_bin(params_) - params_.camera_height_min_mm;
    params_.camera_height_min_mm += raise, params_.camera_height_max_mm += raise;
  }
  for (std::size_t i = 0; i < model.mesh.vertices.size(); i += 4)
    vertices_.push_back(model.mesh.vertices[i].cast<double>());
  for (const Eigen::Vector3f& p : spread_surface_points(model.surface, kInViewPoints))
    surface_.push_back(p.cast<double>());
  // The tube's axis from every vertex: a subset need not be centred on it.
  std::vector<Eigen::Vector3d> all;
  for (const auto& v : model.mesh.vertices) all.push_back(v.cast<double>());
  pick_symmetries_ = with_tube_turns(all, model.symmetries);
  if (!cfg.truth_file.empty() && !(truth_ = std::fopen(cfg.truth_file.c_str(), "w")))
    throw SourceError("source.sim.truth_file '" + cfg.truth_file + "': cannot write");
  fill_bin();
}

SimSource::~SimSource() {
  if (truth_) std::fclose(truth_);
}

void SimSource::write_truth(std::uint64_t frame) {
  // {"frame": N, "bin": B, "shakes": shakes of this bin so far, "camera_height_mm": H,
  //  "model_to_cam": [[R row-major (9), t mm (3)], ...],
  //  "in_view": [share of each pipe's surface in the sensor's view, ...],
  //  "covered": [share of each pipe's silhouette covered by the others, ...]}; fprintf allocates nothing.
  std::fprintf(truth_,
               "{\"frame\":%llu,\"bin\":%d,\"shakes\":%d,\"camera_height_mm\":%.1f,\"model_to_cam\":[",
               (unsigned long long)frame, bins_, shakes_, camera_height_mm(world_to_cam_));
  for (std::size_t i = 0; i < pile_.size(); ++i) {
    const Pose p = world_to_cam_ * pile_[i];
    std::fprintf(truth_, "%s[", i ? "," : "");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) std::fprintf(truth_, "%.9f,", p.linear()(r, c));
    std::fprintf(truth_, "%.4f,%.4f,%.4f]", p.translation().x(), p.translation().y(), p.translation().z());
  }
  // In view: where the sensor could read it, were nothing in front: in its range, seen by its
  // camera and its projector.
  std::fprintf(truth_, "],\"in_view\":[");
  const SensorModel& sensor = params_.sensor;
  for (std::size_t i = 0; i < pile_.size(); ++i) {
    const Pose p = world_to_cam_ * pile_[i];
    int inside = 0;
    for (const Eigen::Vector3d& v : surface_) {
      const Eigen::Vector3d c = p * v;
      inside += c.z() >= sensor.min_range_mm && c.z() <= sensor.max_range_mm &&
                camera_and_projector_see(params_, c);
    }
    std::fprintf(truth_, "%s%.3f", i ? "," : "",
                 surface_.empty() ? 0.0 : double(inside) / double(surface_.size()));
  }
  std::fprintf(truth_, "],\"covered\":[");
  for (std::size_t i = 0; i < covered_.size(); ++i) std::fprintf(truth_, "%s%.3f", i ? "," : "", covered_[i]);
  std::fprintf(truth_, "]}\n");
  std::fflush(truth_);
}

void SimSource::fill_bin() {
  pile_ = build_pile(model_, params_.pile, rng_);
  world_to_cam_ = draw_camera(params_, rng_);
  ++bins_;
  shakes_ = 0;
  render();
}

void SimSource::found_none() {
  if (cfg_.shake_after_none) shake();
}

void SimSource::shake() {
  if (pile_.empty()) return;
  PileParams left = params_.pile;
  left.pipes = int(pile_.size());
  pile_ = build_pile(model_, left, rng_);
  ++shakes_;
  render();
}

void SimSource::render() {
  SimulatedScene scene;
  DepthTarget projector;
  render_views(model_, pile_, world_to_cam_, params_, &scene.clean, &projector);
  view_ = prepare_sensor_view(scene.clean, projector, params_.intrinsics, params_.sensor);
  if (!truth_) return;
  // Each pipe's share under the others, as the scorer's bound on a right pick counts it (a pipe
  // covered over more than 15 % is no right pick), for the truth file.
  scene.camera.intrinsics = params_.intrinsics;
  scene.camera.world_to_cam = world_to_cam_;
  scene.model_to_world = pile_;
  scene.depth_mm = scene.clean.z_mm;  // read only for the valid pixels' count, not used here
  covered_.clear();
  for (const GtInfo& g : visibility_info(model_, scene)) covered_.push_back(g.occ_by_pipes);
}

GrabStatus SimSource::grab(Clock::time_point, Clock::time_point, Frame* out) {
  // A bin whose last pipes are never handed out would be seen for ever: a new one, if asked.
  if (cfg_.refill && cfg_.refill_after_frames_without_pick > 0 &&
      ++frames_without_pick_ > cfg_.refill_after_frames_without_pick) {
    frames_without_pick_ = 0;
    fill_bin();
  }
  // The simulated sensor exposes now, after the trigger.
  apply_sensor_noise(view_, params_.intrinsics, params_.sensor, int(pile_.size()), rng_, &out->depth_mm);
  // In the sensor's 16-bit units, as a real sensor (and a simulated dataset's PNG) reports it.
  out->camera.depth_scale = 1.0;
  round_to_raw_units(&out->depth_mm, out->camera.depth_scale);
  out->camera.intrinsics = params_.intrinsics;
  out->camera.world_to_cam = world_to_cam_;
  out->captured = Clock::now();
  out->sequence = ++sequence_;
  out->scene_id = bins_;
  out->im_id = int(sequence_);
  if (truth_) write_truth(sequence_);
  return GrabStatus::ok;
}

void SimSource::picked(const Pose& model_to_cam) {
  int best = -1;
  double best_err = kPickMatchMm;
  for (std::size_t i = 0; i < pile_.size(); ++i) {
    const double err = mssd(vertices_, model_to_cam, world_to_cam_ * pile_[i], pick_symmetries_, best_err);
    if (err <= best_err) {
      best_err = err;
      best = int(i);
    }
  }
  if (best < 0) return;  // a pose off every pipe: the gripper closes on nothing
  frames_without_pick_ = 0;
  pile_.erase(pile_.begin() + best);
  if (pile_.empty() && cfg_.refill)
    fill_bin();
  else
    render();
}

std::vector<Pose> SimSource::pipes_in_camera() const {
  std::vector<Pose> out;
  for (const Pose& p : pile_) out.push_back(world_to_cam_ * p);
  return out;
}

std::string SimSource::describe() const {
  char text[512];
  std::snprintf(
      text, sizeof text,
      "sim: %d pipes of %s per bin (%.0f x %.0f mm), seed %d, %s sensor %.0f-%.0f mm above the floor%s, "
      "tilt up to %.1f deg, %dx%d, %s%s",
      cfg_.pipes, model_.source.c_str(), params_.pile.bin.inner_x_mm, params_.pile.bin.inner_y_mm, cfg_.seed,
      cfg_.sensor.c_str(), params_.camera_height_min_mm, params_.camera_height_max_mm,
      params_.camera_height_min_mm > cfg_.camera_height_min_mm ? " (raised to see the whole bin)" : "",
      cfg_.tilt_deg, params_.intrinsics.width, params_.intrinsics.height,
      cfg_.refill ? "refilled when empty" : "not refilled",
      cfg_.shake_after_none ? ", shaken after each DONE_NONE" : "");
  return text;
}

}  // namespace pipeloc
