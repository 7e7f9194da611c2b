// A tube swept along a centreline of straight runs and circular bends.
#pragma once

#include <string>
#include <vector>

#include "core/pose.hpp"
#include "model/mesh.hpp"

namespace pipeloc {

struct CentrelineSegment {
  enum Kind { straight, bend } kind = straight;
  double length_mm = 0;  // straight
  double angle_deg = 0;  // bend: turn angle (negative turns the other way)
  double radius_mm = 0;  // bend: radius of the centreline arc
  double twist_deg = 0;  // bend: rotation of the bend plane about the tangent first
};

struct PipeSpec {
  double diameter_mm = 20;
  std::vector<CentrelineSegment> segments;
  Pose model_frame = Pose::Identity();  // applied to the swept mesh: the frame need not be centred
  int sides = 32;                       // polygon around the tube
  double bend_step_deg = 5;             // ring spacing along bends
};

// Parses "S60,B90r50,S40,B-80r45t120": S<length>, B<angle>r<radius>[t<twist>], mm and degrees.
// Throws ModelError naming the token at fault.
std::vector<CentrelineSegment> parse_centreline(const std::string& text);

// Built-in pipes shaped like the paper's three kinds: "sbend", "u", "torus".
PipeSpec pipe_preset(const std::string& name);

Mesh make_pipe(const PipeSpec& spec);

}  // namespace pipeloc
