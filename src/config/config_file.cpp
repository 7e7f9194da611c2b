#include "config/config_file.hpp"

#include <toml++/toml.h>

#include <filesystem>
#include <sstream>

namespace pipeloc {
namespace {

struct Field {
  const char* key;
  double LocateConfig::*real = nullptr;
  int LocateConfig::*integer = nullptr;
  double min, max;
  const char* unit;
};

#define REAL(name, lo, hi, unit) \
  Field { #name, &LocateConfig::name, nullptr, lo, hi, unit }
#define INT(name, lo, hi, unit) \
  Field { #name, nullptr, &LocateConfig::name, lo, hi, unit }

const Field kLocateFields[] = {
    REAL(zbuffer_pixel_mm, 0.25, 10, "mm"),
    REAL(zbuffer_max_side_mm, 100, 5000, "mm"),
    REAL(hole_fill_mm, 0, 50, "mm"),
    REAL(normal_window_mm, 1, 50, "mm"),
    REAL(normal_min_valid_share, 0.05, 1, "share"),
    REAL(upward_normal_max_deg, 1, 89, "deg"),
    REAL(continuity_max_deg, 1, 89, "deg"),
    REAL(continuity_step_max_mm, 0.1, 100, "mm"),
    REAL(core_min_area_of_d2, 0, 100, "x D^2"),
    REAL(core_max_extent_of_l, 0.1, 10, "x L"),
    REAL(region_min_extent_of_l, 0, 2, "x L"),
    REAL(convexity_min_share, 0, 1, "share"),
    REAL(region_max_drop_of_d, 0.1, 5, "x D"),
    REAL(section_width_min_of_d, 0.1, 2, "x D"),
    REAL(section_width_max_of_d, 0.1, 3, "x D"),
    REAL(scan_step_deg, 0.5, 45, "deg"),
    REAL(ridge_cell_mm, 0.5, 10, "mm"),
    INT(initial_rotations, 1, 12, "states per direction"),
    INT(icp_max_iterations, 1, 500, "iterations"),
    INT(icp_probe_iterations, 1, 500, "iterations"),
    INT(icp_continued_states, 1, 48, "states"),
    REAL(icp_converged_mm, 0.001, 10, "mm"),
    REAL(residual_max_of_d, 0.01, 5, "x D"),
    INT(refine_iterations, 0, 200, "iterations"),
    REAL(refine_inlier_mm, 0.5, 50, "mm"),
    INT(refine_max_points, 50, 100000, "points"),
    REAL(verify_tolerance_mm, 0.5, 100, "mm"),
    REAL(verify_min_agreement, 0, 1, "share"),
    REAL(verify_max_free_space, 0, 1, "share"),
    REAL(verify_max_occluded, 0, 1, "share"),
    REAL(ambiguity_pose_mm, 0, 1000, "mm"),
    REAL(ambiguity_quality_margin, 0, 1, "share"),
    INT(verify_hypotheses, 1, 24, "fits per region"),
    INT(max_candidates, 1, 256, "regions"),
    INT(max_results, 1, 256, "poses"),
    INT(threads, 1, 64, "threads"),
};

[[noreturn]] void fail(const std::string& path, const std::string& key, const std::string& what) {
  throw ConfigError("config '" + path + "': " + key + ": " + what);
}

void read_locate(const std::string& path, const toml::table& table, LocateConfig* cfg) {
  for (const auto& [key, node] : table) {
    const Field* field = nullptr;
    for (const auto& f : kLocateFields)
      if (key.str() == f.key) field = &f;
    const std::string name = "locate." + std::string(key.str());
    if (!field) fail(path, name, "unknown key");
    std::ostringstream range;
    range << "expected " << (field->integer ? "an integer" : "a number") << " in [" << field->min << ", "
          << field->max << "] " << field->unit;
    double value;
    if (field->integer) {
      const auto v = node.value_exact<std::int64_t>();
      if (!v) fail(path, name, range.str());
      value = double(*v);
    } else {
      const auto v = node.value<double>();
      if (!v || !node.is_number()) fail(path, name, range.str());
      value = *v;
    }
    if (!(value >= field->min && value <= field->max)) fail(path, name, range.str());
    if (field->integer)
      cfg->*(field->integer) = int(value);
    else
      cfg->*(field->real) = value;
  }
  if (cfg->section_width_min_of_d >= cfg->section_width_max_of_d)
    fail(path, "locate.section_width_min_of_d", "must be below locate.section_width_max_of_d");
}

}  // namespace

AppConfig load_config(const std::string& path) {
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << "config '" << path << "': line " << e.source().begin.line << ": " << e.description();
    throw ConfigError(msg.str());
  }
  AppConfig cfg;
  for (const auto& [key, node] : root) {
    const std::string section(key.str());
    if (!node.is_table()) fail(path, section, "expected a [" + section + "] table");
    const toml::table& t = *node.as_table();
    if (section == "locate") {
      read_locate(path, t, &cfg.locate);
    } else if (section == "model") {
      for (const auto& [k, v] : t) {
        if (k.str() != "stl") fail(path, "model." + std::string(k.str()), "unknown key");
        const auto s = v.value<std::string>();
        if (!s || s->empty()) fail(path, "model.stl", "expected a path to the pipe's STL file");
        std::filesystem::path p(*s);
        if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
        cfg.model_path = p.lexically_normal().string();
      }
    } else {
      fail(path, section, "unknown section (expected [model] or [locate])");
    }
  }
  return cfg;
}

std::vector<std::string> describe_config(const AppConfig& cfg) {
  std::vector<std::string> lines;
  lines.push_back("model.stl = \"" + cfg.model_path + "\"");
  for (const auto& f : kLocateFields) {
    std::ostringstream s;
    s << "locate." << f.key << " = ";
    if (f.integer)
      s << cfg.locate.*(f.integer);
    else
      s << cfg.locate.*(f.real);
    s << "  # " << f.unit;
    lines.push_back(s.str());
  }
  return lines;
}

}  // namespace pipeloc
