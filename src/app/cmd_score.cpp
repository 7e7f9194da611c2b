#include <spdlog/spdlog.h>

#include <fstream>
#include <iostream>

#include "app/commands.hpp"
#include "score/scorer.hpp"

namespace pipeloc::app {

void add_score(CLI::App& app) {
  struct Options {
    std::string dataset, results, json, picks, misses;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("score", "Score BOP results against a dataset's ground truth (DESIGN.md scoring)");
  cmd->add_option("--dataset", opt->dataset, "BOP dataset directory")->required();
  cmd->add_option("--results", opt->results, "results CSV")->required();
  cmd->add_option("--json", opt->json, "also write the figures as JSON here");
  cmd->add_option("--picks", opt->picks,
                  "the pose handed out per image (eval-bop --picks): also score pick rate, pick-correct, "
                  "wrong picks");
  cmd->add_option("--misses", opt->misses,
                  "also write each top pipe no estimate matched within 5 mm, with the nearest estimate's "
                  "error (mm, capped at 500) and rank, as CSV here");
  cmd->callback([opt] {
    const ResultsFile results = read_results_csv(opt->results);
    ResultsFile picks;
    if (!opt->picks.empty()) picks = read_results_csv(opt->picks);
    const ScoreReport report =
        score_results(opt->dataset, results, {}, opt->picks.empty() ? nullptr : &picks, !opt->misses.empty());
    std::cout << format_report(report);
    if (!opt->json.empty()) write_json(opt->json, report_to_json(report));
    if (!opt->misses.empty()) {
      std::ofstream out(opt->misses);
      if (!(out << format_misses(report))) throw IoError("cannot write '" + opt->misses + "'");
    }
  });
}

}  // namespace pipeloc::app
