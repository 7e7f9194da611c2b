// Beyond the paper: a depth sensor's stray readings taken out before the localizer reads a frame.
// Noise blown up at grazing incidence, or a stereo matcher's outlier, reports a depth no surface
// around it has; its point then stands in the Z-buffer far above (or below) the cells around it:
// the highest cell of a core that the core's length is measured to, or the floor's.
#pragma once

#include "core/image.hpp"

namespace pipeloc {

// The reading's neighbourhood: this many pixels each way (the sensor's lateral noise moves a
// surface's readings by up to a pixel or two; a speckle has no surface this close).
constexpr int kSpeckleReachPx = 2;

// Copies depth_mm into *out (resized to it, no allocation once sized), without the speckles:
// readings nearer or farther than every reading within kSpeckleReachPx by more than step_mm (the
// largest step between neighbours on one surface). A reading between its neighbours (a depth edge,
// a sensor blending the two sides) stays, so does one without neighbours. Returns how many went.
int remove_speckles(const Image<float>& depth_mm, float step_mm, Image<float>* out);

}  // namespace pipeloc
