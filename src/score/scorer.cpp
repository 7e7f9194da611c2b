#include "score/scorer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "model/stl.hpp"
#include "score/mssd.hpp"

namespace pipeloc {
namespace {

constexpr double kBoundsMm[2] = {5.0, 10.0};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * double(v.size() - 1);
  const std::size_t lo = std::size_t(std::floor(pos)), hi = std::size_t(std::ceil(pos));
  return v[lo] + (v[hi] - v[lo]) * (pos - double(lo));
}

double ratio(int num, int den) { return den > 0 ? double(num) / den : std::nan(""); }

struct ObjectData {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Pose> symmetries;
};

// Greedy matching of DESIGN.md: estimates by descending score, each to the unmatched true pose
// with the least error, if that error is within the bound. Returns the true pose matched to
// each estimate (-1 for none).
std::vector<int> greedy_match(const std::vector<std::vector<double>>& error, std::size_t truths,
                              double bound) {
  std::vector<int> match(error.size(), -1);
  std::vector<bool> taken(truths, false);
  for (std::size_t e = 0; e < error.size(); ++e) {
    int best = -1;
    for (std::size_t g = 0; g < truths; ++g)
      if (!taken[g] && error[e][g] < bound && (best < 0 || error[e][g] < error[e][best])) best = int(g);
    if (best >= 0) taken[best] = true, match[e] = best;
  }
  return match;
}

// The top pipes `match` leaves unmatched, each with the estimate nearest to it.
void add_misses(const ObjectData& obj, const std::vector<const ResultRow*>& est,
                const std::vector<const GtPose*>& gt, const std::vector<const GtInfo*>& info,
                const std::vector<int>& match, const TopMiss& image, ScoreReport* report) {
  std::vector<bool> matched(gt.size(), false);
  for (int g : match)
    if (g >= 0) matched[g] = true;
  for (std::size_t g = 0; g < gt.size(); ++g) {
    if (!info[g]->top || matched[g]) continue;
    TopMiss m = image;
    m.gt_index = int(g);
    m.occ_by_pipes = info[g]->occ_by_pipes;
    m.visib_fract = info[g]->visib_fract;
    m.nearest_mm = kMissCapMm;
    for (std::size_t e = 0; e < est.size(); ++e) {
      const double d =
          mssd(obj.vertices, est[e]->model_to_cam, gt[g]->model_to_cam, obj.symmetries, m.nearest_mm);
      if (d < m.nearest_mm) m.nearest_mm = d, m.nearest_rank = int(e), m.nearest_score = est[e]->score;
    }
    report->misses.push_back(m);
  }
}

}  // namespace

double ScoreCounts::top_recall(int bound) const {
  return ratio(bound == 5 ? top_matched_5 : top_matched_10, top_pipes);
}
double ScoreCounts::best_correct(int bound) const {
  return ratio(bound == 5 ? best_correct_5 : best_correct_10, images);
}
double ScoreCounts::precision_10() const { return ratio(matched_10, estimates); }
double ScoreCounts::time_median_s() const { return percentile(times_s, 0.5); }
double ScoreCounts::time_p95_s() const { return percentile(times_s, 0.95); }
double ScoreCounts::pick_rate() const { return ratio(picked_images, pick_images); }
double ScoreCounts::pick_correct_5mm() const { return ratio(pick_correct_5, picks); }

void ScoreCounts::add(const ScoreCounts& o) {
  images += o.images;
  top_pipes += o.top_pipes;
  top_matched_5 += o.top_matched_5;
  top_matched_10 += o.top_matched_10;
  best_correct_5 += o.best_correct_5;
  best_correct_10 += o.best_correct_10;
  estimates += o.estimates;
  matched_10 += o.matched_10;
  times_s.insert(times_s.end(), o.times_s.begin(), o.times_s.end());
  pick_images += o.pick_images;
  picked_images += o.picked_images;
  picks += o.picks;
  pick_correct_5 += o.pick_correct_5;
  wrong_picks += o.wrong_picks;
}

ScoreReport score_results(const std::string& dataset, const ResultsFile& results, const ScoreParams& params,
                          const ResultsFile* picks, bool list_misses) {
  ScoreReport report;
  std::map<std::tuple<int, int, int>, const ResultRow*> pick_of;
  if (picks) {
    report.has_picks = true;
    report.pick_rows_malformed = picks->malformed;
    for (const auto& r : picks->rows)
      if (!pick_of.emplace(std::tuple{r.scene_id, r.im_id, r.obj_id}, &r).second) ++report.pick_rows_extra;
  }
  int pick_rows_used = 0;
  report.malformed_rows = results.malformed;
  report.malformed_examples = results.first_errors;
  const auto targets = read_targets(dataset + "/test_targets_bop19.json");
  const auto models_info = read_models_info(dataset + "/models/models_info.json");

  std::map<int, ObjectData> objects;
  std::map<int, std::map<int, std::vector<GtPose>>> scene_gt;
  std::map<int, std::map<int, std::vector<GtInfo>>> scene_info;
  // Rows by image, in file order (ties in score keep it).
  std::map<std::tuple<int, int, int>, std::vector<const ResultRow*>> rows;
  for (const auto& r : results.rows) rows[{r.scene_id, r.im_id, r.obj_id}].push_back(&r);
  int rows_used = 0;

  for (const auto& t : targets) {
    if (!objects.count(t.obj_id)) {
      const Mesh mesh = read_stl(model_path(dataset, t.obj_id));
      ObjectData& o = objects[t.obj_id];
      for (const auto& v : mesh.vertices) o.vertices.push_back(v.cast<double>());
      const auto info = models_info.find(t.obj_id);
      if (info != models_info.end()) {
        o.symmetries = info->second.symmetries;
        report.object_names[t.obj_id] = info->second.name;
      }
      o.symmetries = with_tube_turns(o.vertices, o.symmetries);
    }
    if (!scene_gt.count(t.scene_id)) {
      scene_gt[t.scene_id] = read_scene_gt(scene_dir(dataset, t.scene_id) + "/scene_gt.json");
      scene_info[t.scene_id] = read_scene_gt_info(scene_dir(dataset, t.scene_id) + "/scene_gt_info.json");
    }
    const ObjectData& obj = objects[t.obj_id];
    const auto& all_gt = scene_gt[t.scene_id][t.im_id];
    const auto& all_info = scene_info[t.scene_id][t.im_id];
    if (all_gt.size() != all_info.size())
      throw IoError("scene " + std::to_string(t.scene_id) + " image " + std::to_string(t.im_id) +
                    ": scene_gt and scene_gt_info disagree on the number of instances");
    std::vector<const GtPose*> gt;
    std::vector<const GtInfo*> info;
    for (std::size_t i = 0; i < all_gt.size(); ++i)
      if (all_gt[i].obj_id == t.obj_id) gt.push_back(&all_gt[i]), info.push_back(&all_info[i]);

    std::vector<const ResultRow*> est;
    if (auto it = rows.find({t.scene_id, t.im_id, t.obj_id}); it != rows.end()) est = it->second;
    rows_used += int(est.size());
    std::stable_sort(est.begin(), est.end(),
                     [](const ResultRow* a, const ResultRow* b) { return a->score > b->score; });

    ScoreCounts c;
    c.images = 1;
    c.estimates = int(est.size());
    for (const auto* i : info) c.top_pipes += i->top ? 1 : 0;
    if (!est.empty() && est.front()->time_s >= 0) c.times_s.push_back(est.front()->time_s);

    std::vector<std::vector<double>> error(est.size(), std::vector<double>(gt.size()));
    for (std::size_t e = 0; e < est.size(); ++e)
      for (std::size_t g = 0; g < gt.size(); ++g)
        error[e][g] =
            mssd(obj.vertices, est[e]->model_to_cam, gt[g]->model_to_cam, obj.symmetries, kBoundsMm[1]);

    for (double bound : kBoundsMm) {
      const auto match = greedy_match(error, gt.size(), bound);
      int top = 0, matched = 0;
      for (std::size_t e = 0; e < match.size(); ++e) {
        if (match[e] < 0) continue;
        ++matched;
        top += info[match[e]]->top ? 1 : 0;
      }
      const bool best_ok =
          !match.empty() && match[0] >= 0 && info[match[0]]->occ_by_pipes <= params.top_occlusion_max;
      if (bound == kBoundsMm[0]) {
        c.top_matched_5 = top;
        c.best_correct_5 = best_ok;
        if (list_misses)
          add_misses(obj, est, gt, info, match, TopMiss{t.scene_id, t.im_id, t.obj_id}, &report);
      } else {
        c.top_matched_10 = top;
        c.best_correct_10 = best_ok;
        c.matched_10 = matched;
      }
    }
    if (picks) {
      const auto it = pick_of.find({t.scene_id, t.im_id, t.obj_id});
      const ResultRow* pick = it == pick_of.end() ? nullptr : it->second;
      c.pick_images = c.top_pipes > 0;
      c.picked_images = c.top_pipes > 0 && pick;
      if (pick) {
        ++pick_rows_used;
        c.picks = 1;
        // The PLC's pose against every pipe the gripper could take: covered at most the bound.
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t g = 0; g < gt.size(); ++g)
          if (info[g]->occ_by_pipes <= params.top_occlusion_max)
            best = std::min(best, mssd(obj.vertices, pick->model_to_cam, gt[g]->model_to_cam, obj.symmetries,
                                       params.wrong_pick_mm));
        c.pick_correct_5 = best < kBoundsMm[0];
        c.wrong_picks = best > params.wrong_pick_mm;
      }
    }
    report.per_object[t.obj_id].add(c);
    report.overall.add(c);
  }
  report.rows_outside_targets = int(results.rows.size()) - rows_used;
  if (picks) report.pick_rows_outside_targets = int(pick_of.size()) - pick_rows_used;
  return report;
}

std::string format_report(const ScoreReport& r) {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof line, "%-18s %6s %5s %9s %10s %7s %8s %8s %5s %10s %10s", "object", "images",
                "top", "recall@5", "recall@10", "best@5", "best@10", "prec@10", "est", "t_med_ms",
                "t_p95_ms");
  out << line;
  if (r.has_picks) {
    std::snprintf(line, sizeof line, " %9s %7s %11s %6s", "pick_rate", "picks", "pick_ok@5", "wrong");
    out << line;
  }
  out << '\n';
  auto row = [&](const std::string& name, const ScoreCounts& c) {
    std::snprintf(line, sizeof line, "%-18s %6d %5d %9.3f %10.3f %7.3f %8.3f %8.3f %5d %10.1f %10.1f",
                  name.c_str(), c.images, c.top_pipes, c.top_recall(5), c.top_recall(10), c.best_correct(5),
                  c.best_correct(10), c.precision_10(), c.estimates, c.time_median_s() * 1e3,
                  c.time_p95_s() * 1e3);
    out << line;
    if (r.has_picks) {
      std::snprintf(line, sizeof line, " %9.3f %7d %11.3f %6d", c.pick_rate(), c.picks, c.pick_correct_5mm(),
                    c.wrong_picks);
      out << line;
    }
    out << '\n';
  };
  for (const auto& [id, c] : r.per_object) {
    const auto name = r.object_names.count(id) ? r.object_names.at(id) : "";
    row(std::to_string(id) + (name.empty() ? "" : " " + name), c);
  }
  row("all", r.overall);
  out << "malformed rows: " << r.malformed_rows
      << ", rows for images not in the targets: " << r.rows_outside_targets << '\n';
  for (const auto& e : r.malformed_examples) out << "  " << e << '\n';
  if (r.has_picks)
    out << "picks: images with a top pipe given a pose / such images (pick_rate); handed-out poses within 5 "
           "mm "
           "of a pipe covered at most 15 % / handed-out poses (pick_ok@5); wrong: more than 10 mm from every "
           "such pipe. pick rows malformed: "
        << r.pick_rows_malformed << ", for images not in the targets: " << r.pick_rows_outside_targets
        << ", more than one for an image: " << r.pick_rows_extra << '\n';
  return out.str();
}

std::string format_misses(const ScoreReport& r) {
  std::ostringstream out;
  out << "scene_id,im_id,obj_id,gt_index,occ_by_pipes,visib_fract,nearest_mm,nearest_rank,nearest_score\n";
  char line[160];
  for (const auto& m : r.misses) {
    std::snprintf(line, sizeof line, "%d,%d,%d,%d,%.3f,%.3f,%.1f,%d,%.3f\n", m.scene_id, m.im_id, m.obj_id,
                  m.gt_index, m.occ_by_pipes, m.visib_fract, m.nearest_mm, m.nearest_rank, m.nearest_score);
    out << line;
  }
  return out.str();
}

Json report_to_json(const ScoreReport& r) {
  auto counts = [&r](const ScoreCounts& c) {
    auto num = [](double v) { return std::isnan(v) ? Json(nullptr) : Json(v); };
    Json j{{"images", c.images},
           {"top_pipes", c.top_pipes},
           {"top_recall_5mm", num(c.top_recall(5))},
           {"top_recall_10mm", num(c.top_recall(10))},
           {"best_correct_5mm", num(c.best_correct(5))},
           {"best_correct_10mm", num(c.best_correct(10))},
           {"precision_10mm", num(c.precision_10())},
           {"estimates", c.estimates},
           {"time_median_s", num(c.time_median_s())},
           {"time_p95_s", num(c.time_p95_s())}};
    if (r.has_picks) {
      j["pick_images"] = c.pick_images;
      j["picked_images"] = c.picked_images;
      j["pick_rate"] = num(c.pick_rate());
      j["picks"] = c.picks;
      j["pick_correct_5mm"] = num(c.pick_correct_5mm());
      j["pick_correct_5mm_count"] = c.pick_correct_5;
      j["wrong_picks"] = c.wrong_picks;
    }
    return j;
  };
  Json j = {{"overall", counts(r.overall)},
            {"malformed_rows", r.malformed_rows},
            {"rows_outside_targets", r.rows_outside_targets},
            {"pick_rows_malformed", r.pick_rows_malformed},
            {"pick_rows_outside_targets", r.pick_rows_outside_targets},
            {"pick_rows_extra", r.pick_rows_extra},
            {"per_object", Json::object()}};
  for (const auto& [id, c] : r.per_object) j["per_object"][std::to_string(id)] = counts(c);
  return j;
}

}  // namespace pipeloc
