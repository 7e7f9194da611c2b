// Each subcommand registers itself on the CLI; its callback throws on bad input at start-up
// and main() turns that into one clear message and a non-zero exit.
#pragma once

#include <CLI/CLI.hpp>

namespace pipeloc::app {

void add_make_pipe(CLI::App& app);
void add_simulate(CLI::App& app);
void add_score(CLI::App& app);
void add_locate(CLI::App& app);
void add_eval_bop(CLI::App& app);
void add_bench(CLI::App& app);
void add_serve(CLI::App& app);
void add_record(CLI::App& app);
void add_timing_report(CLI::App& app);
void add_calibrate_bin(CLI::App& app);
void add_calibrate_hand_eye(CLI::App& app);
void add_plot_budget(CLI::App& app);

// Exit status a callback asks for (0 unless set).
int& exit_status();

}  // namespace pipeloc::app
