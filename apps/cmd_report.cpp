// Placeholder until the `report` subcommand lands: it exists (with --help) so that the command
// line is complete, and refuses to run.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "apps/commands.hpp"

namespace confpack::app {

void registerReport(CLI::App& app) {
  auto* sub = app.add_subcommand("report", "Tables and figures of a study, the two backends side by side");
  sub->allow_extras();
  sub->callback([] {
    std::fputs("confpack report: not implemented yet\n", stderr);
    throw CLI::RuntimeError(2);
  });
}

}  // namespace confpack::app
