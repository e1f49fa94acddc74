// Placeholder until the `run` subcommand lands: it exists (with --help) so that the command
// line is complete, and refuses to run.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "apps/commands.hpp"

namespace confpack::app {

void registerRun(CLI::App& app) {
  auto* sub = app.add_subcommand("run", "Deposit, compact with a backend until equilibrium, analyse and write result.json");
  sub->allow_extras();
  sub->callback([] {
    std::fputs("confpack run: not implemented yet\n", stderr);
    throw CLI::RuntimeError(2);
  });
}

}  // namespace confpack::app
