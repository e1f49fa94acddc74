// Reference values (study/reference_values.hpp): the strict reader refuses what it does not know by
// name, the example file of the docs reads, and the most specific entry of a family wins.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "study/reference_values.hpp"
#include "tests/support/scratch.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using nlohmann::json;

namespace {

json value(double v, double u = 0.01, const std::string& citation = "A. Author, J. Granular 1, 1 (2000)") {
  return {{"value", v}, {"uncertainty", u}, {"citation", citation}};
}

json document(const json& families) {
  return {{"format", "confpack-reference"}, {"version", 1}, {"families", families}};
}

}  // namespace

TEST_CASE("reference values: a family-wide entry and entries narrowed to x_S and mu_w") {
  const json doc = document({{"MSP", {{"phi_bulk", value(0.64)}, {"Z_bulk", value(6.0, 0.0)}}},
                             {"BSP", json::array({{{"x_S", 25}, {"phi_bulk", value(0.66)}},
                                                  {{"phi_bulk", value(0.65)}, {"C", value(0.3, 0.05)}},
                                                  {{"x_S", 25}, {"mu_w", 0.5}, {"phi_bulk", value(0.67)}}})}});
  const study::ReferenceValues r = study::parseReferenceValues(doc, "ref.json");
  CHECK(r.source == "ref.json");
  REQUIRE(r.entries.size() == 4);
  const study::ReferenceValue* phi = r.find("MSP", 0.0, 0.3, "phi_bulk");
  REQUIRE(phi);
  CHECK(phi->value == 0.64);
  CHECK(phi->uncertainty == 0.01);
  CHECK(phi->citation == "A. Author, J. Granular 1, 1 (2000)");
  CHECK(r.find("MSP", 0.0, 0.0, "Z_bulk")->uncertainty == 0.0);
  CHECK_FALSE(r.find("MSP", 0.0, 0.0, "C"));
  CHECK_FALSE(r.find("MPP", 0.0, 0.0, "phi_bulk"));
  // The most specific entry that gives the quantity: x_S and mu_w, then x_S, then the family's.
  CHECK(r.find("BSP", 25.0, 0.5, "phi_bulk")->value == 0.67);
  CHECK(r.find("BSP", 25.0, 0.0, "phi_bulk")->value == 0.66);
  CHECK(r.find("BSP", 10.0, 0.0, "phi_bulk")->value == 0.65);
  CHECK(r.find("BSP", 25.0, 0.5, "C")->value == 0.3);
}

TEST_CASE("reference values: the docs' example file reads") {
  const study::ReferenceValues r =
      study::readReferenceValues(fs::path(CONFPACK_SOURCE_DIR) / "docs" / "examples" / "reference-values.json");
  REQUIRE(r.find("MSP", 0.0, 0.0, "phi_bulk"));
  CHECK(r.find("MSP", 0.0, 0.0, "phi_bulk")->value == 0.64);
  CHECK(r.find("MSP", 0.0, 0.5, "Z_bulk")->value == 6.0);
  CHECK_THAT(r.description, Catch::StartsWith("example"));
}

TEST_CASE("reference values: every refusal names the file and the field") {
  auto refused = [](const json& doc, const std::string& message) {
    INFO(doc.dump());
    CHECK_THROWS_WITH(study::parseReferenceValues(doc, "ref.json"), message);
  };
  const json ok = value(0.64);
  // The header may be left out, and is checked when given.
  CHECK_NOTHROW(study::parseReferenceValues({{"families", {{"MSP", {{"phi_bulk", ok}}}}}}, "ref.json"));
  refused(json::array(), "ref.json: document: must be a JSON object (got array)");
  refused({{"families", {{"MSP", {{"phi_bulk", ok}}}}}, {"reference", 1}},
          "ref.json: reference: unknown key (known: format, version, description, families)");
  refused({{"format", "confpack-sweep"}, {"families", {{"MSP", {{"phi_bulk", ok}}}}}},
          "ref.json: format: must be \"confpack-reference\" (got \"confpack-sweep\")");
  refused({{"version", 2}, {"families", {{"MSP", {{"phi_bulk", ok}}}}}},
          "ref.json: version: must be 1, the version this build reads (got 2)");
  refused({{"format", "confpack-reference"}}, "ref.json: families: missing (an object keyed by MSP, BSP, MPP, BPP)");
  refused({{"description", 3}, {"families", {{"MSP", {{"phi_bulk", ok}}}}}},
          "ref.json: description: must be a string (got 3)");
  refused(document(json::object()), "ref.json: families: expected a non-empty object keyed by MSP, BSP, MPP, BPP");
  refused(document({{"RCP", {{"phi_bulk", ok}}}}),
          "ref.json: families.RCP: unknown family (known: MSP, BSP, MPP, BPP)");
  refused(document({{"MSP", {{"phi_bulkk", ok}}}}),
          "ref.json: families.MSP.phi_bulkk: unknown key (known: x_S, mu_w, phi_bulk, C, Z_bulk, C_Z, "
          "lambda_L_over_d_avg)");
  refused(document({{"MSP", {{"x_S", 0}}}}),
          "ref.json: families.MSP: gives no value (known quantities: phi_bulk, C, Z_bulk, C_Z, lambda_L_over_d_avg)");
  refused(document({{"MSP", json::array()}}), "ref.json: families.MSP: expected a non-empty list of entries");
  refused(document({{"MSP", json::array({{{"phi_bulk", ok}}, 3})}}),
          "ref.json: families.MSP[1]: must be a JSON object (got number)");
  // Each value needs its uncertainty and its source, of the right kind.
  refused(document({{"MSP", {{"phi_bulk", {{"value", 0.64}, {"citation", "x"}}}}}}),
          "ref.json: families.MSP.phi_bulk.uncertainty: missing (a reference value needs value, uncertainty and "
          "citation)");
  refused(document({{"MSP", {{"phi_bulk", {{"value", 0.64}, {"uncertainty", 0.01}}}}}}),
          "ref.json: families.MSP.phi_bulk.citation: missing (a reference value needs value, uncertainty and "
          "citation)");
  refused(document({{"MSP", {{"phi_bulk", value(0.64, -0.1)}}}}),
          "ref.json: families.MSP.phi_bulk.uncertainty: must be >= 0 (got -0.1)");
  refused(document({{"MSP", {{"phi_bulk", {{"value", "0.64"}, {"uncertainty", 0.01}, {"citation", "x"}}}}}}),
          "ref.json: families.MSP.phi_bulk.value: must be a number (got \"0.64\")");
  refused(document({{"MSP", {{"phi_bulk", value(0.64, 0.01, "")}}}}),
          "ref.json: families.MSP.phi_bulk.citation: must be a non-empty string (got \"\")");
  refused(
      document({{"MSP", {{"phi_bulk", {{"value", 0.64}, {"uncertainty", 0.01}, {"citation", "x"}, {"doi", "y"}}}}}}),
      "ref.json: families.MSP.phi_bulk.doi: unknown key (known: value, uncertainty, citation)");
  // Selectors: in range and consistent with the family's name.
  refused(document({{"MSP", {{"x_S", 10}, {"phi_bulk", ok}}}}),
          "ref.json: families.MSP.x_S: MSP is monodisperse: x_S must be 0 (got 10)");
  refused(document({{"BPP", {{"x_S", 0}, {"phi_bulk", ok}}}}),
          "ref.json: families.BPP.x_S: BPP is bidisperse: x_S must be > 0 (got 0)");
  refused(document({{"BSP", {{"x_S", 120}, {"phi_bulk", ok}}}}),
          "ref.json: families.BSP.x_S: must be a number in [0, 100] (got 120)");
  refused(document({{"MSP", {{"mu_w", -1}, {"phi_bulk", ok}}}}),
          "ref.json: families.MSP.mu_w: must be a number >= 0 (got -1)");
  // Two published numbers for the same series and quantity: which one would the report show?
  refused(document({{"BSP", json::array({{{"x_S", 25}, {"phi_bulk", ok}}, {{"x_S", 25}, {"phi_bulk", value(0.65)}}})}}),
          "ref.json: families.BSP[1].phi_bulk: given twice for the same family, x_S and mu_w (also in "
          "families.BSP[0])");
}

TEST_CASE("reference values: a file that is not JSON, or is a folder, is refused") {
  const fs::path dir = testing::freshDir("reference_values");
  std::ofstream(dir / "bad.json") << "{ \"families\": ";
  CHECK_THROWS_WITH(study::readReferenceValues(dir / "bad.json"),
                    Catch::StartsWith((dir / "bad.json").string() + ": not valid JSON"));
  CHECK_THROWS_WITH(study::readReferenceValues(dir), (dir.string() + ": is a folder, not a reference file"));
  fs::remove_all(dir);
}
