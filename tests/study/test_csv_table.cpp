// The CSV reader and writer (study/csv_table.hpp): the runs' profiles, the report's tables.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>

#include "study/csv_table.hpp"

using namespace confpack;

TEST_CASE("csv: metadata skipped, header named, non-numbers NaN, ragged rows dropped") {
  const auto t = study::parseCsv("# seed: 1\ny,phi\n0,0.5\n\n1,x\n2,0.6,9\n# end\n3,0.7\n");
  REQUIRE(t);
  CHECK(t->columns == std::vector<std::string>{"y", "phi"});
  REQUIRE(t->rows.size() == 3);
  CHECK(t->rows[0] == std::vector<double>{0.0, 0.5});
  CHECK(std::isnan(t->rows[1][1]));
  CHECK(t->rows[2] == std::vector<double>{3.0, 0.7});
  CHECK_FALSE(study::parseCsv("y\n1\n2\n"));        // one column: not a profile
  CHECK_FALSE(study::parseCsv("# only\ny,phi\n"));  // no row
  CHECK_FALSE(study::readCsv("/nonexistent/phi_y.csv"));
}

TEST_CASE("csv: written tables read back cell for cell, numbers exactly, quoted text whole") {
  const double third = 1.0 / 3.0;
  const std::vector<std::string> columns = {"key", "mean", "note"};
  const std::vector<std::vector<std::string>> rows = {{"coordination/Z", fmt::format("{:.17g}", third), ""},
                                                      {"a,b", "2", "say \"hi\"\nthere"}};
  const std::string text = study::formatCsv(columns, rows);
  CHECK(text == "key,mean,note\ncoordination/Z,0.33333333333333331,\n\"a,b\",2,\"say \"\"hi\"\" there\"\n");
  const auto t = study::parseCsv(text);
  REQUIRE(t);
  CHECK(t->columns == columns);
  REQUIRE(t->rows.size() == 2);
  CHECK(t->rows[0][1] == third);  // full precision: the same double
  CHECK(std::isnan(t->rows[0][2]));
  CHECK(t->text[0] == rows[0]);
  CHECK(t->text[1] == std::vector<std::string>{"a,b", "2", "say \"hi\" there"});
}
