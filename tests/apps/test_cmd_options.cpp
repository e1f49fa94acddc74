// `confpack options` (apps/cmd_options.cpp): the settings tables it prints are those of the code,
// and docs/backend-options.md carries them row for row, so the docs cannot drift from what the
// readers accept.
#include <catch2/catch.hpp>
#include <fstream>
#include <sstream>
#include <string>

#include "apps/commands.hpp"
#include "tests/support/confpack_binary.hpp"

using namespace confpack;

TEST_CASE("settings table: docs/backend-options.md lists every key as confpack options prints it") {
  std::ifstream in(std::string(CONFPACK_SOURCE_DIR) + "/docs/backend-options.md");
  REQUIRE(in);
  std::stringstream doc;
  doc << in.rdbuf();
  for (const char* part :
       {"config", "box", "walls", "population", "pinacoid", "deposition", "compaction", "nscd", "bullet"}) {
    std::istringstream rows(app::optionsListing(part));
    std::string row;
    while (std::getline(rows, row)) {
      INFO(part << ": " << row);
      CHECK(doc.str().find(row) != std::string::npos);
    }
  }
}

TEST_CASE("confpack options prints one part's table, refuses an unknown part with exit 2") {
  testing::ConfpackSession s("options");
  const auto ok = s.run("options nscd");
  CHECK(ok.code == 0);
  CHECK(ok.out == app::optionsListing("nscd"));
  const auto bad = s.run("options nsdc");
  CHECK(bad.code == 2);
  CHECK(bad.out.empty());
}
