// Beyond the paper: does the depth image confirm the model at a pose? The model is drawn into
// the camera image and compared pixel by pixel with what the sensor measured.
#pragma once

#include "core/camera.hpp"
#include "core/image.hpp"
#include "locate/locate_config.hpp"
#include "model/mesh.hpp"
#include "render/raster.hpp"

namespace pipeloc {

struct Verification {
  int model_px = 0;       // pixels the model covers in the image, less its one-pixel rim
  int agree_px = 0;       // measured depth within tolerance of the model
  int free_space_px = 0;  // measured farther: the sensor saw through where the model would be
  int occluded_px = 0;    // measured nearer: something lies in front (another pipe, or the pose sank in)
  float agreement() const { return model_px ? float(agree_px) / float(model_px) : 0.f; }
  float free_space() const { return model_px ? float(free_space_px) / float(model_px) : 1.f; }
  float occluded() const { return model_px ? float(occluded_px) / float(model_px) : 1.f; }
};

// scratch: camera-sized image whose contents are overwritten in the model's box; projected:
// reserved for the mesh. winding: of the mesh, if closed (its back faces are then not drawn).
Verification verify_pose(const Mesh& mesh, Winding winding, const Pose& model_to_cam,
                         const Image<float>& depth_mm, const Intrinsics& k, float tolerance_mm,
                         Image<float>* scratch, ProjectedMesh* projected);

}  // namespace pipeloc
