#include "locate/verify.hpp"

namespace pipeloc {

Verification verify_pose(const Mesh& mesh, Winding winding, const Pose& model_to_cam,
                         const Image<float>& depth, const Intrinsics& k, float tol, Image<float>* scratch,
                         ProjectedMesh* projected) {
  Verification v;
  const PixelBox box = render_depth_in_box(mesh, model_to_cam, k, scratch, projected, winding);
  for (int y = box.y0; y <= box.y1; ++y)
    for (int x = box.x0; x <= box.x1; ++x) {
      const float zm = scratch->at(x, y);
      if (zm <= 0) continue;
      // The silhouette's rim is left out: lateral noise mixes it with the background.
      if (x == box.x0 || y == box.y0 || x == box.x1 || y == box.y1 || scratch->at(x - 1, y) <= 0 ||
          scratch->at(x + 1, y) <= 0 || scratch->at(x, y - 1) <= 0 || scratch->at(x, y + 1) <= 0)
        continue;
      ++v.model_px;
      const float zo = depth.at(x, y);
      if (!(zo > 0)) continue;  // no reading: neither for nor against
      if (zo > zm + tol)
        ++v.free_space_px;
      else if (zo < zm - tol)
        ++v.occluded_px;
      else
        ++v.agree_px;
    }
  return v;
}

}  // namespace pipeloc
