// The integrator's picture of one frame: what the camera saw and what the localizer found.
#pragma once

#include "locate/locator.hpp"
#include "render/overlay.hpp"

namespace pipeloc {

// Depth shaded in grey; candidate regions purple with blue cores; estimated axes orange;
// Z-ridges green; the model's outline at each accepted pose (yellow; grey if not pickable);
// the pick in red with a cross at its centre.
Image<Rgb> draw_locate_overlay(const Locator& locator, const Image<float>& depth_mm,
                               const CameraInfo& camera);

}  // namespace pipeloc
