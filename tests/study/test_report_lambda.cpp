// The report's wall-ordering length (study/report_lambda.hpp): the width it reads lambda_L at.
#include <catch2/catch.hpp>

#include "study/report_lambda.hpp"

using namespace confpack;

TEST_CASE("lambda_L is read at W = 10 or at the nearest width a family has", "[study][report]") {
  CHECK(study::lambdaWidth({5.0, 10.0, 20.0}, 10.0) == 10.0);
  CHECK(study::lambdaWidth({20.0, 5.0, 10.0}, 10.0) == 10.0);  // in any order
  CHECK(study::lambdaWidth({5.0, 20.0}, 10.0) == 5.0);         // 5 is nearer than 20
  CHECK(study::lambdaWidth({3.0, 4.5, 6.0}, 10.0) == 6.0);     // a shrunken study: its widest
  CHECK(study::lambdaWidth({8.0, 12.0}, 10.0) == 12.0);        // a tie goes to the wider
  CHECK(study::lambdaWidth({5.0, 10.0, 20.0}, 20.0) == 20.0);  // another setting
  CHECK_FALSE(study::lambdaWidth({}, 10.0));
}
