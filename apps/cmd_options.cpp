// `confpack options [config|box|walls|population|pinacoid|deposition|compaction|nscd|bullet]`: the settings each part
// reads, as Markdown tables (key, default, unit, accepted values, meaning), printed from the descriptions that read
// them (core/settings_table.hpp), so the listing cannot drift from the code. docs/backend-options.md holds the same
// tables.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "backends/backend_factory.hpp"
#include "core/box.hpp"
#include "core/pinacoid.hpp"
#include "core/population.hpp"
#include "core/run_config.hpp"
#include "core/settings_table.hpp"
#include "core/walls.hpp"

namespace confpack::app {

std::string optionsListing(const std::string& part) {
  if (part == "config") return core::runConfigTable().markdown(core::RunConfig{});
  if (part == "box") return core::boxTable().markdown(core::BoxDef{});
  if (part == "walls") return core::wallMaterialTable().markdown(core::WallMaterial{});
  if (part == "population") return core::populationTable().markdown(core::PopulationDef{});
  if (part == "pinacoid") return core::pinacoidTable().markdown(core::PinacoidParams{});
  if (part == "compaction") return core::compactionTable().markdown(core::CompactionDef{});
  if (part == "deposition") return core::depositionTable().markdown(core::DepositionDef{});
  return backends::optionsMarkdown(part);
}

void registerOptions(CLI::App& app) {
  auto part = std::make_shared<std::string>();
  static constexpr const char* kParts[] = {"config",     "box",        "walls", "population", "pinacoid",
                                           "deposition", "compaction", "nscd",  "bullet"};
  CLI::App* sub =
      app.add_subcommand("options",
                         "Print the settings of the run configuration (config.json and its objects) or of a backend "
                         "(--backend-options) as a Markdown table: key, default, unit, accepted values, meaning");
  sub->add_option(
         "part", *part,
         "config, box, walls, population, pinacoid, deposition, compaction, nscd or bullet; all of them when omitted")
      ->check(CLI::IsMember(std::vector<std::string>(std::begin(kParts), std::end(kParts))));
  sub->callback([part] {
    runWork("options", [&] {
      for (const char* p : kParts) {
        if (!part->empty() && *part != p) continue;
        if (part->empty()) std::printf("## %s\n\n", p);
        std::printf("%s%s", optionsListing(p).c_str(), part->empty() ? "\n" : "");
      }
    });
  });
}

}  // namespace confpack::app
