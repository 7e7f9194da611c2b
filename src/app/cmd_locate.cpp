#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>

#include "app/commands.hpp"
#include "config/config_file.hpp"
#include "io/bop.hpp"
#include "io/results_csv.hpp"
#include "locate/locator.hpp"
#include "locate/speckles.hpp"
#include "model/pipe_model.hpp"
#include "report/locate_overlay.hpp"
#include "service/frame_source.hpp"

namespace pipeloc::app {
namespace {

AppConfig config_or_default(const std::string& path) {
  if (path.empty()) return AppConfig{};
  const AppConfig cfg = load_config(path);
  for (const auto& line : describe_config(cfg)) spdlog::info("config: {}", line);
  return cfg;
}

// What the depth image said of a pose (an estimate's, or a candidate's best refined fit).
Json verification_json(const Verification& v) {
  return {{"agreement", v.agreement()},
          {"free_space", v.free_space()},
          {"inner_free_space", v.inner_free_space()},
          {"occluded", v.occluded()},
          {"unread", v.unread()},
          {"outside_view", v.outside_view},
          {"seen_through_patch", v.seen_through_patch},
          {"side_level", v.side_level()},
          {"side_px", v.side_px},
          {"ends_pinned", v.ends_pinned},
          {"ends_continued", v.ends_continued},
          {"ends_seen_ending", v.ends_seen_ending},
          {"ends_out_of_view", v.ends_out_of_view}};
}

// The names of the bits set of the first `kinds` (Withheld's or Ambiguity's), in their order.
Json bit_names(unsigned bits, int kinds, const char* (*name)(int)) {
  Json names = Json::array();
  for (int k = 0; k < kinds; ++k)
    if (bits & (1u << k)) names.push_back(name(k));
  return names;
}

Json estimate_json(const PipeEstimate& e, int rank, bool pick) {
  Json j = {{"rank", rank},
            {"pick", pick},
            {"score", e.score},
            {"R", rotation_rowmajor(e.model_to_cam)},
            {"t_mm", translation_mm(e.model_to_cam)},
            {"pickable", e.pickable},
            {"ambiguous", e.ambiguous()},
            {"ridge_residual_mm", e.ridge_cost_mm},
            {"ridge_points", e.ridge_points},
            {"refine_inliers", e.refine_inliers},
            {"refine_points", e.refine_points},
            {"refine_rms_mm", e.refine_rms_mm},
            {"model_px", e.check.model_px},
            {"relief_sigmas", e.relief_sigmas},
            {"unresolved", e.unresolved}};
  j["withheld"] = bit_names(e.withheld, kWithheldKinds, withheld_name);  // empty where it is pickable
  j["ambiguous_why"] = bit_names(e.ambiguous_why, kAmbiguityKinds, ambiguity_name);  // empty where not
  j.update(verification_json(e.check));
  return j;
}

}  // namespace

void add_locate(CLI::App& app) {
  struct Options {
    std::string depth, camera, model, overlay, config;
    int im_id = -1;
    bool traces = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("locate", "Localize the top pipes in one depth image; one JSON line per pipe");
  cmd->add_option("--depth", opt->depth, "16-bit depth PNG")->required();
  cmd->add_option("--camera", opt->camera, "scene_camera.json (BOP) holding this image's camera")->required();
  cmd->add_option("--im-id", opt->im_id,
                  "image id in the camera file (default: the file's only or first entry)");
  cmd->add_option("--model", opt->model, "pipe STL (mm); default: [model] stl of the config");
  cmd->add_option("--overlay", opt->overlay, "write the overlay PNG here");
  cmd->add_option("--config", opt->config, "TOML config ([locate] thresholds)");
  cmd->add_flag("--traces", opt->traces,
                "also print one JSON line per candidate region: its outcome and the poses it reached");
  cmd->callback([opt] {
    const AppConfig app_cfg = config_or_default(opt->config);
    const LocateConfig& cfg = app_cfg.locate;
    const std::string model_file = opt->model.empty() ? app_cfg.model_path : opt->model;
    if (model_file.empty()) throw ModelError("locate: no model: give --model or [model] stl in the config");
    const auto cameras = read_scene_camera(opt->camera);
    if (cameras.empty()) throw IoError("'" + opt->camera + "': holds no camera");
    const auto it = opt->im_id < 0 ? cameras.begin() : cameras.find(opt->im_id);
    if (it == cameras.end())
      throw IoError("'" + opt->camera + "': no entry for image " + std::to_string(opt->im_id));
    CameraInfo sized = it->second;
    const Image<float> depth = read_depth_for_camera(opt->depth, opt->camera, it->first, &sized);
    // The frame checks of the service's cycle (where such a frame gets ERROR 2): said, not an
    // empty result that looks like a bin without pipes.
    if (const char* why = "";
        check_frame(depth, sized.intrinsics, kMinValidDepthShare, &why) != GrabStatus::ok)
      throw IoError("depth '" + opt->depth + "': not a frame to localize in: " + why + " (" +
                    std::to_string(valid_depth_pixels(depth)) + " of " + std::to_string(depth.pixels.size()) +
                    " pixels have a depth; the service answers such a frame with ERROR 2)");
    const PipeModel model = load_pipe_model(model_file);
    spdlog::info("model: {}", describe_near_symmetries(model));
    if (const std::string twin =
            describe_twin_resolution(model, sized.intrinsics.fx, cfg.twin_beyond_resolution_ambiguous);
        !twin.empty())
      spdlog::info("model: {}", twin);
    Locator locator(model, cfg, sized.intrinsics);
    const LocateOutput& out = locator.locate(depth, sized);
    const int pick = out.pick();
    for (std::size_t i = 0; i < out.estimates.size(); ++i)
      std::cout << estimate_json(out.estimates[i], int(i), int(i) == pick).dump() << '\n';
    if (opt->traces) {
      const Pose bin_to_cam = bin_to_camera(sized);
      for (std::size_t c = 0; c < out.traces.size(); ++c) {
        const CandidateTrace& tr = out.traces[c];
        const Pose ridge_to_cam = bin_to_cam * tr.ridge_pose;
        Json j = {{"candidate", c},
                  {"outcome", outcome_name(tr.outcome)},
                  {"searched_again", tr.searched_again},
                  {"region_centre_mm",
                   translation_mm(bin_to_cam * Pose(Eigen::Translation3d(tr.axis.centre.cast<double>())))},
                  {"ridge_points", tr.ridge_count},
                  {"ridge_residual_mm", tr.ridge_cost_mm},
                  {"ridge_R", rotation_rowmajor(ridge_to_cam)},
                  {"ridge_t_mm", translation_mm(ridge_to_cam)},
                  {"refined_R", rotation_rowmajor(tr.refined_to_cam)},
                  {"refined_t_mm", translation_mm(tr.refined_to_cam)}};
        j.update(verification_json(tr.check));
        // Every pose the candidate reached (camera frame), to trace a miss to the stage that lost it.
        const auto reached_json = [&](const auto& poses, int n, const char* value) {
          Json a = Json::array();
          for (int k = 0; k < n; ++k) {
            const Pose to_cam = bin_to_cam * poses[std::size_t(k)].model_to_bin;
            a.push_back({{"R", rotation_rowmajor(to_cam)},
                         {"t_mm", translation_mm(to_cam)},
                         {value, poses[std::size_t(k)].value}});
          }
          return a;
        };
        j["ridge_fits"] = reached_json(tr.reached.fits, tr.reached.n_fits, "residual_mm");
        j["hypotheses"] = reached_json(tr.reached.hypotheses, tr.reached.n_hypotheses, "agreement");
        j["poses_left_out"] = tr.reached.left_out;
        std::cout << j.dump() << '\n';
      }
    }
    spdlog::info(
        "{} pipes found ({} candidate regions ({} of pieces joined across gaps, {} shorter than a * L "
        "tried last, {} grown again to the equator after leaking, {} left over by a pose), {} cores "
        "({} split off touching pipes, {} standing on the floor, {} too long kept whole), {} of them "
        "in a larger one's region ({} tried last), {} grown mostly into earlier regions; {} too short, "
        "{} not convex, {} leaked) in {:.1f} ms; pick: {}",
        out.estimates.size(), out.regions.candidates, out.regions.joined, out.regions.short_candidates,
        out.regions.regrown_after_leak, out.regions.leftover, out.regions.cores_kept, out.regions.split_cores,
        out.regions.raised_cores, out.regions.whole_long_cores, out.regions.claimed,
        out.regions.retried_claimed, out.regions.overlapping, out.regions.short_regions,
        out.regions.not_convex, out.regions.leaked, out.times.total_ms,
        pick >= 0 ? "rank " + std::to_string(pick) : std::string("none"));
    const StageTimes& st = out.times;
    if (out.noise.samples > 0)
      spdlog::info("depth noise {:.2f} mm (1 sigma, measured) at a median depth of {:.0f} mm",
                   out.noise.sigma_mm, out.noise.depth_mm);
    if (locator.config().remove_speckles)
      spdlog::info("speckles left out: {} readings beyond every reading within {} px by more than {:.1f} mm",
                   out.speckles, kSpeckleReachPx, locator.config().continuity_step_max_mm);
    spdlog::info("the sensor's view: columns {}-{}, rows {}-{} (beyond, it reads nothing: out of the view)",
                 out.view.x0, out.view.x1, out.view.y0, out.view.y1);
    spdlog::info(
        "thresholds in effect: continuity step {:.1f} mm, verify tolerance {:.1f} mm, refine inliers "
        "{:.1f} mm, normal window {:.1f} mm, hole fill {:.1f} mm",
        locator.config().continuity_step_max_mm, locator.config().verify_tolerance_mm,
        locator.config().refine_inlier_mm, locator.config().normal_window_mm, locator.config().hole_fill_mm);
    spdlog::info(
        "stages ms: zbuffer {:.1f} normals {:.1f} regions {:.1f} axis {:.1f} ridge_icp {:.1f} refine {:.1f} "
        "verify {:.1f}",
        st.zbuffer_ms, st.normals_ms, st.regions_ms, st.axis_ms, st.ridge_icp_ms, st.refine_ms, st.verify_ms);
    for (std::size_t c = 0; c < out.traces.size(); ++c) {
      const CandidateTrace& tr = out.traces[c];
      spdlog::info(
          "candidate {}: {} (ridge points {}, ridge residual {:.2f} mm, axis sections {}, agreement {:.2f}, "
          "free space {:.2f} (inside the rim band {:.2f}), occluded {:.2f}, not read {:.2f}, sides level {:.2f})",
          c, outcome_name(tr.outcome), tr.ridge_count, tr.ridge_cost_mm, tr.axis.best_count,
          tr.check.agreement(), tr.check.free_space(), tr.check.inner_free_space(), tr.check.occluded(),
          tr.check.unread(), tr.check.side_level());
    }
    if (!opt->overlay.empty()) {
      write_rgb_png(opt->overlay, draw_locate_overlay(locator, depth, sized));
      spdlog::info("overlay written to {}", opt->overlay);
    }
  });
}

void add_eval_bop(CLI::App& app) {
  struct Options {
    std::string dataset, out, config, match = "zridge", search = "default", overlays, picks;
    double budget_ms = 0;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("eval-bop", "Run every target of a BOP dataset and write BOP results CSV");
  cmd->add_option("--dataset", opt->dataset, "BOP dataset directory")->required();
  cmd->add_option("--out", opt->out, "results CSV to write")->required();
  cmd->add_option("--config", opt->config, "TOML config ([locate] thresholds)");
  cmd->add_option("--match", opt->match, "zridge (the paper) or surface (whole visible surface)")
      ->check(CLI::IsMember({"zridge", "surface"}));
  cmd->add_option(
         "--search", opt->search,
         "default (beyond the paper) or paper (IV-B's 12 starts at the measured centre, no yaw turns, "
         "no sliding)")
      ->check(CLI::IsMember({"default", "paper"}));
  cmd->add_option("--overlays", opt->overlays, "also write an overlay PNG per image into this directory");
  cmd->add_option("--picks", opt->picks,
                  "also write the pose the service would hand out per image (the first pickable; no row = "
                  "DONE_NONE), BOP results CSV");
  cmd->add_option("--budget-ms", opt->budget_ms,
                  "localize each image under this budget (ms), as the service's cycle does (0 = none)")
      ->check(CLI::Range(0.0, 60000.0));
  cmd->callback([opt] {
    LocateConfig cfg = config_or_default(opt->config).locate;
    cfg.match_surface = opt->match == "surface";
    if (opt->search == "paper") use_paper_search(&cfg);
    const auto targets = read_targets(opt->dataset + "/test_targets_bop19.json");
    if (!opt->overlays.empty()) {  // the integrator names a folder; it need not exist yet
      std::error_code ec;
      std::filesystem::create_directories(opt->overlays, ec);
      if (ec) throw IoError("cannot create the overlay folder '" + opt->overlays + "': " + ec.message());
    }
    std::map<int, std::unique_ptr<PipeModel>> models;
    std::map<int, std::unique_ptr<Locator>> locators;
    std::map<int, std::map<int, CameraInfo>> cameras;
    std::ofstream csv(opt->out);
    if (!csv) throw IoError("cannot write '" + opt->out + "'");
    write_results_header(csv);
    std::ofstream picks_csv;
    if (!opt->picks.empty()) {
      picks_csv.open(opt->picks);
      if (!picks_csv) throw IoError("cannot write '" + opt->picks + "'");
      write_results_header(picks_csv);
    }
    int images = 0, rows = 0, picked = 0, refused = 0;
    double total_ms = 0;
    for (const auto& t : targets) {
      const TargetFrame frame = read_target_frame(opt->dataset, t, &cameras);
      const Image<float>& depth = frame.depth_mm;
      const CameraInfo& cam = frame.camera;
      if (const char* why = "";
          check_frame(depth, cam.intrinsics, kMinValidDepthShare, &why) != GrabStatus::ok) {
        spdlog::warn(
            "scene {} image {}: not a frame to localize in: {} ({} of {} pixels have a depth): no rows",
            t.scene_id, t.im_id, why, valid_depth_pixels(depth), depth.pixels.size());
        ++refused;
        continue;
      }
      if (!locators.count(t.obj_id)) {
        models[t.obj_id] = std::make_unique<PipeModel>(load_pipe_model(model_path(opt->dataset, t.obj_id)));
        locators[t.obj_id] = std::make_unique<Locator>(*models[t.obj_id], cfg, cam.intrinsics);
      }
      Locator& locator = *locators[t.obj_id];
      // The service's deadline starts at the trigger; here, when the frame is in memory.
      const Clock::time_point deadline =
          opt->budget_ms > 0 ? Clock::now() + ms_duration(opt->budget_ms) : Clock::time_point::max();
      const LocateOutput& out = locator.locate(depth, cam, deadline);
      for (const auto& e : out.estimates) {
        write_result_row(
            csv, {t.scene_id, t.im_id, t.obj_id, e.score, e.model_to_cam, out.times.total_ms / 1000.0});
        ++rows;
      }
      if (const int pick = out.pick(); pick >= 0 && picks_csv.is_open()) {
        const PipeEstimate& e = out.estimates[std::size_t(pick)];
        write_result_row(
            picks_csv, {t.scene_id, t.im_id, t.obj_id, e.score, e.model_to_cam, out.times.total_ms / 1000.0});
        ++picked;
      }
      ++images;
      total_ms += out.times.total_ms;
      if (!opt->overlays.empty()) {
        char name[64];
        std::snprintf(name, sizeof name, "/%06d_%06d_obj%d.png", t.scene_id, t.im_id, t.obj_id);
        write_rgb_png(opt->overlays + name, draw_locate_overlay(locator, depth, cam));
      }
      spdlog::debug("scene {} image {}: {} estimates in {:.1f} ms", t.scene_id, t.im_id, out.estimates.size(),
                    out.times.total_ms);
    }
    spdlog::info("{} images, {} result rows, mean {:.1f} ms per image -> {}", images, rows,
                 images ? total_ms / images : 0.0, opt->out);
    if (picks_csv.is_open())
      spdlog::info("{} of {} images hand out a pick -> {}", picked, images, opt->picks);
    if (refused) spdlog::warn("{} images refused (no usable depth): no rows for them", refused);
  });
}

}  // namespace pipeloc::app
