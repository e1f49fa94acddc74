// Placeholder until the `bench` subcommand lands: it exists (with --help) so that the command
// line is complete, and refuses to run.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "apps/commands.hpp"

namespace confpack::app {

void registerBench(CLI::App& app) {
  auto* sub = app.add_subcommand("bench", "Time the backends on the same packings");
  sub->allow_extras();
  sub->callback([] {
    std::fputs("confpack bench: not implemented yet\n", stderr);
    throw CLI::RuntimeError(2);
  });
}

}  // namespace confpack::app
