// pipeloc: localize freely curved pipes in a bin and hand the best pick to a PLC.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <exception>
#include <memory>

#include "app/commands.hpp"

namespace pipeloc::app {
int& exit_status() {
  static int status = 0;
  return status;
}
}  // namespace pipeloc::app

int main(int argc, char** argv) {
  // Log lines go to stderr: stdout carries what a command produces (locate's JSON lines, the score
  // and bench tables), for a pipe or a file.
  spdlog::set_default_logger(
      std::make_shared<spdlog::logger>("", std::make_shared<spdlog::sinks::stderr_color_sink_mt>()));
  CLI::App app{"pipeloc: pipe localization for bin picking (see README.md)"};
  app.require_subcommand(1);
  pipeloc::app::add_make_pipe(app);
  pipeloc::app::add_simulate(app);
  pipeloc::app::add_score(app);
  pipeloc::app::add_locate(app);
  pipeloc::app::add_eval_bop(app);
  pipeloc::app::add_bench(app);
  pipeloc::app::add_serve(app);
  pipeloc::app::add_record(app);
  pipeloc::app::add_timing_report(app);
  pipeloc::app::add_calibrate_bin(app);
  pipeloc::app::add_calibrate_hand_eye(app);
  pipeloc::app::add_plot_budget(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version succeed; any other command-line error is a start-up error: exit 2,
    // as a bad config or model is (CLI11's own codes run 104-114).
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  return pipeloc::app::exit_status();
}
