// The profile CSV reader (study/csv_table.hpp).
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
