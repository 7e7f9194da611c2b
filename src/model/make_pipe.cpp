#include "model/make_pipe.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace pipeloc {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

struct Frame {
  Eigen::Vector3d p, t, n, b;  // position, tangent, bend direction, binormal
};

double parse_number(const std::string& token, const std::string& text, std::size_t* pos) {
  const char* begin = text.c_str() + *pos;
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end == begin || !std::isfinite(value))
    throw ModelError("centreline token '" + token + "': expected a number at '" + std::string(begin) + "'");
  *pos += std::size_t(end - begin);
  return value;
}

// phase: where vertex 0 lies from f.n: a twist of the frame turns it back by as much, so that
// vertex k of one ring and of the next stay side by side (faces along the wall, not across it).
void add_ring(Mesh* mesh, const Frame& f, double radius, int sides, double phase) {
  for (int k = 0; k < sides; ++k) {
    const double a = 2.0 * M_PI * k / sides + phase;
    const Eigen::Vector3d v = f.p + radius * (std::cos(a) * f.n + std::sin(a) * f.b);
    mesh->vertices.push_back(v.cast<float>());
  }
}

void add_cap(Mesh* mesh, const Frame& f, int ring_start, int sides, bool at_start) {
  const int centre = int(mesh->vertices.size());
  mesh->vertices.push_back(f.p.cast<float>());
  for (int k = 0; k < sides; ++k) {
    const int a = ring_start + k, b = ring_start + (k + 1) % sides;
    // Outward: against the tangent at the start, along it at the end.
    if (at_start)
      mesh->faces.push_back({centre, b, a});
    else
      mesh->faces.push_back({centre, a, b});
  }
}

}  // namespace

std::vector<CentrelineSegment> parse_centreline(const std::string& text) {
  std::vector<CentrelineSegment> out;
  std::stringstream ss(text);
  std::string token;
  while (std::getline(ss, token, ',')) {
    if (token.empty()) throw ModelError("centreline '" + text + "': empty segment");
    CentrelineSegment seg;
    std::size_t pos = 1;
    if (token[0] == 'S' || token[0] == 's') {
      seg.kind = CentrelineSegment::straight;
      seg.length_mm = parse_number(token, token, &pos);
      if (seg.length_mm <= 0) throw ModelError("centreline token '" + token + "': length must be > 0");
    } else if (token[0] == 'B' || token[0] == 'b') {
      seg.kind = CentrelineSegment::bend;
      seg.angle_deg = parse_number(token, token, &pos);
      if (pos >= token.size() || token[pos] != 'r')
        throw ModelError("centreline token '" + token + "': expected 'r<radius>' after the angle");
      ++pos;
      seg.radius_mm = parse_number(token, token, &pos);
      if (seg.radius_mm <= 0) throw ModelError("centreline token '" + token + "': radius must be > 0");
      if (pos < token.size() && token[pos] == 't') {
        ++pos;
        seg.twist_deg = parse_number(token, token, &pos);
      }
    } else {
      throw ModelError("centreline token '" + token + "': expected S<length> or B<angle>r<radius>");
    }
    if (pos != token.size())
      throw ModelError("centreline token '" + token + "': unexpected '" + token.substr(pos) + "'");
    out.push_back(seg);
  }
  if (out.empty()) throw ModelError("centreline is empty");
  return out;
}

PipeSpec pipe_preset(const std::string& name) {
  PipeSpec spec;
  if (name == "sbend") {
    spec.diameter_mm = 20;
    spec.segments = parse_centreline("S50,B75r60,S40,B80r50t150,S50");
  } else if (name == "u") {
    spec.diameter_mm = 16;
    spec.segments = parse_centreline("S70,B90r40,B90r40t50,S60");
  } else if (name == "torus") {
    spec.diameter_mm = 18;
    spec.segments = parse_centreline("S10,B250r55,S10");
  } else {
    throw ModelError("unknown pipe preset '" + name + "' (expected sbend, u or torus)");
  }
  // Model frames of real CAD files are rarely centred on the part.
  spec.model_frame.translation() = Eigen::Vector3d(12, -8, 5);
  return spec;
}

Mesh make_pipe(const PipeSpec& spec) {
  if (!(spec.diameter_mm > 0) || !std::isfinite(spec.diameter_mm))
    throw ModelError("pipe diameter must be a number > 0 mm (got " + std::to_string(spec.diameter_mm) + ")");
  if (spec.segments.empty()) throw ModelError("pipe centreline has no segments");
  const double r = spec.diameter_mm / 2;
  const int sides = std::max(8, spec.sides);
  Mesh mesh;
  Frame f{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
          Eigen::Vector3d::UnitZ()};
  double phase = 0;
  add_ring(&mesh, f, r, sides, phase);
  int rings = 1;
  auto extend = [&](const Frame& g) {
    add_ring(&mesh, g, r, sides, phase);
    const int a0 = (rings - 1) * sides, b0 = rings * sides;
    for (int k = 0; k < sides; ++k) {
      const int k1 = (k + 1) % sides;
      // Wound so that face normals point out of the tube.
      mesh.faces.push_back({a0 + k, b0 + k1, b0 + k});
      mesh.faces.push_back({a0 + k, a0 + k1, b0 + k1});
    }
    ++rings;
  };
  for (const auto& seg : spec.segments) {
    if (seg.kind == CentrelineSegment::straight) {
      f.p += seg.length_mm * f.t;
      extend(f);
      continue;
    }
    if (seg.radius_mm <= r)
      throw ModelError("bend radius " + std::to_string(seg.radius_mm) + " mm must exceed the tube radius " +
                       std::to_string(r) + " mm");
    const Eigen::AngleAxisd twist(seg.twist_deg * kDegToRad, f.t);
    f.n = twist * f.n;
    f.b = twist * f.b;
    phase -= seg.twist_deg * kDegToRad;
    // A negative angle turns towards -n: the centre of the arc lies on that side.
    const double side = seg.angle_deg < 0 ? -1.0 : 1.0;
    const Eigen::Vector3d centre = f.p + side * seg.radius_mm * f.n;
    const Eigen::Vector3d axis = side * f.t.cross(f.n);  // turning t towards side * n
    const int steps = std::max(1, int(std::ceil(std::abs(seg.angle_deg) / spec.bend_step_deg)));
    const Frame start = f;
    for (int s = 1; s <= steps; ++s) {
      const Eigen::AngleAxisd rot(std::abs(seg.angle_deg) * kDegToRad * s / steps, axis);
      f.p = centre + rot * (start.p - centre);
      f.t = rot * start.t;
      f.n = rot * start.n;
      f.b = rot * start.b;
      extend(f);
    }
  }
  add_cap(&mesh, Frame{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), {}, {}}, 0, sides, true);
  add_cap(&mesh, f, (rings - 1) * sides, sides, false);
  for (auto& v : mesh.vertices) v = (spec.model_frame * v.cast<double>()).cast<float>();
  return mesh;
}

}  // namespace pipeloc
