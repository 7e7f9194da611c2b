#include <spdlog/spdlog.h>

#include <sstream>

#include "app/commands.hpp"
#include "model/make_pipe.hpp"
#include "model/pipe_model.hpp"
#include "model/stl.hpp"

namespace pipeloc::app {

void add_make_pipe(CLI::App& app) {
  struct Options {
    std::string out, path, preset;
    double diameter = 0;
    std::vector<double> offset, rotate;
    bool ascii = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("make-pipe", "Write an STL of a tube swept along a centreline");
  cmd->add_option("--out", opt->out, "STL file to write")->required();
  cmd->add_option("--path", opt->path,
                  "centreline: S<length>, B<angle>r<radius>[t<twist>] comma-separated, mm/deg "
                  "(e.g. S60,B90r50,S40,B-80r45t120)");
  cmd->add_option("--preset", opt->preset, "sbend | u | torus (the paper's three kinds)");
  cmd->add_option("--diameter", opt->diameter, "tube diameter, mm");
  cmd->add_option("--offset", opt->offset, "model-frame offset x y z, mm (the frame need not be centred)")
      ->expected(3);
  cmd->add_option("--rotate", opt->rotate, "model-frame rotation about x, y, z, degrees")->expected(3);
  cmd->add_flag("--ascii", opt->ascii, "write ASCII STL instead of binary");
  cmd->callback([opt, cmd] {
    if (opt->preset.empty() == opt->path.empty())
      throw ModelError("make-pipe: give exactly one of --path or --preset");
    if (cmd->count("--diameter") && !(opt->diameter > 0 && opt->diameter <= 1000))
      throw ModelError("make-pipe: --diameter: expected a tube diameter in (0, 1000] mm, got " +
                       std::to_string(opt->diameter));
    PipeSpec spec = opt->preset.empty() ? PipeSpec{} : pipe_preset(opt->preset);
    if (!opt->path.empty()) spec.segments = parse_centreline(opt->path);
    if (cmd->count("--diameter")) spec.diameter_mm = opt->diameter;
    if (!opt->rotate.empty()) {
      const double d = M_PI / 180;
      spec.model_frame.linear() = (Eigen::AngleAxisd(opt->rotate[2] * d, Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(opt->rotate[1] * d, Eigen::Vector3d::UnitY()) *
                                   Eigen::AngleAxisd(opt->rotate[0] * d, Eigen::Vector3d::UnitX()))
                                      .toRotationMatrix();
    }
    if (!opt->offset.empty())
      spec.model_frame.translation() = Eigen::Vector3d(opt->offset[0], opt->offset[1], opt->offset[2]);
    const Mesh mesh = make_pipe(spec);
    // Derived first, so that a pipe the localizer would refuse (too long, too thin) is not written.
    const PipeModel model = derive_pipe_model(mesh, opt->out);
    write_stl(opt->out, mesh, opt->ascii ? StlFormat::ascii : StlFormat::binary);
    spdlog::info(
        "wrote {}: {} triangles, tube diameter {:.2f} mm, longest extent L {:.1f} mm, {} symmetries, {} near "
        "symmetries",
        opt->out, mesh.faces.size(), model.tube_diameter_mm, model.extent_mm, model.symmetries.size(),
        model.near_symmetries.size());
  });
}

}  // namespace pipeloc::app
