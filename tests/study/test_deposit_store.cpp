// The deposit file (study/deposit_store.hpp): a real deposit written and read back gives the same
// bits, and a document that is not a deposit is refused naming the field.
#include <catch2/catch.hpp>
#include <filesystem>

#include "compaction/deposition.hpp"
#include "study/deposit_store.hpp"
#include "tests/support/same_bits.hpp"
#include "tests/support/scratch.hpp"

using namespace confpack;
namespace fs = std::filesystem;
using testing::sameBits;

TEST_CASE("a deposit written to disk reads back bit for bit") {
  core::BoxDef box;
  box.lengthX = 5.0;
  box.width = 1.0 / 3.0 + 3.0;  // not a short decimal
  box.height = 3.0;
  core::PopulationDef population;
  population.smallFraction = 30.0;  // two sizes, both with awkward doubles
  core::DepositionDef def;
  def.grainCount = 60;
  const compaction::Deposit d = compaction::deposit(box, population, def, 21);
  REQUIRE(d.grains.size() == 60);
  const fs::path dir = testing::freshDir("deposit_store");
  study::writeDeposit(d, box, dir / "deposit.json");
  const compaction::Deposit back = study::readDeposit(dir / "deposit.json");
  REQUIRE(back.grains.size() == d.grains.size());
  REQUIRE(back.placeholders.size() == d.placeholders.size());
  bool same = true;
  for (std::size_t i = 0; i < d.grains.size(); ++i) {
    const core::Grain &a = d.grains[i], &b = back.grains[i];
    same = same && a.shape == b.shape && sameBits(a.size, b.size);
    same = same && sameBits(a.position, b.position) && sameBits(d.placeholders[i], back.placeholders[i]) &&
           sameBits(a.orientation, b.orientation);
  }
  CHECK(same);
  CHECK(sameBits(back.placeholderDiameter, d.placeholderDiameter));
  CHECK(sameBits(back.pileHeight, d.pileHeight));
  CHECK(sameBits(back.placeholderSolidFraction, d.placeholderSolidFraction));
  CHECK(sameBits(back.solidFraction, d.solidFraction));
  fs::remove_all(dir);
}

TEST_CASE("a document that is not a whole deposit is refused naming the field") {
  core::BoxDef box;
  compaction::Deposit d;
  d.grains.resize(2);
  d.grains[0].position = core::Vec3(1.0, 1.0, 0.5);
  d.grains[1].position = core::Vec3(3.0, 1.0, 0.5);
  d.placeholders = {d.grains[0].position, d.grains[1].position};
  d.placeholderDiameter = 1.0;
  const nlohmann::json good = study::depositToJson(d, box);
  CHECK(study::depositFromJson(good).grains.size() == 2);
  nlohmann::json j = good;
  j["format"] = "confpack-packing";
  CHECK_THROWS_WITH(study::depositFromJson(j, "d.json"), Catch::Contains("d.json: format"));
  j = good;
  j["version"] = 2;
  CHECK_THROWS_WITH(study::depositFromJson(j, "d.json"), Catch::Contains("version"));
  j = good;
  j["placeholders"].erase(1);
  CHECK_THROWS_WITH(study::depositFromJson(j, "d.json"), Catch::Contains("placeholders"));
  j = good;
  j["placeholders"][1] = {1.0, "two", 3.0};
  CHECK_THROWS_WITH(study::depositFromJson(j, "d.json"), Catch::Contains("placeholders[1]"));
  j = good;
  j.erase("pile_height");
  CHECK_THROWS_WITH(study::depositFromJson(j, "d.json"), Catch::Contains("pile_height"));
  j = good;
  j["pile_hieght"] = 3.0;
  CHECK_THROWS_WITH(study::depositFromJson(j, "d.json"),
                    Catch::StartsWith("d.json: pile_hieght: unknown key (known: "));
  j = good;
  j["packing"]["grains"][0]["size"] = -1.0;
  CHECK_THROWS_WITH(study::depositFromJson(j, "d.json"), Catch::Contains("d.json: packing") && Catch::Contains("size"));
}
