#pragma once
// The subcommands of `confpack` (README, "Command line"). Each register function adds one
// subcommand to the root app, with its options bound to state it owns and a callback that does the
// work. A callback ends with CLI::RuntimeError(code) when it fails (main returns the code; the
// message has already been printed): 2 for bad input, 1 for a runtime failure. See
// apps/cli_common.hpp.
#include <string>

namespace CLI {
class App;
}

namespace confpack::app {

void registerDeposit(CLI::App& app);    ///< deposit a pile and write it (apps/cmd_deposit.cpp)
void registerRun(CLI::App& app);        ///< deposit, compact, analyse (apps/cmd_run.cpp)
void registerAnalyze(CLI::App& app);    ///< analyse a packing file (apps/cmd_analyze.cpp)
void registerSweep(CLI::App& app);      ///< run a study (apps/cmd_sweep.cpp)
void registerReport(CLI::App& app);     ///< tables and figures of a study (apps/cmd_report.cpp)
void registerReproduce(CLI::App& app);  ///< the confinement study at a scale (apps/cmd_reproduce.cpp)
void registerOptions(CLI::App& app);    ///< the settings tables (apps/cmd_options.cpp)

/// The Markdown table of "deposition", "compaction", "nscd" or "bullet" that `confpack options` prints.
std::string optionsListing(const std::string& part);

}  // namespace confpack::app
