// The integrator's picture of one frame: what the camera saw and what the localizer found.
#pragma once

#include <string>

#include "locate/locator.hpp"
#include "render/overlay.hpp"

namespace pipeloc {

// Depth shaded in grey; candidate regions purple with blue cores; estimated axes orange;
// Z-ridges green; the model's outline at each accepted pose (yellow; grey if not pickable);
// the pick in red with a cross at its centre.
Image<Rgb> draw_locate_overlay(const Locator& locator, const Image<float>& depth_mm,
                               const CameraInfo& camera);

// One pose on the frame it was found in: the depth greyed, the model's outline at the pose in red
// with a cross at its centre, and a caption at the top left (a pick that took nothing).
Image<Rgb> draw_pose_overlay(const Image<float>& depth_mm, const CameraInfo& camera, const LocatorModel& lm,
                             const Pose& model_to_cam, const std::string& caption);

}  // namespace pipeloc
