// Placeholder until the `sweep` subcommand lands: it exists (with --help) so that the command
// line is complete, and refuses to run.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "apps/commands.hpp"

namespace confpack::app {

void registerSweep(CLI::App& app) {
  auto* sub = app.add_subcommand("sweep", "Run a study: every combination of widths, shapes, fractions, frictions, seeds and backends");
  sub->allow_extras();
  sub->callback([] {
    std::fputs("confpack sweep: not implemented yet\n", stderr);
    throw CLI::RuntimeError(2);
  });
}

}  // namespace confpack::app
