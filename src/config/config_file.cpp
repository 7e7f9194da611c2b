#include "config/config_file.hpp"

#include <arpa/inet.h>
#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

namespace pipeloc {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& key, const std::string& what) {
  throw ConfigError("config '" + path + "': " + key + ": " + what);
}

// One [section] of the file: each read takes its key (or keeps the default), checks type and
// range, and records the value in effect; finish() rejects keys nobody asked for.
class Section {
 public:
  Section(const std::string& file, std::string name, const toml::table* table,
          std::vector<std::string>* effective)
      : file_(file), name_(std::move(name)), table_(table), effective_(effective) {}

  void real(const char* key, double* dst, double lo, double hi, const char* unit) {
    if (const toml::node* n = take(key)) {
      const auto v = n->value<double>();
      if (!v || !n->is_number() || !(*v >= lo && *v <= hi))
        fail(file_, full(key), range("a number", lo, hi, unit));
      *dst = *v;
    }
    record(key, *dst, unit);
  }
  void integer(const char* key, int* dst, int lo, int hi, const char* unit) {
    if (const toml::node* n = take(key)) {
      const auto v = n->value_exact<std::int64_t>();
      if (!v || *v < lo || *v > hi) fail(file_, full(key), range("an integer", lo, hi, unit));
      *dst = int(*v);
    }
    record(key, *dst, unit);
  }
  void boolean(const char* key, bool* dst) {
    if (const toml::node* n = take(key)) {
      const auto v = n->value_exact<bool>();
      if (!v) fail(file_, full(key), "expected true or false");
      *dst = *v;
    }
    record(key, *dst ? "true" : "false", "");
  }
  // choices empty: any string (allow_empty says whether "" is fine).
  void text(const char* key, std::string* dst, std::initializer_list<const char*> choices = {},
            bool allow_empty = true) {
    if (const toml::node* n = take(key)) {
      const auto v = n->value_exact<std::string>();
      std::string expected = "expected a string";
      if (choices.size()) {
        expected = "expected one of";
        for (const char* c : choices) expected += std::string(" \"") + c + "\"";
      }
      if (!v) fail(file_, full(key), expected);
      bool ok = choices.size() == 0 && (allow_empty || !v->empty());
      for (const char* c : choices) ok = ok || *v == c;
      if (!ok)
        fail(file_, full(key), expected + (v->empty() ? " (got an empty string)" : ", got \"" + *v + "\""));
      *dst = *v;
    }
    record(key, "\"" + *dst + "\"", "");
  }
  // A fixed count of numbers; `optional` allows the key to be absent (dst stays empty).
  void numbers(const char* key, std::vector<double>* dst, std::size_t count, const char* unit) {
    if (const toml::node* n = take(key)) {
      const toml::array* a = n->as_array();
      const std::string expected =
          "expected an array of " + std::to_string(count) + " numbers (" + unit + ")";
      if (!a || a->size() != count) fail(file_, full(key), expected);
      dst->clear();
      for (const toml::node& e : *a) {
        const auto v = e.value<double>();
        if (!v || !e.is_number() || !std::isfinite(*v)) fail(file_, full(key), expected);
        dst->push_back(*v);
      }
    }
    std::ostringstream s;
    s << "[";
    for (std::size_t i = 0; i < dst->size(); ++i) s << (i ? ", " : "") << (*dst)[i];
    s << "]";
    record(key, s.str(), unit);
  }
  // A list of strings, each checked by `valid` (which says what was expected when it is not).
  void texts(const char* key, std::vector<std::string>* dst, bool (*valid)(const std::string&),
             const char* expected) {
    if (const toml::node* n = take(key)) {
      const toml::array* a = n->as_array();
      if (!a) fail(file_, full(key), std::string("expected an array of ") + expected);
      dst->clear();
      for (const toml::node& e : *a) {
        const auto v = e.value_exact<std::string>();
        if (!v || !valid(*v))
          fail(file_, full(key),
               std::string("expected an array of ") + expected +
                   (v ? ", got \"" + *v + "\"" : std::string(", got a non-string")));
        dst->push_back(*v);
      }
    }
    std::string s = "[";
    for (std::size_t i = 0; i < dst->size(); ++i) s += (i ? ", \"" : "\"") + (*dst)[i] + "\"";
    record(key, s + "]", "");
  }
  void triple(const char* key, std::array<double, 3>* dst, const char* unit) {
    std::vector<double> v(dst->begin(), dst->end());
    numbers(key, &v, 3, unit);
    std::copy(v.begin(), v.end(), dst->begin());
  }
  // Rejects keys nobody asked for, and sub-tables other than `subsections` (read by their own
  // Section): a misspelt [locate.extra] is as wrong as a misspelt key.
  void finish(std::initializer_list<const char*> subsections = {}) const {
    if (!table_) return;
    for (const auto& [key, node] : *table_) {
      const std::string k(key.str());
      if (node.is_table()) {
        bool known = false;
        for (const char* sub : subsections) known = known || k == sub;
        if (!known) fail(file_, full(k.c_str()), unknown_section(subsections));
      } else if (!taken_.count(k)) {
        fail(file_, full(k.c_str()), "unknown key");
      }
    }
  }
  // The key was written in the file (not left at its default).
  bool given(const char* key) const { return table_ && table_->contains(key); }
  const std::string& file() const { return file_; }
  std::string full(const char* key) const { return name_ + "." + key; }

 private:
  const toml::node* take(const char* key) {
    taken_.insert(key);
    return table_ ? table_->get(key) : nullptr;
  }
  std::string unknown_section(std::initializer_list<const char*> subsections) const {
    if (subsections.size() == 0) return "unknown section ([" + name_ + "] has no sub-sections)";
    std::string expected;
    for (const char* sub : subsections) expected += std::string(expected.empty() ? "" : " or ") + sub;
    return "unknown section (expected " + expected + ")";
  }
  static std::string range(const char* what, double lo, double hi, const char* unit) {
    std::ostringstream s;
    s << "expected " << what << " in [" << lo << ", " << hi << "] " << unit;
    return s.str();
  }
  template <typename T>
  void record(const char* key, const T& value, const char* unit) {
    std::ostringstream s;
    s << full(key) << " = " << value;
    if (*unit) s << "  # " << unit;
    effective_->push_back(s.str());
  }

  std::string file_, name_;
  const toml::table* table_;
  std::vector<std::string>* effective_;
  std::set<std::string> taken_;
};

// [locate] roi_min_mm / roi_max_mm: the bin interior in the bin frame (calibrate-bin prints it);
// both or neither, min below max on each axis.
void read_roi(Section& s, RegionOfInterest* roi) {
  std::vector<double> lo, hi;
  if (roi->on()) lo = {roi->min_x_mm, roi->min_y_mm}, hi = {roi->max_x_mm, roi->max_y_mm};
  s.numbers("roi_min_mm", &lo, 2, "x y, mm, bin frame");
  s.numbers("roi_max_mm", &hi, 2, "x y, mm, bin frame");
  if (lo.empty() != hi.empty())
    fail(s.file(), lo.empty() ? "locate.roi_min_mm" : "locate.roi_max_mm",
         "missing: give roi_min_mm and roi_max_mm together (pipeloc calibrate-bin prints both)");
  if (lo.empty()) return;
  for (int i = 0; i < 2; ++i) {
    if (std::abs(lo[i]) > 5000 || std::abs(hi[i]) > 5000)
      fail(s.file(), "locate.roi_min_mm", "expected values within +-5000 mm");
    if (!(lo[i] < hi[i]))
      fail(s.file(), "locate.roi_min_mm",
           std::string("its ") + (i ? "y" : "x") +
               " must be below roi_max_mm's (the bin interior, min corner first)");
  }
  *roi = {lo[0], lo[1], hi[0], hi[1]};
}

void read_locate(Section& s, LocateConfig* c) {
  s.boolean("raise_to_noise", &c->raise_to_noise);
  s.boolean("remove_speckles", &c->remove_speckles);
  s.real("zbuffer_pixel_mm", &c->zbuffer_pixel_mm, 0.25, 10, "mm");
  s.real("zbuffer_max_side_mm", &c->zbuffer_max_side_mm, 100, 5000, "mm");
  s.real("hole_fill_mm", &c->hole_fill_mm, 0, 50, "mm (0: derived)");
  s.real("normal_window_mm", &c->normal_window_mm, 0, 50, "mm (0: derived)");
  s.real("normal_min_valid_share", &c->normal_min_valid_share, 0.05, 1, "share");
  s.real("upward_normal_max_deg", &c->upward_normal_max_deg, 1, 89, "deg");
  s.real("continuity_max_deg", &c->continuity_max_deg, 1, 89, "deg");
  s.real("continuity_step_max_mm", &c->continuity_step_max_mm, 0, 100, "mm (0: derived)");
  s.real("core_min_area_of_d2", &c->core_min_area_of_d2, 0, 100, "x D^2");
  s.real("core_max_extent_of_l", &c->core_max_extent_of_l, 0.1, 10, "x L");
  s.real("core_valley_turn", &c->core_valley_turn, 0, 2, "difference of unit-normal components");
  s.real("core_split_max_area_of_ld", &c->core_split_max_area_of_ld, 0, 1000, "x L x D");
  s.real("core_whole_max_extent_of_l", &c->core_whole_max_extent_of_l, 0, 10, "x L");
  s.real("region_min_extent_of_l", &c->region_min_extent_of_l, 0, 2, "x L");
  s.real("short_region_min_extent_of_l", &c->short_region_min_extent_of_l, 0, 2, "x L");
  s.integer("max_short_candidates", &c->max_short_candidates, 0, 256, "regions");
  s.real("convexity_min_share", &c->convexity_min_share, 0, 1, "share");
  s.real("region_max_drop_of_d", &c->region_max_drop_of_d, 0.1, 5, "x D");
  s.real("region_max_reach_of_d", &c->region_max_reach_of_d, 0.1, 100, "x D");
  s.real("region_join_gap_of_d", &c->region_join_gap_of_d, 0, 20, "x D (0: off)");
  s.real("hole_bridge_of_d", &c->hole_bridge_of_d, 0, 10, "x D (0: off)");
  s.real("region_max_claimed_share", &c->region_max_claimed_share, 0, 1, "share");
  s.boolean("retry_claimed_cores", &c->retry_claimed_cores);
  s.boolean("leftover_regions", &c->leftover_regions);
  s.real("section_width_min_of_d", &c->section_width_min_of_d, 0.1, 2, "x D");
  s.real("section_width_max_of_d", &c->section_width_max_of_d, 0.1, 3, "x D");
  s.real("scan_step_deg", &c->scan_step_deg, 0.5, 45, "deg");
  s.real("ridge_cell_mm", &c->ridge_cell_mm, 0.5, 10, "mm");
  s.integer("initial_rotations", &c->initial_rotations, 1, 12, "states per direction");
  s.real("initial_yaw_step_deg", &c->initial_yaw_step_deg, 1, 180, "deg");
  s.real("start_slide_step_of_d", &c->start_slide_step_of_d, 0.1, 10, "x D");
  s.boolean("slide_starts", &c->slide_starts);
  s.real("edge_slide_along_of_l", &c->edge_slide_along_of_l, 0, 2, "x L");
  s.integer("icp_max_iterations", &c->icp_max_iterations, 1, 500, "iterations");
  s.integer("icp_probed_states", &c->icp_probed_states, 1, 10000, "states");
  s.integer("icp_probe_iterations", &c->icp_probe_iterations, 1, 500, "iterations");
  s.real("icp_probe_cell_mm", &c->icp_probe_cell_mm, 0.5, 20, "mm");
  s.integer("icp_continued_states", &c->icp_continued_states, 1, 48, "states");
  s.integer("icp_continued_states_sliding", &c->icp_continued_states_sliding, 1, 48, "states");
  s.integer("icp_fine_iterations", &c->icp_fine_iterations, 1, 500, "iterations");
  s.real("icp_converged_mm", &c->icp_converged_mm, 0.001, 10, "mm");
  s.real("residual_max_of_d", &c->residual_max_of_d, 0.01, 5, "x D");
  s.real("residual_rescue_of_rth", &c->residual_rescue_of_rth, 1, 10, "x R_th (1: off)");
  s.real("retry_surface_cell_of_d", &c->retry_surface_cell_of_d, 0, 2, "x D (0: off)");
  s.boolean("second_search_may_pick", &c->second_search_may_pick);
  s.integer("refine_iterations", &c->refine_iterations, 0, 200, "iterations");
  s.real("refine_inlier_mm", &c->refine_inlier_mm, 0, 50, "mm (0: derived)");
  s.integer("refine_max_points", &c->refine_max_points, 50, 100000, "points");
  s.boolean("refine_on_explained", &c->refine_on_explained);
  s.boolean("twins_refined_on_region", &c->twins_refined_on_region);
  s.boolean("polish_best", &c->polish_best);
  s.boolean("refine_facing_only", &c->refine_facing_only);
  s.boolean("refine_ray_pairs", &c->refine_ray_pairs);
  s.real("verify_tolerance_mm", &c->verify_tolerance_mm, 0, 100, "mm (0: derived)");
  s.real("verify_min_agreement", &c->verify_min_agreement, 0, 1, "share");
  s.real("verify_min_read_share", &c->verify_min_read_share, 0, 1, "share");
  s.real("verify_max_free_space", &c->verify_max_free_space, 0, 1, "share");
  s.real("free_space_band_of_d", &c->free_space_band_of_d, 0, 2, "x D");
  s.real("verify_max_occluded", &c->verify_max_occluded, 0, 1, "share");
  s.real("verify_max_outside_view", &c->verify_max_outside_view, 0, 1, "share");
  s.real("verify_max_outside_view_well_seen", &c->verify_max_outside_view_well_seen, 0, 1, "share");
  s.real("verify_max_outside_view_ends_seen", &c->verify_max_outside_view_ends_seen, 0, 1, "share");
  s.real("verify_well_seen_agreement", &c->verify_well_seen_agreement, 0, 1, "share");
  s.real("side_drop_of_d", &c->side_drop_of_d, 0, 5, "x D");
  s.real("verify_max_side_level", &c->verify_max_side_level, 0, 1, "share (1: off)");
  s.real("pick_min_relief_sigmas", &c->pick_min_relief_sigmas, 0, 100, "sigmas of the noise (0: off)");
  s.real("pick_min_relief_sigmas_bent", &c->pick_min_relief_sigmas_bent, 0, 100, "sigmas of the noise");
  s.real("ambiguity_pose_mm", &c->ambiguity_pose_mm, 0, 1000, "mm");
  s.real("ambiguity_quality_margin", &c->ambiguity_quality_margin, 0, 1, "share");
  s.boolean("tell_rivals_apart", &c->tell_rivals_apart);
  s.integer("verify_hypotheses", &c->verify_hypotheses, 1, 24, "fits per region");
  s.boolean("judge_rolls", &c->judge_rolls);
  s.real("roll_ambiguity_mm", &c->roll_ambiguity_mm, 0, 1000, "mm");
  s.boolean("tell_rolls_apart", &c->tell_rolls_apart);
  s.boolean("judge_other_parts", &c->judge_other_parts);
  s.boolean("rivals_judged_where_seen", &c->rivals_judged_where_seen);
  s.boolean("twin_beyond_resolution_ambiguous", &c->twin_beyond_resolution_ambiguous);
  s.boolean("rivals_across_regions", &c->rivals_across_regions);
  s.boolean("judge_slides", &c->judge_slides);
  s.boolean("pin_slides_by_ends", &c->pin_slides_by_ends);
  s.boolean("ends_read_further", &c->ends_read_further);
  s.boolean("ends_read_slanted", &c->ends_read_slanted);
  s.boolean("ends_probed_past_itself", &c->ends_probed_past_itself);
  s.boolean("slides_placed_first", &c->slides_placed_first);
  s.boolean("place_slides_finely", &c->place_slides_finely);
  s.boolean("follow_slides_to_ends", &c->follow_slides_to_ends);
  s.boolean("pin_part_in_view_by_ends", &c->pin_part_in_view_by_ends);
  s.boolean("end_unread_as_out_of_view", &c->end_unread_as_out_of_view);
  s.boolean("end_shown_where_both_in_view", &c->end_shown_where_both_in_view);
  s.integer("max_candidates", &c->max_candidates, 1, 256, "regions");
  s.integer("max_results", &c->max_results, 0, 256, "poses (0: every pose found)");
  s.integer("threads", &c->threads, 1, 64, "threads");
  std::string search = "default";
  s.text("search", &search, {"default", "paper"});
  read_roi(s, &c->roi);
  s.finish();
  if (c->section_width_min_of_d >= c->section_width_max_of_d)
    fail(s.file(), "locate.section_width_min_of_d", "must be below locate.section_width_max_of_d");
  if (search == "paper") use_paper_search(c);
}

void read_model(Section& s, const std::string& file, ModelConfig* m) {
  s.text("stl", &m->stl);
  s.text("preset", &m->preset, {"", "sbend", "u", "torus"});
  s.triple("grasp_xyz_mm", &m->grasp_xyz_mm, "mm, model frame");
  s.triple("grasp_rxyz_deg", &m->grasp_rxyz_deg, "deg, plc.euler convention");
  s.finish();
  if (!m->stl.empty() && !m->preset.empty()) fail(file, "model", "give either stl or preset, not both");
  if (!m->stl.empty() && std::filesystem::path(m->stl).is_relative() && !file.empty())
    m->stl = (std::filesystem::path(file).parent_path() / m->stl).lexically_normal().string();
}

void read_source(const std::string& file, const toml::table* t, std::vector<std::string>* eff,
                 std::vector<std::string>* warnings, SourceConfig* c) {
  auto sub = [&](const char* name) -> const toml::table* {
    if (!t) return nullptr;
    const toml::node* n = t->get(name);
    if (n && !n->is_table())
      fail(file, std::string("source.") + name, "expected a [source." + std::string(name) + "] table");
    return n ? n->as_table() : nullptr;
  };
  Section s(file, "source", t, eff);
  s.text("kind", &c->kind, {"sim", "replay", "openni2"});
  s.finish({"sim", "replay", "openni2"});
  // A source's own table is read (and checked) whatever the kind, but only the chosen one is used.
  if (t)
    for (const char* name : {"sim", "replay", "openni2"})
      if (name != c->kind && t->contains(name))
        warnings->push_back("config '" + file + "': [source." + name + "] is ignored: source.kind is \"" +
                            c->kind + "\"");

  Section sim(file, "source.sim", sub("sim"), eff);
  sim.integer("pipes", &c->sim.pipes, 1, 200, "pipes");
  sim.integer("seed", &c->sim.seed, 0, 1 << 30, "");
  sim.real("tilt_deg", &c->sim.tilt_deg, 0, 45, "deg");
  sim.real("camera_height_min_mm", &c->sim.camera_height_min_mm, 200, 3000, "mm");
  sim.real("camera_height_max_mm", &c->sim.camera_height_max_mm, 200, 3000, "mm");
  sim.boolean("camera_sees_bin", &c->sim.camera_sees_bin);
  sim.text("sensor", &c->sim.sensor, {"kinect", "stereo"});
  sim.boolean("refill", &c->sim.refill);
  sim.integer("refill_after_frames_without_pick", &c->sim.refill_after_frames_without_pick, 0, 1000000,
              "frames (0: never)");
  sim.boolean("shake_after_none", &c->sim.shake_after_none);
  sim.text("truth_file", &c->sim.truth_file);
  sim.finish();
  if (c->sim.camera_height_min_mm > c->sim.camera_height_max_mm)
    fail(file, "source.sim.camera_height_max_mm", "expected at least camera_height_min_mm");

  Section rp(file, "source.replay", sub("replay"), eff);
  rp.text("path", &c->replay.path);
  rp.text("camera", &c->replay.camera);
  rp.integer("max_frames", &c->replay.max_frames, 1, 100000, "frames");
  rp.finish();
  auto relative_to_file = [&](std::string* p) {
    if (!p->empty() && std::filesystem::path(*p).is_relative() && !file.empty())
      *p = (std::filesystem::path(file).parent_path() / *p).lexically_normal().string();
  };
  relative_to_file(&c->replay.path);
  relative_to_file(&c->replay.camera);
  if (c->kind == "replay" && c->replay.path.empty())
    fail(file, "source.replay.path",
         "expected a BOP dataset or a folder of depth PNGs (source.kind is \"replay\")");

  Section on(file, "source.openni2", sub("openni2"), eff);
  on.text("uri", &c->openni2.uri);
  on.real("fx", &c->openni2.fx, 1, 10000, "px");
  on.real("fy", &c->openni2.fy, 1, 10000, "px");
  on.real("cx", &c->openni2.cx, 0, 10000, "px");
  on.real("cy", &c->openni2.cy, 0, 10000, "px");
  on.integer("calib_width", &c->openni2.calib_width, 1, 10000, "px");
  on.integer("calib_height", &c->openni2.calib_height, 1, 10000, "px");
  on.integer("frame_timeout_ms", &c->openni2.frame_timeout_ms, 10, 60000, "ms");
  on.integer("reopen_interval_ms", &c->openni2.reopen_interval_ms, 10, 600000, "ms");
  on.numbers("world_to_cam", &c->openni2.world_to_cam, 16, "4x4 row-major, mm");
  on.finish();
}

bool is_ipv4_address(const std::string& text) {
  in_addr a{};
  return inet_pton(AF_INET, text.c_str(), &a) == 1;
}

// Why a 4x4 row-major matrix is not a rigid transform ("" when it is). Rows of the rotation must
// be orthonormal to 1e-3 (a hand-eye result typed with 4 decimals passes; it is then made exactly
// orthonormal), its determinant +1 (not a reflection), the bottom row 0 0 0 1.
std::string rigid_transform_problem(const double* m) {
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1) return "the bottom row must be 0, 0, 0, 1";
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double dot = m[4 * i] * m[4 * j] + m[4 * i + 1] * m[4 * j + 1] + m[4 * i + 2] * m[4 * j + 2];
      if (std::abs(dot - (i == j ? 1.0 : 0.0)) > 1e-3)
        return "the rows of the 3x3 rotation are not orthonormal (row " + std::to_string(i + 1) + " . row " +
               std::to_string(j + 1) + " = " + std::to_string(dot) + ")";
    }
  const double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                     m[2] * (m[4] * m[9] - m[5] * m[8]);
  if (det < 0) return "the 3x3 part is a reflection (determinant -1), not a rotation";
  return "";
}

void read_plc(Section& s, std::vector<std::string>* warnings, PlcConfig* p) {
  s.text("mode", &p->mode, {"server", "client", "none"});
  s.text("address", &p->address, {}, false);
  if (!is_ipv4_address(p->address))
    fail(s.file(), s.full("address"),
         "expected an IPv4 address such as \"127.0.0.1\" or \"0.0.0.0\" (all interfaces), got \"" +
             p->address + "\" (host names are not resolved)");
  s.integer("port", &p->port, 1, 65535, "");
  s.integer("base", &p->base, 0, 65535 - reg::kSize, "register");
  s.integer("unit_id", &p->unit_id, 0, 255, "");
  s.integer("max_clients", &p->max_clients, 1, 64, "connections");
  s.integer("poll_ms", &p->poll_ms, 5, 10000, "ms");
  s.integer("reconnect_max_ms", &p->reconnect_max_ms, 100, 600000, "ms");
  s.integer("request_timeout_ms", &p->request_timeout_ms, 10, 60000, "ms");
  s.integer("idle_timeout_ms", &p->idle_timeout_ms, 100, 86400000, "ms");
  s.texts("plc_addresses", &p->plc_addresses, is_ipv4_address, "IPv4 addresses such as \"192.168.0.10\"");
  s.integer("byte_timeout_ms", &p->byte_timeout_ms, 10, 5000, "ms");
  s.boolean("write_held", &p->write_held);
  std::string order = word_order_name(p->encoding.order);
  s.text("word_order", &order, {"ABCD", "CDAB", "BADC", "DCBA"});
  p->encoding.order = parse_word_order(order);
  std::string encoding = p->encoding.scaled_int32 ? "scaled_int32" : "float32";
  s.text("encoding", &encoding, {"float32", "scaled_int32"});
  p->encoding.scaled_int32 = encoding == "scaled_int32";
  std::string euler = p->euler == EulerConvention::zyx ? "ZYX" : "XYZ";
  s.text("euler", &euler, {"ZYX", "XYZ"});
  p->euler = parse_euler_convention(euler);
  s.numbers("robot_from_camera", &p->robot_from_camera, 16, "4x4 row-major, mm");
  // Keys of the other mode are checked like the rest but do nothing: say so (a warning, not an
  // error: one file may serve cells in both modes, or a cell switched from one to the other).
  auto ignored = [&](std::initializer_list<const char*> keys, const char* used_in) {
    for (const char* k : keys)
      if (s.given(k))
        warnings->push_back("config '" + s.file() + "': " + s.full(k) + " is ignored: it is used in " +
                            used_in + " mode only and plc.mode is \"" + p->mode + "\"");
  };
  if (p->mode != "server")
    ignored({"max_clients", "request_timeout_ms", "idle_timeout_ms", "plc_addresses"}, "server");
  if (p->mode != "client")
    ignored({"unit_id", "poll_ms", "reconnect_max_ms", "byte_timeout_ms", "write_held"}, "client");
  if (!p->robot_from_camera.empty()) {
    const std::string why = rigid_transform_problem(p->robot_from_camera.data());
    if (!why.empty())
      fail(s.file(), s.full("robot_from_camera"),
           "expected a rigid transform (rotation and translation): " + why);
  }
  s.finish();
}

void read_status(Section& s, StatusConfig* c) {
  s.boolean("enabled", &c->enabled);
  s.text("address", &c->address, {}, false);
  if (!is_ipv4_address(c->address))
    fail(s.file(), s.full("address"),
         "expected an IPv4 address such as \"127.0.0.1\" (this machine only) or \"0.0.0.0\" (every "
         "interface), got \"" +
             c->address + "\"");
  s.integer("port", &c->port, 0, 65535, "TCP port (0: any free one)");
  s.integer("overlay_every", &c->overlay_every, 0, 1000000, "LOCATE cycles (0 = no overlay on the page)");
  s.integer("refresh_s", &c->refresh_s, 1, 3600, "s");
  s.finish();
}

void read_all(const std::string& file, const toml::table& root, AppConfig* cfg) {
  static const char* const kSections[] = {"model", "locate", "source", "service", "plc", "log", "status"};
  for (const auto& [key, node] : root) {
    bool known = false;
    for (const char* s : kSections) known = known || key.str() == s;
    if (!known)
      fail(file, std::string(key.str()),
           "unknown section (expected [model], [locate], [source], [service], [plc], [log] or [status])");
    if (!node.is_table())
      fail(file, std::string(key.str()), "expected a [" + std::string(key.str()) + "] table");
  }
  auto table = [&](const char* name) { return root.get_as<toml::table>(name); };
  auto* eff = &cfg->effective;

  Section model(file, "model", table("model"), eff);
  read_model(model, file, &cfg->model);
  cfg->model_path = cfg->model.stl;

  Section locate(file, "locate", table("locate"), eff);
  read_locate(locate, &cfg->locate);

  read_source(file, table("source"), eff, &cfg->warnings, &cfg->source);

  Section service(file, "service", table("service"), eff);
  service.real("budget_ms", &cfg->service.budget_ms, 5, 60000, "ms");
  service.integer("summary_every", &cfg->service.summary_every, 1, 1000000, "cycles");
  service.boolean("withhold_unchanged_picks", &cfg->service.withhold_unchanged_picks);
  service.finish();

  Section plc(file, "plc", table("plc"), eff);
  read_plc(plc, &cfg->warnings, &cfg->plc);

  Section log(file, "log", table("log"), eff);
  log.text("dir", &cfg->log.dir, {}, false);
  log.integer("max_file_kb", &cfg->log.max_file_kb, 1, 1 << 22, "KiB");
  log.integer("keep_files", &cfg->log.keep_files, 1, 1000, "files");
  log.integer("overlay_every", &cfg->log.overlay_every, 0, 1000000, "LOCATE cycles (0 = never)");
  log.integer("no_pick_frames", &cfg->log.no_pick_frames, 0, 1000, "frames kept (0 = none)");
  log.integer("took_nothing_frames", &cfg->log.took_nothing_frames, 0, 1000, "frames kept (0 = none)");
  log.finish();

  Section status(file, "status", table("status"), eff);
  read_status(status, &cfg->status);
}

}  // namespace

AppConfig load_config(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw ConfigError("config '" + path + "': no such file");
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << "config '" << path << "': line " << e.source().begin.line << ": " << e.description();
    throw ConfigError(msg.str());
  }
  AppConfig cfg;
  cfg.path = path;
  read_all(path, root, &cfg);
  return cfg;
}

AppConfig default_config() {
  AppConfig cfg;
  read_all("", toml::table{}, &cfg);
  return cfg;
}

AppConfig embedded_default_config() {
  AppConfig cfg = default_config();
  cfg.model.preset = "sbend";
  for (std::string& line : cfg.effective)
    if (line.rfind("model.preset = ", 0) == 0) line = "model.preset = \"sbend\"";
  return cfg;
}

std::vector<std::string> describe_config(const AppConfig& cfg) { return cfg.effective; }

}  // namespace pipeloc
