#include "report/locate_overlay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <vector>

#include "render/raster.hpp"
#include "render/text.hpp"

namespace pipeloc {
namespace {

const Rgb kRegion{170, 90, 220}, kCore{40, 110, 255}, kAxis{255, 150, 0}, kRidge{40, 230, 60},
    kOutline{255, 235, 60}, kOther{150, 150, 150}, kPick{255, 30, 30}, kFloor{0, 150, 140},
    kViewEdge{0, 200, 255};

// A core at floor height that gave no pose is the bin floor seen between pipes, not a pipe: it is
// drawn faintly in its own colour, without region, direction or ridge. Floor height: within D/2
// of the lowest surface seen (a pipe lying on the floor has its core about D above it).
bool floor_core(const CandidateRegion& r, const CandidateTrace* trace, float floor_z_mm, float tube_d_mm) {
  const bool posed = trace && trace->outcome == CandidateOutcome::accepted;
  return !posed && r.core_centroid.z() < floor_z_mm + 0.5f * tube_d_mm;
}

Eigen::Vector2d to_pixel(const CameraInfo& cam, const Pose& bin_to_cam, const Eigen::Vector3f& p_bin) {
  return cam.intrinsics.project(bin_to_cam * p_bin.cast<double>());
}

// A pixel of a render's outline: rendered, at the edge of its box or beside a pixel not rendered.
bool on_outline(const Image<float>& z, const PixelBox& box, int x, int y) {
  if (z.at(x, y) <= 0) return false;
  return x == box.x0 || y == box.y0 || x == box.x1 || y == box.y1 || z.at(x - 1, y) <= 0 ||
         z.at(x + 1, y) <= 0 || z.at(x, y - 1) <= 0 || z.at(x, y + 1) <= 0;
}

void draw_outline(Image<Rgb>* img, const Mesh& mesh, const Pose& model_to_cam, const Intrinsics& k, Rgb color,
                  int thickness, Image<float>* scratch, ProjectedMesh* projected) {
  const PixelBox box = render_depth_in_box(mesh, model_to_cam, k, scratch, projected);
  for (int y = box.y0; y <= box.y1; ++y)
    for (int x = box.x0; x <= box.x1; ++x)
      if (on_outline(*scratch, box, x, y)) draw_dot(img, x, y, thickness / 2, color);
}

struct LegendEntry {
  Rgb color;
  const char* text;
  bool swatch = true;  // false: the line goes on explaining the entry above
};
const LegendEntry kLegend[] = {{kPick, "PICK: POSE HANDED TO THE PLC"},
                               {kOutline, "POSE, PICKABLE (R<RANK> <SCORE> OK)"},
                               {kOther, "POSE, NOT PICKABLE (R<RANK> <SCORE> WHY):"},
                               {kOther, " AMBIGUOUS <WHY>: ANOTHER POSE FITS AS WELL:", false},
                               {kOther, "  TWIN FAR (TOO FAR TO TELL ITS TWIN), RIVAL (A TWIN OR", false},
                               {kOther, "  SLID POSE), SLIDES (ALONG ITSELF), ROLL (ABOUT ITS", false},
                               {kOther, "  LENGTH), OTHER PART (OF IT), TWO WAYS (TWO REGIONS)", false},
                               {kOther, " COVERED: UNDER OTHERS  PART SEEN: TOO LITTLE SEEN", false},
                               {kOther, " GOES ON: THE TUBE GOES ON PAST BOTH ENDS", false},
                               {kOther, " NO END: NO END SEEN ENDING", false},
                               {kOther, " UNSURE: SECOND SEARCH, TOO LITTLE CONFIRMED", false},
                               {kOther, " NOISY: THE SENSOR DOES NOT RESOLVE THE TUBE", false},
                               {kOther, " TOOK NOTHING: HANDED OUT, THE BIN STAYED AS IT WAS", false},
                               {kCore, "CORE REGION (UPWARD NORMALS)"},
                               {kRegion, "CANDIDATE REGION (GROWN)"},
                               {kAxis, "PRINCIPAL DIRECTION"},
                               {kRidge, "Z-RIDGE POINTS"},
                               {kFloor, "FLOOR SEEN BETWEEN PIPES (NO CANDIDATE)"},
                               {kViewEdge, "EDGE OF THE VIEW (NO DEPTH READ BEYOND)"}};
constexpr int kLegendScale = 1, kLegendLine = 9, kLegendX0 = 4, kLegendY0 = 4;

// The pixels the legend covers, at the top left.
PixelBox legend_box() {
  std::size_t longest = 0;
  for (const LegendEntry& e : kLegend) longest = std::max(longest, std::strlen(e.text));
  const int w = 15 + 4 * kLegendScale * int(longest) + 3, h = kLegendLine * int(std::size(kLegend)) + 4;
  return {kLegendX0, kLegendY0, kLegendX0 + w - 1, kLegendY0 + h - 1};
}

void draw_legend(Image<Rgb>* img) {
  const PixelBox box = legend_box();
  for (int y = box.y0; y <= box.y1; ++y)
    for (int x = box.x0; x <= box.x1; ++x)
      if (img->inside(x, y)) img->at(x, y) = {20, 20, 20};
  int y = box.y0 + 3;
  for (const LegendEntry& e : kLegend) {
    for (int dy = 0; dy < 5 && e.swatch; ++dy)
      for (int dx = 0; dx < 8; ++dx)
        if (img->inside(box.x0 + 3 + dx, y + dy)) img->at(box.x0 + 3 + dx, y + dy) = e.color;
    draw_text(img, box.x0 + 15, y, e.text, {235, 235, 235}, kLegendScale);
    y += kLegendLine;
  }
}

// The edges of the sensor's view (read_view) that lie inside the image, dashed: beyond them it
// reads nothing, and a pose's part there counts as out of the view.
void draw_view_edges(Image<Rgb>* img, const PixelBox& view) {
  constexpr int kDash = 6;
  const auto dashed = [&](int x0, int y0, int x1, int y1) {  // a horizontal or vertical line
    const int dx = x1 > x0, dy = y1 > y0, n = std::max(x1 - x0, y1 - y0);
    for (int i = 0; i <= n; i += 2 * kDash) {
      const int j = std::min(n, i + kDash);
      draw_line(img, x0 + dx * i, y0 + dy * i, x0 + dx * j, y0 + dy * j, kViewEdge, 1);
    }
  };
  if (view.empty()) return;
  if (view.x0 > 0) dashed(view.x0, view.y0, view.x0, view.y1);
  if (view.x1 < img->width - 1) dashed(view.x1, view.y0, view.x1, view.y1);
  if (view.y0 > 0) dashed(view.x0, view.y0, view.x1, view.y0);
  if (view.y1 < img->height - 1) dashed(view.x0, view.y1, view.x1, view.y1);
}

// The depth shaded and greyed down, so what is drawn on it stands out.
Image<Rgb> grey_depth(const Image<float>& depth) {
  Image<Rgb> img = shade_depth(depth);
  for (auto& p : img.pixels) {
    const std::uint8_t g = std::uint8_t((p.r + p.g + p.b) / 3 * 0.7);
    p = {g, g, g};
  }
  return img;
}

void draw_cross(Image<Rgb>* img, const Eigen::Vector2d& c, Rgb color) {
  draw_line(img, c.x() - 8, c.y() - 8, c.x() + 8, c.y() + 8, color, 3);
  draw_line(img, c.x() - 8, c.y() + 8, c.x() + 8, c.y() - 8, color, 3);
}

}  // namespace

Image<Rgb> draw_locate_overlay(const Locator& loc, const Image<float>& depth, const CameraInfo& cam) {
  Image<Rgb> img = grey_depth(depth);
  const Pose bin_to_cam = bin_to_camera(cam);
  const ZBuffer& zb = loc.zbuffer();
  const RegionBuffers& rb = loc.regions();
  const int w = zb.z.width;
  const LocateOutput& out = loc.output();
  const float tube_d_mm = loc.locator_model().tube_d_mm;
  std::vector<bool> floor(rb.candidates.size(), false);
  for (std::size_t c = 0; c < rb.candidates.size(); ++c) {
    const CandidateRegion& r = rb.candidates[c];
    floor[c] =
        floor_core(r, c < out.traces.size() ? &out.traces[c] : nullptr, out.lowest_surface_z_mm, tube_d_mm);
    if (floor[c]) {
      for (int k = r.core_begin; k < r.core_end; ++k) {
        const int cell = rb.core_cells[std::size_t(k)];
        const Eigen::Vector2d px = to_pixel(cam, bin_to_cam, zb.point(cell % w, cell / w));
        tint(&img, int(std::lround(px.x())), int(std::lround(px.y())), kFloor, 0.3f);
      }
      continue;
    }
    for (int k = r.cells_begin; k < r.cells_end; ++k) {
      const int cell = rb.region_cells[std::size_t(k)];
      const Eigen::Vector2d px = to_pixel(cam, bin_to_cam, zb.point(cell % w, cell / w));
      tint(&img, int(std::lround(px.x())), int(std::lround(px.y())), kRegion, 0.45f);
    }
    for (int k = r.core_begin; k < r.core_end; ++k) {
      const int cell = rb.core_cells[std::size_t(k)];
      const Eigen::Vector2d px = to_pixel(cam, bin_to_cam, zb.point(cell % w, cell / w));
      tint(&img, int(std::lround(px.x())), int(std::lround(px.y())), kCore, 0.6f);
    }
  }
  Image<float> scratch(depth.width, depth.height, 0.0f);
  const Mesh& mesh = loc.locator_model().model->mesh;
  ProjectedMesh projected;
  projected.reserve(mesh);
  const int pick = out.pick();
  for (int i = int(out.estimates.size()) - 1; i >= 0; --i) {
    const PipeEstimate& e = out.estimates[std::size_t(i)];
    draw_outline(&img, mesh, e.model_to_cam, cam.intrinsics,
                 i == pick    ? kPick
                 : e.pickable ? kOutline
                              : kOther,
                 i == pick ? 3 : 1, &scratch, &projected);
  }
  for (std::size_t c = 0; c < out.traces.size(); ++c) {
    const CandidateTrace& t = out.traces[c];
    if (c < floor.size() && floor[c]) continue;
    // III's principal direction, drawn across its own region only.
    const Eigen::Vector3f dir(t.axis.axis.x(), t.axis.axis.y(), 0);
    float lo = 0, hi = 0;
    if (c < rb.candidates.size()) {
      const CandidateRegion& r = rb.candidates[c];
      for (int k = r.cells_begin; k < r.cells_end; ++k) {
        const int cell = rb.region_cells[std::size_t(k)];
        const float along = (zb.point(cell % w, cell / w) - t.axis.centre).dot(dir);
        lo = std::min(lo, along), hi = std::max(hi, along);
      }
    }
    const Eigen::Vector2d a = to_pixel(cam, bin_to_cam, t.axis.centre + lo * dir);
    const Eigen::Vector2d b = to_pixel(cam, bin_to_cam, t.axis.centre + hi * dir);
    draw_line(&img, a.x(), a.y(), b.x(), b.y(), kAxis, 1);
    for (int k = 0; k < t.ridge_count; ++k) {
      const Eigen::Vector2d p = to_pixel(cam, bin_to_cam, loc.ridge_points()[std::size_t(t.ridge_begin + k)]);
      draw_dot(&img, p.x(), p.y(), 1, kRidge);
    }
  }
  if (pick >= 0) {
    const Pose& p = out.estimates[std::size_t(pick)].model_to_cam;
    draw_cross(&img, cam.intrinsics.project(p * loc.locator_model().centroid.cast<double>()), kPick);
  }
  // Beside each pose: rank (0 = best, as the PLC's INDEX), score, pickable or not.
  for (int i = int(out.estimates.size()) - 1; i >= 0; --i) {
    const PipeEstimate& e = out.estimates[std::size_t(i)];
    const Eigen::Vector2d c =
        cam.intrinsics.project(e.model_to_cam * loc.locator_model().centroid.cast<double>());
    if (!c.allFinite()) continue;
    // Not pickable: the first check it fails (Withheld's order), NO where none is named.
    // AMBIGUOUS names its first reason (Ambiguity's order).
    const int first = withheld_index(e.withheld);
    const char* why = first < kWithheldKinds ? withheld_label(first) : "NO";
    const int because = ambiguity_index(e.ambiguous_why);
    const bool says_because = (1u << first) == kWithheldAmbiguous && because < kAmbiguityKinds;
    char tail[40] = "", text[72];
    if (i != pick)
      std::snprintf(tail, sizeof tail, " %s%s%s", e.pickable ? "OK" : why, says_because ? " " : "",
                    says_because ? ambiguity_label(because) : "");
    std::snprintf(text, sizeof text, "%sR%d %.2f%s", i == pick ? "PICK " : "", i, e.score, tail);
    // Beside the centre, moved into the image and off the legend: a pose reaching out of the view
    // has its centre near the image's edge or beyond it.
    // (A centre nearly in the camera's plane projects far out: held to a few images' width first.)
    const auto near_pixel = [&](double v) { return int(std::lround(std::clamp(v, -1e5, 1e5))); };
    const Eigen::Vector2i at = place_label(near_pixel(c.x()) + 12, near_pixel(c.y()) - 16, text, img.width,
                                           img.height, legend_box());
    draw_label(&img, at.x(), at.y(), text, i == pick ? kPick : e.pickable ? kOutline : kOther);
  }
  draw_view_edges(&img, out.view);
  draw_legend(&img);
  return img;
}

Image<Rgb> draw_pose_overlay(const Image<float>& depth, const CameraInfo& cam, const LocatorModel& lm,
                             const Pose& model_to_cam, const std::string& caption) {
  Image<Rgb> img = grey_depth(depth);
  Image<float> scratch(depth.width, depth.height, 0.0f);
  ProjectedMesh projected;
  projected.reserve(lm.model->mesh);
  const PixelBox box =
      render_depth_in_box(lm.model->mesh, model_to_cam, cam.intrinsics, &scratch, &projected);
  draw_outline(&img, lm.model->mesh, model_to_cam, cam.intrinsics, kPick, 3, &scratch, &projected);
  draw_cross(&img, cam.intrinsics.project(model_to_cam * lm.centroid.cast<double>()), kPick);
  draw_label(&img, 6, 6, caption, kPick);
  draw_label(&img, 6, 22, "RED: THE POSE AND ITS CENTRE", kPick);
  if (box.empty()) return img;
  // An inset at the bottom right: the pose's surroundings, near bright and far dark over their
  // own depths, enlarged, so a small or far pipe shows against what lies around it.
  const int margin = std::max(8, (box.x1 - box.x0 + box.y1 - box.y0) / 2);
  const int x0 = std::max(0, box.x0 - margin), y0 = std::max(0, box.y0 - margin);
  const int x1 = std::min(depth.width - 1, box.x1 + margin), y1 = std::min(depth.height - 1, box.y1 + margin);
  const int w = x1 - x0 + 1, h = y1 - y0 + 1;
  const int scale = std::clamp(std::min(depth.width / 3 / w, depth.height / 3 / h), 1, 8);
  Image<float> around(w, h, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) around.at(x, y) = depth.at(x0 + x, y0 + y);
  const Image<Rgb> local = shade_depth(around, DepthShade::grey);
  const int ox = depth.width - w * scale - 6, oy = depth.height - h * scale - 6;
  if (ox < 0 || oy < 30) return img;  // the pose fills the view: the frame itself shows it
  for (int y = -1; y <= h * scale; ++y)
    for (int x = -1; x <= w * scale; ++x) {
      Rgb c = kPick;  // the inset's frame
      if (x >= 0 && y >= 0 && x < w * scale && y < h * scale) {
        const int sx = x / scale, sy = y / scale, fx = x0 + sx, fy = y0 + sy;
        const bool edge =
            fx >= box.x0 && fx <= box.x1 && fy >= box.y0 && fy <= box.y1 && on_outline(scratch, box, fx, fy);
        c = edge ? kPick : local.at(sx, sy);
      }
      if (img.inside(ox + x, oy + y)) img.at(ox + x, oy + y) = c;
    }
  char zoom[32];
  std::snprintf(zoom, sizeof zoom, "AROUND THE POSE X%d, NEAR BRIGHT", scale);
  const Eigen::Vector2i at = place_label(ox, oy - 16, zoom, img.width, img.height, PixelBox{});
  draw_label(&img, at.x(), at.y(), zoom, kPick);
  return img;
}

}  // namespace pipeloc
