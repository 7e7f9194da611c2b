#include "locate/verify.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>

#include "locate/rigid_fit.hpp"
#include "model/slides.hpp"

namespace pipeloc {
namespace {

// The sides are read this many pixels beyond the silhouette: the pixel next to it mixes pipe and
// background (lateral noise).
constexpr int kSideStepPx = 2;
// Where beyond a tube's end the image is read (shares of D along the centreline's direction).
constexpr float kEndProbesOfD[] = {0.75f, 1.25f};
// ... and the tube's own surface at its tip and this far inside it (EndReading::tip_must_show).
constexpr float kTipProbesOfD[] = {0.0f, 0.5f};
// With read_further, where neither of those probes reads the way the tube would go on, one more
// this far beyond (shares of D), along the bend the centreline's last D lies on ...
constexpr float kFurtherProbeOfD = 2.0f;
// ... taken as straight where it bends on a circle wider than this many D.
constexpr float kStraightBendOfD = 20.0f;
// judge_part_in_view fits at most this many centreline points in view (fixed buffers).
constexpr int kMaxPartPoints = 256;
// other_parts_in_view keeps at most this many placements.
constexpr int kMaxOtherParts = 4;
// With past_itself, the probes beyond a tip move out this far at a time (shares of D) while the
// nearer one shows the pose's own tube, at most this far in all.
constexpr float kProbeShiftOfD = 0.25f;
constexpr float kMostProbeShiftOfD = 1.5f;
// With slanted, a tube's surface along the camera's ray is read at most 1 / this root farther from
// its centreline than D / 2 (as a tube slanted 60 degrees to the image).
constexpr float kLeastCosineSquared = 0.25f;

// The pixels the sensor reads (read_view()), or the whole image where none is given.
PixelBox view_or_image(const PixelBox* view, int width, int height) {
  return view ? *view : PixelBox{0, 0, width - 1, height - 1};
}

// The image point (x, y) lies in `view` (each pixel's whole area: up to x1 + 1).
bool in_view(const PixelBox& view, double x, double y) {
  return x >= view.x0 && y >= view.y0 && x < view.x1 + 1 && y < view.y1 + 1;
}

// The point p (camera frame) lies in front of the camera and projects into `view`.
bool point_in_view(const PixelBox& view, const Intrinsics& k, const Eigen::Vector3d& p) {
  const Eigen::Vector2d px = k.project(p);
  return p.z() > 0 && in_view(view, px.x(), px.y());
}

// Where the centreline, going on beyond its point `end` as it bends on the circle through the
// points `in`, `mid` and `end`, lies `s_mm` beyond it (model frame; a straight line where the
// three are (nearly) in line).
Eigen::Vector3f along_the_bend(const Eigen::Vector3f& in, const Eigen::Vector3f& mid,
                               const Eigen::Vector3f& end, float s_mm, float d) {
  const Eigen::Vector3f ab = mid - in, ac = end - in, normal = ab.cross(ac);
  const float n2 = normal.squaredNorm();
  if (n2 > 0) {
    const Eigen::Vector3f centre =
        in + (ac.squaredNorm() * normal.cross(ab) + ab.squaredNorm() * ac.cross(normal)) / (2 * n2);
    const float radius = (end - centre).norm();
    if (radius > 0 && radius < kStraightBendOfD * d) {
      const Eigen::Vector3f axis = (in - centre).cross(end - centre).normalized();
      return centre + Eigen::AngleAxisf(s_mm / radius, axis) * (end - centre);
    }
  }
  return end + s_mm * ac.normalized();
}

// The depth a render drew at (x, y): its image within the box it was drawn in; 0 elsewhere.
float drawn_mm(const Image<float>& render, const PixelBox& box, int x, int y) {
  const bool in_box = x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1;
  return in_box && render.at(x, y) > 0 ? render.at(x, y) : 0.f;
}

}  // namespace

PixelBox read_view(const Image<float>& depth, std::vector<int>* col_reads, std::vector<int>* row_reads) {
  col_reads->assign(std::size_t(depth.width), 0);
  row_reads->assign(std::size_t(depth.height), 0);
  for (int y = 0; y < depth.height; ++y)
    for (int x = 0; x < depth.width; ++x) {
      const bool read = depth.at(x, y) > 0;
      (*col_reads)[std::size_t(x)] += read, (*row_reads)[std::size_t(y)] += read;
    }
  const auto read_enough = [](int reads, int of) { return float(reads) >= kMinReadShare * float(of); };
  PixelBox view{0, 0, depth.width - 1, depth.height - 1};
  while (view.x0 <= view.x1 && !read_enough((*col_reads)[std::size_t(view.x0)], depth.height)) ++view.x0;
  while (view.x1 >= view.x0 && !read_enough((*col_reads)[std::size_t(view.x1)], depth.height)) --view.x1;
  while (view.y0 <= view.y1 && !read_enough((*row_reads)[std::size_t(view.y0)], depth.width)) ++view.y0;
  while (view.y1 >= view.y0 && !read_enough((*row_reads)[std::size_t(view.y1)], depth.width)) --view.y1;
  return view;
}

Verification verify_pose(const Mesh& mesh, Winding winding, const Pose& model_to_cam,
                         const Image<float>& depth, const Intrinsics& k, float tol, float side_drop_mm,
                         int free_band_px, Image<float>* scratch, ProjectedMesh* projected, int hole_side_px,
                         const PixelBox* view) {
  Verification v;
  v.box = render_depth_in_box(mesh, model_to_cam, k, scratch, projected, winding);
  const PixelBox& box = v.box;
  const PixelBox seen = view_or_image(view, k.width, k.height);
  int outside = 0;
  for (std::size_t i = 0; i < mesh.vertices.size() && projected->cam.size() >= mesh.vertices.size(); ++i)
    outside += !(projected->cam[i].z() > 0 && in_view(seen, projected->px[i].x(), projected->px[i].y()));
  v.outside_view = mesh.vertices.empty() ? 0.f : float(outside) / float(mesh.vertices.size());
  const auto model_at = [&](int x, int y) { return drawn_mm(*scratch, box, x, y) > 0; };
  // A side pixel: beyond the rim at (x, y) in direction (dx, dy), not on the model; beyond the
  // free-space band too, so that a pose a band's width to the side does not read its own pipe.
  const int side_step = std::max(kSideStepPx, free_band_px + 1);
  const auto side = [&](int x, int y, int dx, int dy, float zm) {
    const int xs = x + side_step * dx, ys = y + side_step * dy;
    if (!depth.inside(xs, ys) || model_at(xs, ys)) return;
    const float zo = depth.at(xs, ys);
    if (!(zo > 0) || zo < zm - tol) return;  // no reading, or something in front: neither
    ++v.side_px;
    v.side_level_px += zo <= zm + side_drop_mm;
  };
  // An inner pixel: the model goes on for the rim and the band in each of the four directions.
  const auto inner = [&](int x, int y) {
    for (int s = 2; s <= 1 + free_band_px; ++s)
      if (!model_at(x - s, y) || !model_at(x + s, y) || !model_at(x, y - s) || !model_at(x, y + s)) return false;
    return true;
  };
  for (int y = box.y0; y <= box.y1; ++y) {
    const auto [from, to] = projected->drawn_columns(box, y, scratch->height);
    for (int x = from; x <= to; ++x) {
      const float zm = scratch->at(x, y);
      if (zm <= 0 || !in_view(seen, x, y)) continue;
      // The silhouette's rim is left out: lateral noise mixes it with the background. Beyond it
      // the sides are read (the rim is rare: the interior takes the short test).
      if (x == box.x0 || y == box.y0 || x == box.x1 || y == box.y1 || scratch->at(x - 1, y) <= 0 ||
          scratch->at(x + 1, y) <= 0 || scratch->at(x, y - 1) <= 0 || scratch->at(x, y + 1) <= 0) {
        if (!model_at(x - 1, y)) side(x, y, -1, 0, zm);
        if (!model_at(x + 1, y)) side(x, y, 1, 0, zm);
        if (!model_at(x, y - 1)) side(x, y, 0, -1, zm);
        if (!model_at(x, y + 1)) side(x, y, 0, 1, zm);
        continue;
      }
      ++v.model_px;
      const bool judged_for_free_space = inner(x, y);
      v.inner_px += judged_for_free_space;
      const float zo = depth.at(x, y);
      if (!(zo > 0)) {  // no reading: neither for nor against
        ++v.unread_px;
        continue;
      }
      if (zo > zm + tol) {
        ++v.free_space_px;
        v.inner_free_space_px += judged_for_free_space;
      }
      else if (zo < zm - tol)
        ++v.occluded_px;
      else
        ++v.agree_px;
    }
  }
  // Beyond the paper: free space is judged as a share, and a pose across a gap (the hole of a
  // coil's loop, the space between two pipes) sees through a small share of its pixels, but all
  // of them in one place. A square hole_side_px wide seen through entirely rules the pipe out
  // there; right poses see through scattered pixels and strips along their rims. Skipped where
  // fewer pixels inside the rim were seen through than the square holds.
  if (hole_side_px > 0 && v.free_space_px >= hole_side_px * hole_side_px) {
    const auto seen_through = [&](int x, int y) {
      if (x > box.x1 || y > box.y1) return false;
      const float zm = scratch->at(x, y), zo = depth.at(x, y);
      return zm > 0 && zo > zm + tol;
    };
    for (int y = box.y0; y <= box.y1 && !v.seen_through_patch; ++y) {
      const auto [from, to] = projected->drawn_columns(box, y, scratch->height);
      for (int x = from; x <= to && !v.seen_through_patch; ++x) {
        if (!seen_through(x, y)) continue;
        bool all = true;
        for (int dy = 0; dy < hole_side_px && all; ++dy)
          for (int dx = 0; dx < hole_side_px && all; ++dx) all = seen_through(x + dx, y + dy);
        v.seen_through_patch = all;
      }
    }
  }
  return v;
}

void judge_ends(const std::vector<Eigen::Vector3f>& centreline, float d, const Pose& model_to_cam,
                const Image<float>& depth, const Intrinsics& k, float tol, Verification* v,
                const EndReading& how, const PixelBox* view) {
  v->ends_pinned = v->ends_continued = v->ends_seen_ending = v->ends_pinned_further = v->ends_out_of_view = 0;
  v->ends_ending_past_shadow = 0;
  const PixelBox seen = view_or_image(view, depth.width, depth.height);
  const int n = int(centreline.size());
  if (n < 2) return;
  const Eigen::Matrix3f r = model_to_cam.linear().cast<float>();
  const Eigen::Vector3f t = model_to_cam.translation().cast<float>();
  for (int e = 0; e < 2; ++e) {
    const int end = e == 0 ? 0 : n - 1, step = e == 0 ? 1 : -1;
    // The first centreline point at least `dist` from the end (or the other end).
    const auto inward = [&](float dist) {
      int i = end;
      while (i + step >= 0 && i + step < n && (centreline[i] - centreline[end]).norm() < dist) i += step;
      return i;
    };
    // The way out of the tube at this end: from the centreline point about D inside it.
    const int in = inward(d);
    const Eigen::Vector3f tip = r * centreline[end] + t;
    // Where the tube's surface around the centreline point `centre`, `surface_mm` from it, faces
    // the camera.
    const auto facing_of = [](const Eigen::Vector3f& centre, float surface_mm) {
      return Eigen::Vector3f(centre - surface_mm * centre.normalized());
    };
    Eigen::Vector3f out = r * (centreline[end] - centreline[in]);
    const bool way_out = out.norm() > 0.25f * d;
    if (way_out) out.normalize();
    // The end lies in the view where its tip does and so does the point its nearer probe reads
    // (the surface a tube going on would show there); else it counts as out of the view.
    const auto seen_at = [&](const Eigen::Vector3f& p) { return point_in_view(seen, k, p.cast<double>()); };
    const bool end_in_view =
        seen_at(tip) && (!way_out || seen_at(facing_of(tip + kEndProbesOfD[0] * d * out, 0.5f * d)));
    v->ends_out_of_view += !end_in_view;
    // What lies beyond a tip the image cannot show neither pins the end nor shows it going on: a
    // coil's loop at the image's edge, both tips out of the view, was pinned by the floor beyond
    // one and handed out 82 mm from its pipe (18-coil of seed 21, six bins). Nor does what lies
    // beyond a tip just inside the view's edge, its way on out of the view (counted in the view,
    // such ends withheld pipes as NO END: twelve bins of every shape of the four draws take 15
    // more pipes by the first DONE_NONE, docs/experiments.md).
    if (!end_in_view || !way_out) continue;
    // How far from the centreline the tube shows the camera its surface at its tip: D / 2, or with
    // slanted, D / 2 over the cosine of its slant to the image there. (Beyond the tip, where a tube
    // going on would lie, it is read D / 2 from the line: a pin needs the surface there lower than
    // a level tube's, however the pose slants.)
    const float sine =
        how.slanted && tip.z() > 0 ? std::min(std::abs(out.dot(tip.normalized())), 1.0f) : 0.0f;
    const float tip_surface_mm = 0.5f * d / std::sqrt(std::max(1.0f - sine * sine, kLeastCosineSquared));
    // The depth measured where the surface around `centre` faces the camera, and that surface's
    // depth; no reading: 0.
    const auto probe_at = [&](const Eigen::Vector3f& centre, float surface_mm, float* facing_z) {
      if (!(centre.z() > 0)) return 0.0f;
      const Eigen::Vector3f facing = facing_of(centre, surface_mm);
      const Eigen::Vector2d px = k.project(facing.cast<double>());
      const int x = int(std::lround(px.x())), y = int(std::lround(px.y()));
      *facing_z = facing.z();
      return depth.inside(x, y) ? depth.at(x, y) : 0.0f;
    };
    // ... `along` * D beyond the tip along the tube's way out (inside it where negative).
    const auto probe = [&](float along, float* facing_z) {
      return probe_at(tip + along * d * out, along > 0 ? 0.5f * d : tip_surface_mm, facing_z);
    };
    // Does the pixel of a facing point (camera frame) show the pose's own tube? It does where its
    // ray passes within D / 2 and half a pixel's footprint of a centreline segment lying no
    // farther than where a tube going on would show its surface (past_itself).
    const auto shows_itself = [&](const Eigen::Vector3f& facing) {
      if (!(facing.z() > 0)) return false;
      const Eigen::Vector3f u = facing.normalized();
      const float reach = 0.5f * d + 0.5f * facing.z() / float(k.fx);
      const auto near = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
        // The segment's nearest point to the ray, across it (the ray through the origin).
        const Eigen::Vector3f a_across = a - a.dot(u) * u, ab_across = (b - a) - (b - a).dot(u) * u;
        const float len2 = ab_across.squaredNorm();
        const float s = len2 > 0 ? std::clamp(-a_across.dot(ab_across) / len2, 0.0f, 1.0f) : 0.0f;
        const float surface_z = (a + s * (b - a)).z() - 0.5f * d;
        return (a_across + s * ab_across).norm() < reach && surface_z < facing.z() + tol;
      };
      Eigen::Vector3f a = r * centreline[0] + t;
      for (int i = 1; i < n; ++i) {
        const Eigen::Vector3f b = r * centreline[i] + t;
        if (near(a, b)) return true;
        a = b;
      }
      return false;
    };
    float shift = 0;
    while (how.past_itself && shift <= kMostProbeShiftOfD &&
           shows_itself(facing_of(tip + (kEndProbesOfD[0] + shift) * d * out, 0.5f * d)))
      shift += kProbeShiftOfD;
    const bool only_itself = shift > kMostProbeShiftOfD;
    int free = 0, going_on = 0, probes = 0;
    bool first_unread = false;  // the first probe beyond the tip read nothing
    const auto read = [&](float zo, float facing_z) {
      if (!(zo > 0) || zo < facing_z - tol) return;  // no reading, or something in front
      ++probes;
      free += zo > facing_z + tol;
      going_on += zo <= facing_z + tol;
    };
    for (const float beyond : kEndProbesOfD) {
      if (only_itself) break;
      float facing_z = 0;
      const float zo = probe(beyond + shift, &facing_z);
      if (beyond == kEndProbesOfD[0]) first_unread = !(zo > 0);
      read(zo, facing_z);
    }
    // Beyond the paper: a pipe that slides along itself is placed by its ends alone. Where both
    // probes read nothing of the way on (a coil's end tucked under its own next turn, in the
    // shadow of it), the image is read once more, further along the bend the tube would follow
    // (a coil lying alone on the zoo's bin floor, neither end read, was left ambiguous:
    // docs/experiments.md, "A sliding pipe's end read further along its bend").
    bool further_only = false;
    if (probes == 0 && how.read_further) {
      const Eigen::Vector3f beyond = along_the_bend(centreline[in], centreline[inward(0.5f * d)],
                                                    centreline[end], kFurtherProbeOfD * d, d);
      float facing_z = 0;
      const float zo = probe_at(r * beyond + t, 0.5f * d, &facing_z);
      read(zo, facing_z);
      further_only = probes > 0;
    }
    if (probes == 0) continue;
    bool tip_hidden = false;
    for (const float inside : kTipProbesOfD) {
      float facing_z = 0;
      const float zo = probe(-inside, &facing_z);
      tip_hidden = tip_hidden || (zo > 0 && zo < facing_z - tol);
    }
    const bool pinned = free == probes && !(how.tip_must_show && tip_hidden);
    v->ends_pinned += pinned;
    // Pinned with its tip shown by the probes beyond it: seen ending where every one of them
    // read, seen ending but for the shadow where only the first read nothing.
    const bool shown_ending = pinned && !tip_hidden && !further_only;
    v->ends_seen_ending += shown_ending && probes == int(std::size(kEndProbesOfD));
    v->ends_ending_past_shadow += shown_ending && first_unread && probes == 1;
    v->ends_pinned_further += pinned && further_only;
    v->ends_continued += going_on == probes;
  }
}

namespace {

// The centreline's points in the sensor's view (every stride-th of them where there are more
// than kMaxPartPoints: a model's centreline has about 64): their indices, how many lie in view in
// all and their mean depth.
struct PartInView {
  std::array<int, kMaxPartPoints> index;
  int count = 0, in_view = 0, stride = 1;
  double mean_z_mm = 0;
};
void centreline_in_view(const std::vector<Eigen::Vector3f>& centreline, const Pose& model_to_cam,
                        const Intrinsics& k, const PixelBox* view, PartInView* part) {
  const int n = int(centreline.size());
  const PixelBox seen = view_or_image(view, k.width, k.height);
  part->stride = (n + kMaxPartPoints - 1) / kMaxPartPoints;
  part->count = part->in_view = 0;
  double z_sum = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = model_to_cam * centreline[std::size_t(i)].cast<double>();
    if (!point_in_view(seen, k, p)) continue;
    ++part->in_view, z_sum += p.z();
    if (i % part->stride == 0) part->index[std::size_t(part->count++)] = i;
  }
  part->mean_z_mm = part->in_view > 0 ? z_sum / part->in_view : 0;
}

// The rigid motion taking the points of the part in view onto those `sign` * i + offset along the
// centreline (those falling off its ends left out), and the RMS distance it leaves them at.
// Returns the pairs fitted.
int part_moved(const std::vector<Eigen::Vector3f>& centreline, const PartInView& part, int sign, int offset,
               Pose* motion, double* rms_mm) {
  const int n = int(centreline.size());
  std::array<Eigen::Vector3f, kMaxPartPoints> from, to;
  int pairs = 0;
  for (int c = 0; c < part.count; ++c) {
    const int j = sign * part.index[std::size_t(c)] + offset;
    if (j < 0 || j >= n) continue;
    from[std::size_t(pairs)] = centreline[std::size_t(part.index[std::size_t(c)])];
    to[std::size_t(pairs++)] = centreline[std::size_t(j)];
  }
  if (pairs < 3) return pairs;
  *motion = fit_rigid(from.data(), to.data(), pairs);
  double sq = 0;
  for (int c = 0; c < pairs; ++c)
    sq += (*motion * from[std::size_t(c)].cast<double>() - to[std::size_t(c)].cast<double>()).squaredNorm();
  *rms_mm = std::sqrt(sq / pairs);
  return pairs;
}

}  // namespace

void judge_part_in_view(const std::vector<Eigen::Vector3f>& centreline, float step_mm, float d,
                        float slide_mm, const Pose& model_to_cam, const Intrinsics& k, Verification* v,
                        const PixelBox* view) {
  v->part_in_view_slides = false;
  const int n = int(centreline.size());
  if (n < 4 || !(step_mm > 0)) return;
  PartInView part;
  centreline_in_view(centreline, model_to_cam, k, view, &part);
  if (part.in_view == n || part.in_view < 3) return;
  const double within_mm = std::max(double(kSlideCentrelineRmsOfD * d), part.mean_z_mm / k.fx);
  const int shift = std::max(1, int(std::lround(slide_mm / step_mm)));
  for (const int sign : {1, -1}) {
    // The rigid motion taking each point in view onto the point `shift` along, and how far it
    // leaves them.
    Pose m;
    double rms_mm = 0;
    if (part_moved(centreline, part, 1, sign * shift, &m, &rms_mm) >= 3 && rms_mm <= within_mm) {
      v->part_in_view_slides = true;
      return;
    }
  }
}

int other_parts_in_view(const std::vector<Eigen::Vector3f>& centreline, float step_mm, float d,
                        float least_shift_mm, float within_mm, const Pose& model_to_cam, const Intrinsics& k,
                        const PixelBox* view, Pose* motions, int most) {
  const int n = int(centreline.size());
  if (n < 4 || !(step_mm > 0) || most < 1) return 0;
  PartInView part;
  centreline_in_view(centreline, model_to_cam, k, view, &part);
  if (part.in_view == n || part.in_view < 3) return 0;
  // Every placement of the part further along the centreline, or run backwards, that keeps all
  // but a tenth of its points on it; the nearest fits first, each at least D (in steps) from the
  // ones kept before it.
  const int least_pairs = std::max(3, part.count - std::max(1, part.count / 10));
  const int least_shift = std::max(1, int(std::lround(least_shift_mm / step_mm)));
  const int apart = std::max(1, int(std::lround(d / step_mm)));
  const int cap = std::min(most, kMaxOtherParts);
  int kept = 0;
  std::array<int, kMaxOtherParts> kept_sign{}, kept_offset{};
  std::array<double, kMaxOtherParts> kept_rms{};
  for (const int sign : {1, -1}) {
    for (int offset = sign > 0 ? -(n - 1) : 0; offset <= (sign > 0 ? n - 1 : 2 * (n - 1)); ++offset) {
      if (sign > 0 && std::abs(offset) < least_shift) continue;  // the part slid along itself
      Pose m;
      double rms_mm = 0;
      if (part_moved(centreline, part, sign, offset, &m, &rms_mm) < least_pairs || !(rms_mm <= within_mm))
        continue;
      // Where it lies near one kept, the better of the two stays; where the list is full, it
      // takes the worst one's place if better.
      const auto keep = [&](int q) {
        kept_sign[std::size_t(q)] = sign, kept_offset[std::size_t(q)] = offset;
        kept_rms[std::size_t(q)] = rms_mm, motions[q] = m;
      };
      int near = -1;
      for (int q = 0; q < kept && near < 0; ++q)
        if (kept_sign[std::size_t(q)] == sign && std::abs(kept_offset[std::size_t(q)] - offset) < apart)
          near = q;
      if (near >= 0) {
        if (rms_mm < kept_rms[std::size_t(near)]) keep(near);
      } else if (kept < cap) {
        keep(kept++);
      } else {
        int worst = 0;
        for (int q = 1; q < kept; ++q)
          if (kept_rms[std::size_t(q)] > kept_rms[std::size_t(worst)]) worst = q;
        if (rms_mm < kept_rms[std::size_t(worst)]) keep(worst);
      }
    }
  }
  // The nearest fits first.
  for (int q = 1; q < kept; ++q)
    for (int r = q; r > 0 && kept_rms[std::size_t(r)] < kept_rms[std::size_t(r - 1)]; --r) {
      std::swap(kept_rms[std::size_t(r)], kept_rms[std::size_t(r - 1)]);
      std::swap(motions[r], motions[r - 1]);
    }
  return kept;
}

namespace {
// The centreline's two ends under `pose`.
std::array<Eigen::Vector3d, 2> ends_at(const std::vector<Eigen::Vector3f>& centreline, const Pose& pose) {
  return {pose * centreline.front().cast<double>(), pose * centreline.back().cast<double>()};
}
}  // namespace

bool ends_tell_apart(const std::vector<Eigen::Vector3f>& centreline, float d, const Pose& a, const Pose& b) {
  if (centreline.size() < 2) return true;
  const auto [a0, a1] = ends_at(centreline, a);
  const auto [b0, b1] = ends_at(centreline, b);
  const double paired = std::max((a0 - b0).norm(), (a1 - b1).norm());
  const double swapped = std::max((a0 - b1).norm(), (a1 - b0).norm());
  return std::min(paired, swapped) > double(kEndProbesOfD[0] * d);
}

int ends_shared(const std::vector<Eigen::Vector3f>& centreline, float d, const Pose& a, const Pose& b) {
  if (centreline.size() < 2) return 0;
  const std::array<Eigen::Vector3d, 2> ends_b = ends_at(centreline, b);
  const double reach = double(kEndProbesOfD[0] * d);
  int shared = 0;
  for (const Eigen::Vector3d& p : ends_at(centreline, a))
    shared += (p - ends_b[0]).norm() <= reach || (p - ends_b[1]).norm() <= reach;
  return shared;
}

TellingPixels tell_apart(const Image<float>& a_mm, const PixelBox& box_a, const Image<float>& b_mm,
                         const PixelBox& box_b, const Image<float>& depth, float tol) {
  TellingPixels out;
  const auto on_rim = [](const Image<float>& r, const PixelBox& box, int x, int y) {
    return !(drawn_mm(r, box, x - 1, y) > 0 && drawn_mm(r, box, x + 1, y) > 0 &&
             drawn_mm(r, box, x, y - 1) > 0 && drawn_mm(r, box, x, y + 1) > 0);
  };
  // +1: the sensor measured this render's surface; -1: it saw through it; 0: not drawn, or in front.
  const auto says = [&](float zm, float zo) {
    return zm <= 0 ? 0 : std::abs(zo - zm) <= tol ? 1 : zo > zm + tol ? -1 : 0;
  };
  const int x0 = std::min(box_a.x0, box_b.x0), y0 = std::min(box_a.y0, box_b.y0);
  const int x1 = std::max(box_a.x1, box_b.x1), y1 = std::max(box_a.y1, box_b.y1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const float za = drawn_mm(a_mm, box_a, x, y), zb = drawn_mm(b_mm, box_b, x, y);
      if (za <= 0 && zb <= 0) continue;
      if (za > 0 && zb > 0 && std::abs(za - zb) <= tol) continue;  // both say the same
      if ((za > 0 && on_rim(a_mm, box_a, x, y)) || (zb > 0 && on_rim(b_mm, box_b, x, y))) continue;
      const float zo = depth.at(x, y);
      if (!(zo > 0)) continue;
      const int sa = says(za, zo), sb = says(zb, zo);
      out.for_a += sa > sb;
      out.for_b += sb > sa;
    }
  return out;
}

float lowest_surface_z(const ZBuffer& zb, float share, std::vector<int>* histogram) {
  float lo = INFINITY, hi = -INFINITY;
  int valid = 0;
  for (int k = 0; k < zb.width * zb.height; ++k) {
    const float z = zb.z.pixels[std::size_t(k)];
    if (std::isnan(z)) continue;
    lo = std::min(lo, z), hi = std::max(hi, z);
    ++valid;
  }
  if (valid == 0 || histogram->empty()) return NAN;
  std::fill(histogram->begin(), histogram->end(), 0);
  const int bins = int(histogram->size());
  for (int k = 0; k < zb.width * zb.height; ++k) {
    const float z = zb.z.pixels[std::size_t(k)];
    if (!std::isnan(z)) ++(*histogram)[std::size_t(std::min(bins - 1, int(z - lo)))];
  }
  const int wanted = std::max(1, int(share * float(valid)));
  int seen = 0;
  for (int b = 0; b < bins; ++b)
    if ((seen += (*histogram)[std::size_t(b)]) >= wanted) return lo + float(b);
  return hi;
}

float share_below(const Mesh& mesh, const Pose& model_to_bin, float z_mm) {
  if (mesh.vertices.empty()) return 0;
  int below = 0;
  const Eigen::Matrix3f r = model_to_bin.linear().cast<float>();
  const Eigen::Vector3f t = model_to_bin.translation().cast<float>();
  for (const Eigen::Vector3f& v : mesh.vertices) below += (r * v + t).z() < z_mm;
  return float(below) / float(mesh.vertices.size());
}

}  // namespace pipeloc
