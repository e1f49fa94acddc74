// confpack: the command line (README, "Command line"). Thin: parse, dispatch to a subcommand,
// return its code.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "core/build_info.hpp"
#ifdef CONFPACK_ALLOCATION_FAULT
#include "tests/support/allocation_fault.hpp"
#endif

namespace {

int runCommandLine(int argc, char** argv) {
  using namespace confpack::app;
  CLI::App app{
      "confpack: dense packings of frictionless spheres and pinacoids between two walls, compacted by a "
      "native NSCD solver or Bullet"};
  app.name("confpack");
  // Set before the subcommands are added: they copy the root's failure message.
  app.failure_message(oneLineFailure);
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("confpack ") + confpack::core::version() + " (revision " +
                                        confpack::core::sourceRevision() + ")");
  registerDeposit(app);
  registerRun(app);
  registerAnalyze(app);
  registerSweep(app);
  registerReport(app);
  registerReproduce(app);
  registerOptions(app);

  // CLI11 answers a misspelt subcommand with "A subcommand is required"; name it instead.
  if (argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      known = known || sub->get_name() == argv[1];
    }
    if (!known) {
      std::fprintf(stderr, "confpack: error: unknown subcommand '%s' (expected one of %s)\n", argv[1], names.c_str());
      return kExitBadInput;
    }
  }
  return parseAndRun(app, argc, argv);
}

}  // namespace

// The command line's setup (the subcommands' options) allocates before parseAndRun can catch
// anything: a failure there would otherwise end in std::terminate and its two lines.
int main(int argc, char** argv) {
#ifdef CONFPACK_ALLOCATION_FAULT
  // The test build only (tests/support/allocation_fault.hpp): fail the k-th allocation from here.
  confpack::testing::armAllocationFault();
#endif
  try {
    return runCommandLine(argc, argv);
  } catch (const std::bad_alloc&) {
    // Without allocating: memory has run out.
    constexpr const char line[] = "confpack: out of memory while setting up the command line\n";
    std::fflush(stdout);
    (void)!::write(STDERR_FILENO, line, sizeof line - 1);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "confpack: error: %s\n", e.what());
  }
  return confpack::app::kExitRuntimeFailure;
}
