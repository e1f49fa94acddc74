// Placeholder until the `reproduce` subcommand lands: it exists (with --help) so that the command
// line is complete, and refuses to run.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "apps/commands.hpp"

namespace confpack::app {

void registerReproduce(CLI::App& app) {
  auto* sub = app.add_subcommand("reproduce", "Rerun a run from its written configuration and compare");
  sub->allow_extras();
  sub->callback([] {
    std::fputs("confpack reproduce: not implemented yet\n", stderr);
    throw CLI::RuntimeError(2);
  });
}

}  // namespace confpack::app
