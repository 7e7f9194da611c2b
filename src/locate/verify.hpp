// Beyond the paper: does the depth image confirm the model at a pose? The model is drawn into
// the camera image and compared pixel by pixel with what the sensor measured.
#pragma once

#include <algorithm>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/pose.hpp"
#include "locate/locate_config.hpp"
#include "locate/zbuffer.hpp"
#include "model/mesh.hpp"
#include "render/raster.hpp"

namespace pipeloc {

struct Verification {
  int model_px = 0;       // pixels the model covers in the image, less its one-pixel rim
  int agree_px = 0;       // measured depth within tolerance of the model
  int free_space_px = 0;  // measured farther: the sensor saw through where the model would be
  int inner_px = 0;       // model pixels farther than the free-space band from the rim ...
  int inner_free_space_px = 0;  // ... and those of them the sensor saw through
  int occluded_px = 0;    // measured nearer: something lies in front (another pipe, or the pose sank in)
  int unread_px = 0;      // no reading (a sensor's shadow, a specular hole): neither for nor against
  float agreement() const { return model_px ? float(agree_px) / float(model_px) : 0.f; }
  float unread() const { return model_px ? float(unread_px) / float(model_px) : 0.f; }
  // The agreement over the pixels the sensor read (with in_front_left_out, only those where nothing
  // lies in front), at least min_read_share of the model's counted (1: every pixel counts, as
  // agreement()).
  float read_agreement(float min_read_share, bool in_front_left_out = false) const {
    const int left_out = unread_px + (in_front_left_out ? occluded_px : 0);
    const float counted = std::max(float(model_px - left_out), min_read_share * float(model_px));
    return counted > 0 ? float(agree_px) / counted : 0.f;
  }
  float free_space() const { return model_px ? float(free_space_px) / float(model_px) : 1.f; }
  // What the free-space check judges: a right pose a little to the side, or a sensor blending
  // fore- and background at the edge, sees through the model in the band; not inside it. A
  // silhouette too thin to have inner pixels is judged on all of them.
  float inner_free_space() const {
    return inner_px ? float(inner_free_space_px) / float(inner_px) : free_space();
  }
  float occluded() const { return model_px ? float(occluded_px) / float(model_px) : 1.f; }
  // Just beyond the silhouette: a pipe's sides drop away from it (to the pipes beneath or the
  // floor); the surface of a smooth blob goes on at the silhouette's depth.
  int side_px = 0;        // pixels a few steps outside the silhouette with a reading not in front
  int side_level_px = 0;  // ... whose depth lies within the drop of the silhouette's
  // The level share, counted out of at least `out_of` side pixels (a few read say little).
  float side_level(int out_of = 1) const {
    return float(side_level_px) / float(std::max(side_px, std::max(out_of, 1)));
  }
  float below_floor = 0;  // share of the model more than kBelowFloorOfD * D under the lowest surface seen
  float outside_view = 0;  // share of the model's vertices outside the image: seen nowhere
  // A square of the silhouette, hole_side_px wide, that the sensor saw through entirely: the pipe
  // cannot be there (a pose across a gap, over the hole of a loop).
  bool seen_through_patch = false;
  PixelBox box;            // the pixels the model was drawn in (the scratch image holds its depths)
  // The tube's two ends (judge_ends): pinned where the image shows it ends there (the surface
  // beyond lies lower), continued where the tube's surface goes on beyond it (a pose slid along
  // the pipe); neither where nothing is seen there (out of view, no reading, something in front).
  int ends_pinned = 0, ends_continued = 0;
  // ... of the pinned ends, those seen ending outright: the tip shown and every probe beyond it
  // read, lower (with tip_must_show every pinned end whose probes all read).
  int ends_seen_ending = 0;
  // ... and those seen ending but for the sensor's shadow: the tip shown, the first probe beyond it
  // reading nothing and the second lower. A raised end casts the sensor's shadow on what lies
  // beyond it; the first probe (0.75 D past the tip) can fall in it, while a pose slid past the
  // end, over the shadow, reads both probes lower (place_slides_finely and the hand-out order
  // count these ends, with those seen ending outright: ends_shown_ending()).
  int ends_ending_past_shadow = 0;
  int ends_shown_ending() const { return ends_seen_ending + ends_ending_past_shadow; }
  // ... and those pinned by the probe read further along the bend alone (EndReading::read_further):
  // nothing was read between the tip and it, where the tube may go on.
  int ends_pinned_further = 0;
  // ... and the ends whose tip, or what lies just beyond it, is outside the sensor's view: the
  // image cannot show them.
  int ends_out_of_view = 0;
  // The part of the tube in the sensor's view slides along the pipe (judge_part_in_view): only an
  // end the image shows places the pose along it.
  bool part_in_view_slides = false;
};

// A pose is under the floor when more than this share of its model lies more than this * D below
// the lowest surface seen (a third of a tube sunk to its axis); a blob when its sides do not drop
// away (its level side pixels counted out of at least this many).
constexpr float kMaxShareBelowFloor = 0.3f, kBelowFloorOfD = 0.25f;
constexpr int kMinSidePx = 20;

// Beyond the paper: the pixels the sensor reads. An active sensor reads nothing in a band at an
// edge of its image where its projector (structured light) or its second imager (stereo) does not
// see: a RealSense D4xx's left band is f b / z wide, 38-68 px of 640 on the zoo's frames. The view
// is the image less such bands: the columns and rows at its edges with readings in fewer than
// kMinReadShare of their pixels. A pose's part there is out of the view, as beyond the image's
// edge, not disagreeing. col_reads and row_reads: working memory (resized to the image).
constexpr float kMinReadShare = 0.05f;
PixelBox read_view(const Image<float>& depth_mm, std::vector<int>* col_reads, std::vector<int>* row_reads);

// scratch: camera-sized image whose contents are overwritten in the model's box; projected:
// reserved for the mesh. winding: of the mesh, if closed (its back faces are then not drawn).
// side_drop_mm: how far beyond its silhouette a pipe's surroundings lie at least (a share of D).
// free_band_px: the pixels this close inside the rim are left out of inner_free_space().
// hole_side_px: the side of a square seen through that sets seen_through_patch (0: not looked for).
// view: the pixels the sensor reads (read_view); null: the whole image. The model's pixels outside
// it are not judged, and its vertices there count as outside the view.
Verification verify_pose(const Mesh& mesh, Winding winding, const Pose& model_to_cam,
                         const Image<float>& depth_mm, const Intrinsics& k, float tolerance_mm,
                         float side_drop_mm, int free_band_px, Image<float>* scratch,
                         ProjectedMesh* projected, int hole_side_px = 0, const PixelBox* view = nullptr);

// Beyond the paper: are the tube's ends where the image shows them? Beyond each end of the
// centreline (model frame, ordered from one end to the other; tube diameter d_mm), the surface a
// continued tube would show the camera is compared with the depth measured there: farther than
// tolerance_mm is an end the image pins, within it a tube going on. Fills ends_pinned,
// ends_continued, ends_seen_ending and ends_pinned_further of *v, read as `how` says, and
// ends_out_of_view: the ends whose tip, or the nearer probe beyond it, lies outside `view` (the
// sensor's view, read_view(); the whole image where null).
struct EndReading {
  // An end is pinned only where nothing lies in front of the tube at its tip and half a diameter
  // inside it: an end hidden under another pipe is not shown ending there, whatever lies beyond.
  bool tip_must_show = false;
  // An end whose two probes read nothing of the way on (no reading, something in front) is read
  // once more, 2 D beyond along the bend its centreline's last D lies on; pinned or continued by
  // that probe alone, it is not seen ending outright.
  bool read_further = false;
  // Beyond the paper: the tip of an end the tube reaches at a slant to the image (a 3-D pipe's leg
  // coming down to the floor) is read where such a tube shows the camera its surface: along the
  // camera's ray through its centreline, D / 2 over the cosine of its slant from it (read D / 2
  // from it, the tube's own top in front hides a tip the image shows).
  bool slanted = false;
  // Beyond the paper: where the nearer probe beyond a tip shows the pose's own tube (a leg slanting
  // steeply away from the camera hides what lies just beyond its tip behind its own end), both
  // probes move out together, D / 4 at a time, up to 1.5 D; a tip whose probes show its own tube
  // that far has no reading beyond it.
  bool past_itself = false;
};
void judge_ends(const std::vector<Eigen::Vector3f>& centreline, float d_mm, const Pose& model_to_cam,
                const Image<float>& depth_mm, const Intrinsics& k, float tolerance_mm, Verification* v,
                const EndReading& how = {}, const PixelBox* view = nullptr);
// Beyond the paper: does the part of a pipe the sensor sees slide along the pipe? A pose reaching
// out of the view is placed by what is in view: its bends where they are, or its ends. Where the
// centreline's part in view (`view`: read_view(); the whole image where null) moves onto the
// centreline slide_mm further along it, either way, as a rigid motion that leaves it within one
// pixel's footprint there (RMS; at least the share of D a model's own slides land within,
// model/slides.hpp), a pose slid so looks the same in the view: an arc's or a coil's loop running
// out of the image, whatever the pipe does beyond. Sets part_in_view_slides of *v; false for a
// pose wholly in the view (the model's own slides judge it). step_mm: the centreline's spacing.
void judge_part_in_view(const std::vector<Eigen::Vector3f>& centreline, float step_mm, float d_mm,
                        float slide_mm, const Pose& model_to_cam, const Intrinsics& k, Verification* v,
                        const PixelBox* view);
// Beyond the paper: the other parts of the pipe its part in view could be. The centreline's part
// in view (as judge_part_in_view) moved, as a rigid motion, onto as many points elsewhere along it
// (at least least_shift_mm further, or run backwards), all but a tenth of them landing on it,
// within within_mm (RMS): an S's other bend where one bend is in view, a U's other leg. Writes at
// most `most` such motions (model frame; the pose model_to_cam * motion.inverse() shows that other
// part where this one is seen), the nearest fits first, a D apart along the centreline; returns
// how many. None for a pose wholly in the view.
int other_parts_in_view(const std::vector<Eigen::Vector3f>& centreline, float step_mm, float d_mm,
                        float least_shift_mm, float within_mm, const Pose& model_to_cam, const Intrinsics& k,
                        const PixelBox* view, Pose* motions, int most);
// Whether judge_ends can tell two poses of one centreline (model frame, tube diameter d_mm) apart:
// with their ends paired so that they lie closest, an end of one lies farther from the other's
// than the first probe beyond an end reaches. Nearer, both poses' probes read beyond the same end
// of the pipe, and what they read speaks for neither: a near twin whose legs differ by a third of
// D is then told from the pipe by the noise of one pixel (docs/experiments.md).
bool ends_tell_apart(const std::vector<Eigen::Vector3f>& centreline, float d_mm, const Pose& a,
                     const Pose& b);
// How many ends of pose a of a centreline (model frame, tube diameter d_mm) lie within the first
// probe's reach of an end of pose b: what judge_ends reads at such an end speaks for both poses.
int ends_shared(const std::vector<Eigen::Vector3f>& centreline, float d_mm, const Pose& a, const Pose& b);
// Beyond the paper: two poses told apart by the image. Where their renders (depth in each box,
// 0 where not drawn) differ by more than tolerance_mm, each pixel speaks for the pose whose
// surface the sensor measured there, or against one it saw through; rims are left out (lateral
// noise), so are pixels without a reading or with something in front of both.
struct TellingPixels {
  int for_a = 0, for_b = 0;
};
TellingPixels tell_apart(const Image<float>& a_mm, const PixelBox& box_a, const Image<float>& b_mm,
                         const PixelBox& box_b, const Image<float>& depth_mm, float tolerance_mm);

// Beyond the paper: the bin. The lowest surface the frame shows (the floor where it is seen, else
// the lowest pipes), as the height under which `share` of the Z-buffer's valid cells lie;
// histogram: working memory (1 mm bins). NaN when the buffer is empty.
float lowest_surface_z(const ZBuffer& zb, float share, std::vector<int>* histogram);

// The share of the mesh's vertices that lie lower than z_mm in the bin frame.
float share_below(const Mesh& mesh, const Pose& model_to_bin, float z_mm);

}  // namespace pipeloc
