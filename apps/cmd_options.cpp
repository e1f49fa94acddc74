// `confpack options [deposition|compaction|nscd|bullet]`: the settings each part reads, as Markdown tables
// (key, default, unit, accepted values, meaning), printed from the descriptions that read them
// (core/settings_table.hpp), so the listing cannot drift from the code. docs/backend-options.md
// holds the same tables.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "backends/backend_factory.hpp"
#include "core/run_config.hpp"
#include "core/settings_table.hpp"

namespace confpack::app {

std::string optionsListing(const std::string& part) {
  if (part == "compaction") return core::compactionTable().markdown(core::CompactionDef{});
  if (part == "deposition") return core::depositionTable().markdown(core::DepositionDef{});
  return backends::optionsMarkdown(part);
}

void registerOptions(CLI::App& app) {
  auto part = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "options", "Print the settings of the deposition or the compaction (config.json's objects) or of a backend "
                 "(--backend-options) as a Markdown table: key, default, unit, accepted values, meaning");
  sub->add_option("part", *part, "deposition, compaction, nscd or bullet; all four when omitted")
      ->check(CLI::IsMember({"deposition", "compaction", "nscd", "bullet"}));
  sub->callback([part] {
    runWork("options", [&] {
      for (const char* p : {"deposition", "compaction", "nscd", "bullet"}) {
        if (!part->empty() && *part != p) continue;
        if (part->empty()) std::printf("## %s\n\n", p);
        std::printf("%s%s", optionsListing(p).c_str(), part->empty() ? "\n" : "");
      }
    });
  });
}

}  // namespace confpack::app
